// Stage 3b, modes (docs/method/diagnosis.md, "The stages"): a lightly damped pair of the
// simulation that every path of a scope holds (a structure's mode, seen by every sensor; a mode of
// one output's or one input's paths) is moved once, over all those pairs together, before any pair
// is diagnosed alone. Each pair's own fit would split it (a path's residual holds its share of the
// mode and of everything else), or miss it where several modes moved and none alone removes a
// quarter of the pair's chi2.
//
// Candidates: pairs (wn, zeta <= kLightZeta) of the paths' and sensors' poles, inside the band of
// the pairs that hold them, held (wn within kSameRoot) by every X:O pair of the plant, of one
// output, or of one input (at least two pairs). A mode's move is F = D_from(s) / D_to(s) on each
// of its pairs, on top of what the modes before it found: ln wn by a grid over +-kSearchRel of the
// simulated frequency (steps of a quarter of the damping, so the grid falls inside the mode's
// half-power band), then the damping over [zeta / kZetaSpan, zeta * kZetaSpan] and the two
// alternately by Brent's method (as a pole_shift's pair moves). The damping is kept at the
// simulation's unless it lowers chi2 by one penalty more. Greedily, the mode that lowers chi2 most
// is taken while it lowers chi2 by more than k ln 2N in units of its pairs' misfit level
// s = max(1, chi2 / N) (stage 6's scale: a structure measured far better than any model fits it
// otherwise passes every move) and lowers its pairs' error; its factor then stays on its pairs for
// what follows. The findings are pole shifts at the scope, sized again with the rest in 5b.
#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "fralab/core/numerics.h"
#include "stages.h"

