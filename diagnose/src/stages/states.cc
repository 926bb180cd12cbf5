// Stage 3a, states (docs/method/diagnosis.md, "The stages", 3a): where the simulation is a state
// model (plant/state_space.h), its own entries are candidate causes, each fitted once over every
// pair: a diagonal entry of A (a state's time constant), a nonzero entry of A off the diagonal (a
// coupling), of B (how an input drives a state) and of C (how a state shows at an output). One
// changed state moves the poles, zeros and gains of every path it reaches; fitted pair by pair it
// splits into pieces or is missed.
//
// Each candidate's value by a scan (kScan points: a diagonal entry of A over its logarithm within
// a factor kSpan either way, keeping its sign; another entry over +-kSpan times its value) and
// Brent's method between the scan's neighbours; on each pair the factor G_moved / G_sim of its
// path (the actuator's own pair: 1). Greedy, at most kMaxEntries, while the best lowers chi2 by
// more than ln 2N in units of the misfit level s = max(1, chi2 / N) (the modes stage's criterion)
// and lowers the error of the pairs; then, kStateBackfitRounds times, each accepted entry is fitted
// again with the others in place and replaced by another entry that fits better there. The
// accepted entries' factor stays on the pairs, so the stages after it fit what they leave.
#include <algorithm>
#include <cmath>

#include "../causes/state_parameter.h"
#include "fralab/core/numerics.h"
#include "fralab/core/pair_id.h"
#include "stages.h"

namespace fralab::diag {
namespace {

constexpr int kScan = 41;
constexpr double kSpan = 4;
constexpr int kMaxEntries = 3;
constexpr int kStateBrentBits = 30;
constexpr int kStateBackfitRounds = 2;

using Paths = std::vector<std::vector<std::optional<Tf>>>;

// On every prepared pair, its path's response under `to` over that under `from` (the actuator's
// own pair, and a path `from` lacks: 1).
std::vector<std::vector<C>> path_ratio(const DiagnosisRun& r, const StateSpace& ss,
                                       const Paths& from, const Paths& to) {
  std::vector<std::vector<C>> F(r.pairs.size());
  for (size_t k = 0; k < r.pairs.size(); ++k) {
    const PairFit& p = r.pairs[k];
    F[k].assign(p.w.size(), C(1, 0));
    const PairId id = PairId::parse(p.pair);
    if (id.actuator()) continue;
    const auto oi = std::find(ss.outputs.begin(), ss.outputs.end(), id.output);
    const auto ii = std::find(ss.inputs.begin(), ss.inputs.end(), id.input);
    if (oi == ss.outputs.end() || ii == ss.inputs.end()) continue;
    const size_t i = size_t(oi - ss.outputs.begin()), j = size_t(ii - ss.inputs.begin());
    const auto& a = from[i][j];
    const auto& b = to[i][j];
    if (!a) continue;
    for (size_t q = 0; q < p.w.size(); ++q) {
      const C s(0, p.w[q]);
      F[k][q] = b ? b->rational(s) / a->rational(s) : C(0, 0);
    }
  }
  return F;
}

// The factor of the entry moved to v on every prepared pair, over `base` (ss's paths); empty
// when the state model is not stable or cannot be factored at v.
std::vector<std::vector<C>> factors(const DiagnosisRun& r, const StateSpace& ss, const Paths& base,
                                    const StateEntry& e, double v) {
  const auto moved = state_paths(with_entry(ss, e, v));
  if (!moved) return {};
  return path_ratio(r, ss, base, *moved);
}

double state_chi2_with(const DiagnosisRun& r, const std::vector<std::vector<C>>& F) {
  double c = 0;
  for (size_t k = 0; k < r.pairs.size(); ++k) {
    const PairFit& p = r.pairs[k];
    for (size_t q = 0; q < p.w.size(); ++q) {
      const C f = F.empty() ? p.factor[q] : p.factor[q] * F[k][q];
      c += std::norm((p.meas[q] - p.sim[q] * f) / p.sig[q]);
    }
  }
  return c;
}

// rms |ln(model / measured)| over every prepared pair with F on top of their factors.
double state_error_with(const DiagnosisRun& r, const std::vector<std::vector<C>>& F) {
  double s = 0;
  size_t n = 0;
  for (size_t k = 0; k < r.pairs.size(); ++k) {
    const PairFit& p = r.pairs[k];
    for (size_t q = 0; q < p.w.size(); ++q) {
      const C f = F.empty() ? p.factor[q] : p.factor[q] * F[k][q];
      const C m = p.sim[q] * f;
      if (std::abs(m) == 0 || std::abs(p.meas[q]) == 0) continue;
      s += std::norm(std::log(m / p.meas[q]));
      ++n;
    }
  }
  return n ? std::sqrt(s / double(n)) : 0;
}

struct Fitted {
  StateEntry e;
  double value = 0, chi2 = INFINITY;
  std::vector<std::vector<C>> F;
};

Fitted fit_entry(const DiagnosisRun& r, const StateSpace& ss, const Paths& base,
                 const StateEntry& e) {
  const double v0 = entry_value(ss, e);
  const bool rate = e.matrix == 'A' && e.row == e.col;
  // The scan's coordinate x: ln |v| for a rate (its sign kept), v itself otherwise.
  auto value = [&](double x) { return rate ? std::copysign(std::exp(x), v0) : x; };
  const double lo = rate ? std::log(std::abs(v0) / kSpan) : v0 - kSpan * std::abs(v0);
  const double hi = rate ? std::log(std::abs(v0) * kSpan) : v0 + kSpan * std::abs(v0);
  auto chi2_at = [&](double x) {
    const auto F = factors(r, ss, base, e, value(x));
    return F.empty() ? INFINITY : state_chi2_with(r, F);
  };
  std::vector<double> xs(kScan), cs(kScan);
  size_t best = 0;
  for (int q = 0; q < kScan; ++q) {
    xs[size_t(q)] = lo + (hi - lo) * q / (kScan - 1);
    cs[size_t(q)] = chi2_at(xs[size_t(q)]);
    if (cs[size_t(q)] < cs[best]) best = size_t(q);
  }
  Fitted f;
  f.e = e;
  if (!std::isfinite(cs[best])) return f;
  const double a = xs[best > 0 ? best - 1 : 0], b = xs[std::min(best + 1, xs.size() - 1)];
  const double x = detail::brent_minimum(chi2_at, a, b, kStateBrentBits);
  f.value = value(x);
  f.F = factors(r, ss, base, e, f.value);
  f.chi2 = f.F.empty() ? INFINITY : state_chi2_with(r, f.F);
  return f;
}

// The state model's nonzero entries of A, B and C.
std::vector<StateEntry> candidates_of(const StateSpace& ss) {
  std::vector<StateEntry> out;
  for (int i = 0; i < ss.A.rows(); ++i)
    for (int j = 0; j < ss.A.cols(); ++j)
      if (ss.A(i, j) != 0) out.push_back({'A', i, j});
  for (int i = 0; i < ss.B.rows(); ++i)
    for (int j = 0; j < ss.B.cols(); ++j)
      if (ss.B(i, j) != 0) out.push_back({'B', i, j});
  for (int i = 0; i < ss.C.rows(); ++i)
    for (int j = 0; j < ss.C.cols(); ++j)
      if (ss.C(i, j) != 0) out.push_back({'C', i, j});
  return out;
}

bool same_entry(const StateEntry& a, const StateEntry& b) {
  return a.matrix == b.matrix && a.row == b.row && a.col == b.col;
}

// The best entry to move on top of `ss` (the others' factors on the pairs), `skip` left out.
Fitted best_entry(const DiagnosisRun& r, const StateSpace& ss,
                  const std::vector<StateEntry>& skip) {
  Fitted best;
  const auto base = state_paths(ss);
  if (!base) return best;
  for (const StateEntry& e : candidates_of(ss)) {
    if (std::any_of(skip.begin(), skip.end(),
                    [&](const StateEntry& s) { return same_entry(s, e); }))
      continue;
    Fitted f = fit_entry(r, ss, *base, e);
    if (f.chi2 < best.chi2) best = std::move(f);
  }
  return best;
}

}  // namespace

void states(DiagnosisRun& r) {
  if (!r.sim.state_space || r.pairs.empty()) return;
  const StateSpace& sim = *r.sim.state_space;
  const auto sim_paths = state_paths(sim);
  if (!sim_paths) return;
  size_t n = 0;
  std::vector<std::string> pairs;
  std::vector<std::vector<C>> f0;  // the pairs' factors before this stage
  for (const PairFit& p : r.pairs) {
    n += p.w.size();
    f0.push_back(p.factor);
    if (!PairId::parse(p.pair).actuator()) pairs.push_back(p.pair);
  }
  // The accepted entries (distinct, so their order does not matter); set_factors puts those but
  // `skip` on the pairs and returns that state model.
  std::vector<Fitted> taken;
  auto set_factors = [&](size_t skip) {
    StateSpace ss = sim;
    for (size_t j = 0; j < taken.size(); ++j)
      if (j != skip) ss = with_entry(ss, taken[j].e, taken[j].value);
    const auto paths = state_paths(ss);
    const auto F = paths ? path_ratio(r, sim, *sim_paths, *paths) : std::vector<std::vector<C>>{};
    for (size_t k = 0; k < r.pairs.size(); ++k)
      for (size_t q = 0; q < r.pairs[k].w.size(); ++q)
        r.pairs[k].factor[q] = F.empty() ? f0[k][q] : f0[k][q] * F[k][q];
    return ss;
  };
  auto entries_but = [&](size_t skip) {
    std::vector<StateEntry> out;
    for (size_t j = 0; j < taken.size(); ++j)
      if (j != skip) out.push_back(taken[j].e);
    return out;
  };
  for (int round = 0; round < kMaxEntries; ++round) {
    const StateSpace ss = set_factors(taken.size());
    const double c0 = state_chi2_with(r, {}), e0 = state_error_with(r, {});
    Fitted best = best_entry(r, ss, entries_but(taken.size()));
    if (!std::isfinite(best.chi2) || earned(c0, best.chi2, n, 1) <= 0 ||
        !(state_error_with(r, best.F) < e0))
      break;
    taken.push_back(std::move(best));
  }
  // Each accepted entry taken out and the best entry put in its place, the others as they are:
  // a first pick that stood in for two changed entries gives way to the entries that changed.
  for (int round = 0; round < kStateBackfitRounds && taken.size() > 1; ++round) {
    bool swapped = false;
    for (size_t j = 0; j < taken.size(); ++j) {
      const StateSpace ss = set_factors(j);
      const auto base = state_paths(ss);
      if (!base) continue;
      Fitted again = fit_entry(r, ss, *base, taken[j].e);
      Fitted best = best_entry(r, ss, entries_but(j));
      if (std::isfinite(best.chi2) && best.chi2 < again.chi2 * (1 - 1e-9) &&
          !same_entry(best.e, taken[j].e)) {
        taken[j] = std::move(best);
        swapped = true;
      } else if (std::isfinite(again.chi2)) {
        taken[j] = std::move(again);
      }
    }
    if (!swapped) break;
  }
  set_factors(taken.size());
  for (const Fitted& t : taken)
    r.state_findings.push_back(state_parameter_finding(sim, t.e, t.value, pairs));
}

}  // namespace fralab::diag