namespace fralab::diag {
namespace {

constexpr double kLightZeta = 0.2;  // a mode is lighter than this
constexpr double kSameRoot = 1e-3;  // a path holds the mode: a pole within this (relative)
constexpr double kSearchRel = 0.2;  // ln wn searched within +-this of the simulated
constexpr double kZetaSpan = 10;    // the damping within a factor of this of the simulated
constexpr int kMaxModes = 12;       // modes moved at most
constexpr int kRounds = 8;          // frequency / damping alternations at most

struct SharedMode {
  Root root;
  Scope scope = Scope::kPlant;
  std::string input, output;
  std::vector<size_t> pairs;  // into r.pairs
};

bool holds(const Model& m, const PairFit& p, const Root& root) {
  std::vector<Root> v;
  if (const ModelPath* mp = m.path(p.output, p.input)) v = mp->tf.poles;
  const int o = m.output_index(p.output);
  if (o >= 0 && m.outputs[size_t(o)].sensor)
    v.insert(v.end(), m.outputs[size_t(o)].sensor->poles.begin(),
             m.outputs[size_t(o)].sensor->poles.end());
  return std::any_of(v.begin(), v.end(), [&](const Root& q) {
    return q.pair && std::abs(q.wn - root.wn) <= kSameRoot * root.wn;
  });
}

// The scope whose X:O pairs are exactly `holders` (at least two), or nullopt.
std::optional<SharedMode> scope_of(const DiagnosisRun& r, const std::vector<size_t>& holders) {
  if (holders.size() < 2) return std::nullopt;
  auto exactly = [&](const std::function<bool(const PairFit&)>& sel) {
    size_t n = 0;
    for (const PairFit& p : r.pairs) n += !p.output.empty() && sel(p) ? 1 : 0;
    return n == holders.size() &&
           std::all_of(holders.begin(), holders.end(), [&](size_t k) { return sel(r.pairs[k]); });
  };
  SharedMode m;
  m.pairs = holders;
  if (exactly([](const PairFit&) { return true; })) return m;
  const PairFit& first = r.pairs[holders[0]];
  if (exactly([&](const PairFit& p) { return p.output == first.output; })) {
    m.scope = Scope::kOutput, m.output = first.output;
    return m;
  }
  if (exactly([&](const PairFit& p) { return p.input == first.input; })) {
    m.scope = Scope::kInput, m.input = first.input;
    return m;
  }
  return std::nullopt;
}

std::vector<SharedMode> shared_modes(const DiagnosisRun& r) {
  std::vector<Root> seen;
  std::vector<SharedMode> out;
  for (const PairFit& p : r.pairs) {
    if (p.output.empty()) continue;
    std::vector<Root> roots;
    if (const ModelPath* mp = r.sim.path(p.output, p.input)) roots = mp->tf.poles;
    for (const Root& root : roots) {
      if (!root.pair || !(root.zeta > 0 && root.zeta <= kLightZeta)) continue;
      if (std::any_of(seen.begin(), seen.end(), [&](const Root& q) {
            return std::abs(q.wn - root.wn) <= kSameRoot * root.wn;
          }))
        continue;
      seen.push_back(root);
      std::vector<size_t> holders;
      double lo = INFINITY, hi = 0;
      for (size_t k = 0; k < r.pairs.size(); ++k) {
        const PairFit& q = r.pairs[k];
        if (q.output.empty() || q.w.empty() || !holds(r.sim, q, root)) continue;
        holders.push_back(k);
        lo = std::min(lo, q.w.front()), hi = std::max(hi, q.w.back());
      }
      if (!(root.wn >= lo && root.wn <= hi)) continue;
      if (auto m = scope_of(r, holders)) {
        m->root = root;
        out.push_back(*m);
      }
    }
  }
  return out;
}

// A mode moved: its parameters, its factor on each of its pairs, chi2 over them, k.
struct MovedMode {
  double wn = 0, zeta = 0, chi2 = INFINITY;
  int k = 1;
  std::vector<std::vector<C>> F;
};

MovedMode fit_mode(const DiagnosisRun& r, const SharedMode& m) {
  const Root& from = m.root;
  auto factors = [&](double lwn, double lz) {
    Root to = from;
    to.wn = std::exp(lwn), to.zeta = std::exp(lz);
    std::vector<std::vector<C>> F;
    for (size_t k : m.pairs)
      F.push_back(factor_of(r.pairs[k].w, [&](C s) { return from.factor(s) / to.factor(s); }));
    return F;
  };
  auto total = [&](double lwn, double lz) {
    const auto F = factors(lwn, lz);
    double c = 0;
    for (size_t j = 0; j < m.pairs.size(); ++j) c += chi2(r.pairs[m.pairs[j]], F[j]);
    return c;
  };
  const double lz0 = std::log(from.zeta), lw0 = std::log(from.wn);
  const int grid = int(std::ceil(2 * kSearchRel / std::min(0.01, from.zeta / 4)));
  double lwn = minimise_1d([&](double x) { return total(x, lz0); }, lw0 - kSearchRel,
                           lw0 + kSearchRel, grid);
  MovedMode best{std::exp(lwn), from.zeta, total(lwn, lz0), 1, {}};
  double lz = minimise_1d([&](double x) { return total(lwn, x); }, lz0 - std::log(kZetaSpan),
                          lz0 + std::log(kZetaSpan), 40);
  for (int round = 0; round < kRounds; ++round) {
    const double lwn_was = lwn, lz_was = lz;
    const double step = std::max(1e-4, std::exp(lz));
    lwn = detail::brent_minimum([&](double x) { return total(x, lz); }, lwn - step, lwn + step, 24);
    lz = detail::brent_minimum([&](double x) { return total(lwn, x); }, lz - 0.5, lz + 0.5, 24);
    if (std::abs(lwn - lwn_was) < 1e-6 && std::abs(lz - lz_was) < 1e-4) break;
  }
  size_t n = 0;
  for (size_t k : m.pairs) n += r.pairs[k].w.size();
  const double c2 = total(lwn, lz);
  const double s = std::max(1.0, c2 / double(std::max<size_t>(n, 1)));
  if ((best.chi2 - c2) / s > std::log(2.0 * double(n)))
    best = {std::exp(lwn), std::exp(lz), c2, 2, {}};
  best.F = factors(std::log(best.wn), std::log(best.zeta));
  return best;
}

// The error metric over the mode's pairs, their current factors times F (empty: none).
double error_with(const DiagnosisRun& r, const SharedMode& m,
                  const std::vector<std::vector<C>>& F) {
  double s = 0;
  size_t n = 0;
  for (size_t j = 0; j < m.pairs.size(); ++j) {
    const PairFit& p = r.pairs[m.pairs[j]];
    for (size_t q = 0; q < p.w.size(); ++q) {
      const C model = p.sim[q] * p.factor[q] * (F.empty() ? C(1) : F[j][q]);
      s += std::norm(std::log(model / p.meas[q]));
      ++n;
    }
  }
  return n ? std::sqrt(s / double(n)) : 0.0;
}

}  // namespace

void modes(DiagnosisRun& r) {
  std::vector<SharedMode> left = shared_modes(r);
  for (int taken = 0; taken < kMaxModes && !left.empty(); ++taken) {
    size_t best = left.size();
    MovedMode best_fit;
    double best_gain = 0;
    for (size_t c = 0; c < left.size(); ++c) {
      const SharedMode& m = left[c];
      double c0 = 0;
      size_t n = 0;
      for (size_t k : m.pairs) {
        c0 += chi2(r.pairs[k], std::vector<C>(r.pairs[k].w.size(), 1.0));
        n += r.pairs[k].w.size();
      }
      MovedMode f = fit_mode(r, m);
      const double s = std::max(1.0, f.chi2 / double(std::max<size_t>(n, 1)));
      const double gain = (c0 - f.chi2) / s - f.k * std::log(2.0 * double(n));
      if (gain > best_gain && error_with(r, m, f.F) < error_with(r, m, {}))
        best = c, best_fit = std::move(f), best_gain = gain;
    }
    if (best == left.size()) break;
    const SharedMode& m = left[best];
    Finding f;
    f.cause = CauseKind::kPoleShift;
    f.scope = m.scope;
    f.input = m.input;
    f.output = m.output;
    f.parameters = {{"from_rad_s", m.root.wn},
                    {"to_rad_s", best_fit.wn},
                    {"from_zeta", m.root.zeta},
                    {"to_zeta", best_fit.zeta},
                    {"zeta", best_fit.zeta}};
    for (size_t j = 0; j < m.pairs.size(); ++j) {
      PairFit& p = r.pairs[m.pairs[j]];
      f.pairs.push_back(p.pair);
      for (size_t q = 0; q < p.w.size(); ++q) p.factor[q] *= best_fit.F[j][q];
    }
    r.mode_findings.push_back(std::move(f));
    left.erase(left.begin() + long(best));
  }
}

}  // namespace fralab::diag
