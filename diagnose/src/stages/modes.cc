// Stage 3b, modes (docs/method/diagnosis.md, "The stages", 3b): a lightly damped pair of the
// simulation that every path of a scope holds (a structure's mode, seen by every sensor; a mode of
// one output's or one input's paths) is moved once, over all those pairs together, before any
// pair is diagnosed alone. Each pair's own fit would split it, or miss it where several modes
// moved and none alone removes a quarter of the pair's chi2.
//
// Candidates: pairs (zeta <= kLightZeta) of the paths' poles inside the band of the pairs that
// hold them, held (wn within kSameRoot) by every X:O pair of the plant, of one output, or of one
// input (at least two pairs). A move is the factor D_from / D_to on each pair (ln wn by a grid
// over +-kSearchRel, between the neighbours of its pairs (ModeRange), in steps of a third of the
// damping, then the damping, then the two alternately by Brent's method), or, when its chi2 is
// lower, the same move with each path's mode shape kept (mode_residues.h; such moves of several
// modes on one path add, as the modes' terms do, where the factors multiply: Moves). chi2 here is
// taken in the logarithm with each pair's gain left free (pair_log_chi2): a calibration or a path
// gain, fitted by the later stages, is not taken up by a mode, and a wrong neighbour's peak does
// not flatten the mode being fitted. Greedy, while a move lowers chi2 by more than k ln 2N in units
// of its pairs' misfit level s = max(1, chi2 / N) and lowers their error; then each mode fitted
// again with the others in place, the forms compared whole (every move with its shape kept, kept
// when chi2 is lower), neighbours whose bands overlap fitted again in the other order and past
// each other (ModeSearch::other_orders), and the least useful dropped while it does not earn its
// place. A frequency move below kBandShare of the half-power band is a damping_error.
#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <set>

#include "../causes/mode_residues.h"
#include "fralab/core/numerics.h"
#include "stages.h"

namespace fralab::diag {
namespace {

constexpr double kLightZeta = 0.2;  // a mode is lighter than this
constexpr double kSameRoot = 1e-3;  // a path holds the mode: a pole within this (relative)
constexpr double kSearchRel = 0.1;  // ln wn searched within +-this of the simulated
constexpr double kZetaSpan = 10;    // the damping within a factor of this of the simulated
constexpr int kMaxModes = 12;       // modes moved at most
constexpr int kRounds = 8;          // frequency / damping alternations at most
constexpr int kBackfitRounds = 2;   // each mode fitted again with the others in place
constexpr double kBandShare = 0.1;  // a frequency move below this share of the band is none
constexpr int kMaxGrid = 400;       // the frequency grid's points at most (steps >= 0.05 %)
constexpr int kBrentBits = 20;      // Brent's method's precision (bits)
// A mode keeps its place among the modes of its pairs: its frequency stays this many times the
// lighter damping (relative) from each neighbour's frequency as it now is (ModeRange).
constexpr double kApartZetas = 0.25;

struct SharedMode {
  size_t id = 0;  // its index among the stage's candidates
  Root root;
  Scope scope = Scope::kPlant;
  std::string input, output;
  std::vector<size_t> pairs;  // into r.pairs
  // Per pair, for the move with the shape kept: the path's residue at the mode and its rational
  // part at the pair's points (empty when a path does not hold the mode as a simple pole).
  std::vector<C> residue;
  std::vector<std::vector<C>> rational;
  std::vector<std::vector<C>> from_factor;  // per pair, D_from at its points
};

// The residues and rational parts of m's paths (SharedMode), once per mode.
void prepare_residues(const DiagnosisRun& r, SharedMode& m) {
  for (size_t k : m.pairs)
    m.from_factor.push_back(factor_of(r.pairs[k].w, [&](C s) { return m.root.factor(s); }));
  for (size_t k : m.pairs) {
    const PairFit& p = r.pairs[k];
    const ModelPath* mp = r.sim.path(p.output, p.input);
    const auto res = mp ? pair_residue(mp->tf, m.root) : std::nullopt;
    if (!res) {
      m.residue.clear(), m.rational.clear();
      return;
    }
    m.residue.push_back(*res);
    m.rational.push_back(factor_of(p.w, [&](C s) { return mp->tf.rational(s); }));
  }
}

// Two pairs are one mode when their frequencies agree within kSameRoot.
bool same_root(const Root& a, const Root& b) {
  return a.pair && b.pair && std::abs(a.wn - b.wn) <= kSameRoot * b.wn;
}

bool holds(const Model& m, const PairFit& p, const Root& root) {
  std::vector<Root> v;
  if (const ModelPath* mp = m.path(p.output, p.input)) v = mp->tf.poles;
  const int o = m.output_index(p.output);
  if (o >= 0 && m.outputs[size_t(o)].sensor)
    v.insert(v.end(), m.outputs[size_t(o)].sensor->poles.begin(),
             m.outputs[size_t(o)].sensor->poles.end());
  return std::any_of(v.begin(), v.end(), [&](const Root& q) { return same_root(q, root); });
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
      if (std::any_of(seen.begin(), seen.end(), [&](const Root& q) { return same_root(q, root); }))
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
        m->id = out.size();
        m->root = root;
        prepare_residues(r, *m);
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
  bool residues_kept = false;  // the move keeps each path's mode shape (mode_residues.h)
};

// Where a mode's ln wn is searched: within +-kSearchRel of the simulated, and between the
// neighbours of its pairs as they now are (two modes moved onto one frequency are one mode
// counted twice, whose split the data cannot tell), its damping within a factor kZetaSpan. Each
// neighbour bounds it on the side the simulation has it, or on the other side where the search
// took the two past each other (`crossed`, lower id first); `ignore` bounds it not at all.
struct ModeRange {
  double lo = 0, hi = 0, lz_lo = 0, lz_hi = 0;
  double clamp(double x) const { return std::clamp(x, lo, hi); }
  double clamp_z(double x) const { return std::clamp(x, lz_lo, lz_hi); }
};

using Crossed = std::set<std::pair<size_t, size_t>>;

ModeRange range_of(const std::vector<SharedMode>& all, const std::vector<Root>& now, size_t id,
                   const Crossed& crossed, std::optional<size_t> ignore) {
  const SharedMode& m = all[id];
  const double lw0 = std::log(m.root.wn);
  ModeRange g{lw0 - kSearchRel, lw0 + kSearchRel, std::log(m.root.zeta / kZetaSpan),
              std::log(m.root.zeta * kZetaSpan)};
  bool past = false;  // some neighbour bounds it on the other side
  for (const SharedMode& n : all) {
    if (n.id == id || n.id == ignore || std::none_of(n.pairs.begin(), n.pairs.end(), [&](size_t k) {
          return std::find(m.pairs.begin(), m.pairs.end(), k) != m.pairs.end();
        }))
      continue;
    const bool swapped = crossed.count({std::min(id, n.id), std::max(id, n.id)}) > 0;
    past |= swapped;
    const double gap = kApartZetas * std::min(m.root.zeta, now[n.id].zeta);
    const double ln = std::log(now[n.id].wn);
    if ((n.root.wn < m.root.wn) != swapped)
      g.lo = std::max(g.lo, ln + gap);
    else
      g.hi = std::min(g.hi, ln - gap);
  }
  if (!past && !(g.lo < lw0 && lw0 < g.hi)) g.lo = std::min(g.lo, lw0), g.hi = std::max(g.hi, lw0);
  if (!(g.lo < g.hi)) g.lo = g.hi = past ? g.lo : lw0;
  return g;
}

// The mode's move to `to` at point q of its j-th pair: the factor D_from / D_to, or with the
// path's mode shape kept (mode_residues.h; m.residue not empty).
C move_factor(const SharedMode& m, size_t j, size_t q, double w, const Root& to, bool shape_kept) {
  const C s(0, w);
  return shape_kept ? residue_move_factor(m.rational[j][q], m.root, to, m.residue[j], s)
                    : m.from_factor[j][q] / to.factor(s);
}

// The move to `to` on each of the mode's pairs.
std::vector<std::vector<C>> move_factors(const DiagnosisRun& r, const SharedMode& m, const Root& to,
                                         bool shape_kept) {
  std::vector<std::vector<C>> F;
  for (size_t j = 0; j < m.pairs.size(); ++j) {
    const PairFit& p = r.pairs[m.pairs[j]];
    std::vector<C> f(p.w.size());
    for (size_t q = 0; q < p.w.size(); ++q) f[q] = move_factor(m, j, q, p.w[q], to, shape_kept);
    F.push_back(std::move(f));
  }
  return F;
}

// The moves taken so far, per pair of r: the pair's factor is base x mult x (1 + add), base its
// factor before the stage. A move by the factor D_from / D_to multiplies (pole-zero factors
// compose by product); a move with the mode shape kept adds its term to the path's partial
// fractions, (R + delta) / R = 1 + delta / R with delta = r' / (s - p') - r / (s - p) + conj:
// modes add, and the product of two neighbours' factors would count their overlap twice (a few
// per cent near two modes whose half-power bands overlap).
struct Moves {
  std::vector<std::vector<C>> base, mult, add;
  explicit Moves(const DiagnosisRun& r) {
    for (const PairFit& p : r.pairs) {
      base.push_back(p.factor);
      mult.emplace_back(p.factor.size(), C(1));
      add.emplace_back(p.factor.size(), C(0));
    }
  }
  // Pair k's factor at point q with the move F on top (shape_kept: F = 1 + delta / R).
  C with(size_t k, size_t q, C F, bool shape_kept) const {
    return shape_kept ? base[k][q] * mult[k][q] * (C(1) + add[k][q] + (F - C(1)))
                      : base[k][q] * mult[k][q] * (C(1) + add[k][q]) * F;
  }
  C now(size_t k, size_t q) const { return base[k][q] * mult[k][q] * (C(1) + add[k][q]); }
};

// chi2 of one pair in the logarithm, its gain profiled out: each point's term is
// |ln(model / meas) - ln g|^2 (|meas| / sigma)^2, g the pair's real gain that minimises the sum
// (the weighted mean of ln |model / meas|). Near the fit a point's term is its
// |meas - model|^2 / sigma^2; far from it, the logarithm weighs a resonance the model puts where
// the data have none as it weighs one the data have where the model has none (the plain term
// weighs the first by the peak's height squared, and a fit of one mode next to another mode that
// is wrong then flattens its own peak). The gain left free keeps a calibration or a path's gain,
// which later stages fit, from being taken up by the modes.
template <class Model>
double pair_log_chi2(const PairFit& p, Model&& model) {
  double sw = 0, swa = 0, swaa = 0, swbb = 0;
  for (size_t q = 0; q < p.w.size(); ++q) {
    const C m = model(q);
    if (!(std::abs(m) > 0) || !(std::abs(p.meas[q]) > 0)) continue;
    const C l = std::log(m / p.meas[q]);
    const double w = std::norm(p.meas[q]) / (p.sig[q] * p.sig[q]);
    sw += w, swa += w * l.real(), swaa += w * l.real() * l.real(), swbb += w * l.imag() * l.imag();
  }
  return sw > 0 ? std::max(0.0, swaa - swa * swa / sw) + swbb : 0.0;
}

// chi2 over the mode's pairs with the move F on top of their factors (none: their factors as
// they are).
double chi2_with(const DiagnosisRun& r, const Moves& mv, const SharedMode& m,
                 const std::vector<std::vector<C>>& F = {}, bool shape_kept = false) {
  double c = 0;
  for (size_t j = 0; j < m.pairs.size(); ++j) {
    const size_t k = m.pairs[j];
    const PairFit& p = r.pairs[k];
    c += pair_log_chi2(p, [&](size_t q) {
      return p.sim[q] * (F.empty() ? mv.now(k, q) : mv.with(k, q, F[j][q], shape_kept));
    });
  }
  return c;
}

// chi2 over the mode's pairs with the mode moved to `to`, as chi2_with of move_factors without
// building them: the searches' inner loop.
double chi2_moved(const DiagnosisRun& r, const Moves& mv, const SharedMode& m, const Root& to,
                  bool shape_kept) {
  double c = 0;
  for (size_t j = 0; j < m.pairs.size(); ++j) {
    const size_t k = m.pairs[j];
    const PairFit& p = r.pairs[k];
    c += pair_log_chi2(p, [&](size_t q) {
      return p.sim[q] * mv.with(k, q, move_factor(m, j, q, p.w[q], to, shape_kept), shape_kept);
    });
  }
  return c;
}

// The points over the mode's pairs.
size_t points_over(const DiagnosisRun& r, const SharedMode& m) {
  size_t n = 0;
  for (size_t k : m.pairs) n += r.pairs[k].w.size();
  return n;
}

// The minimum of f over [a, b] by Brent's method; a when the interval is empty.
double brent_in(const std::function<double(double)>& f, double a, double b) {
  return b - a > 1e-12 ? detail::brent_minimum(f, a, b, kBrentBits) : a;
}

// From (lwn, lz): the frequency and the damping alternately by Brent's method (the frequency
// within the damping's share either side, the damping within a factor e^0.5, both inside g), at
// most kRounds, until both settle. Then the move at the simulated damping (`kept`, chi2 at lz0) is
// replaced by the free one when the damping lowers chi2 by one penalty in units of the misfit
// level.
MovedMode settle(const std::function<double(double, double)>& total, const ModeRange& g, double lwn,
                 double lz, const MovedMode& kept, size_t n, bool shape_kept) {
  for (int round = 0; round < kRounds; ++round) {
    const double lwn_was = lwn, lz_was = lz;
    const double step = std::max(1e-4, std::exp(lz));
    lwn =
        brent_in([&](double x) { return total(x, lz); }, g.clamp(lwn - step), g.clamp(lwn + step));
    lz =
        brent_in([&](double x) { return total(lwn, x); }, g.clamp_z(lz - 0.5), g.clamp_z(lz + 0.5));
    if (std::abs(lwn - lwn_was) < 1e-6 && std::abs(lz - lz_was) < 1e-4) break;
  }
  const double c2 = total(lwn, lz);
  if (earned(kept.chi2, c2, n, 1) > 0) return {std::exp(lwn), std::exp(lz), c2, 2, {}, shape_kept};
  return kept;
}

// The same move with each path's mode shape kept, from the factor's optimum (frequency and damping
// alternately, as the factor's): it replaces `factor` when it has the lower chi2 (a structure's
// mode moves with its shape, and its antiresonances with it), or always when `shape_only`.
MovedMode with_residues_kept(const DiagnosisRun& r, const Moves& mv, const SharedMode& m,
                             const ModeRange& g, const MovedMode& factor, size_t n,
                             bool shape_only) {
  auto to = [](double lwn, double lz) { return Root::Pair(std::exp(lwn), std::exp(lz)); };
  if (m.residue.empty()) return factor;
  auto total = [&](double lwn, double lz) { return chi2_moved(r, mv, m, to(lwn, lz), true); };
  double lwn = std::log(factor.wn), lz = std::log(m.root.zeta);
  const double step = std::max(1e-4, m.root.zeta);
  lwn = brent_in([&](double x) { return total(x, lz); }, g.clamp(lwn - step), g.clamp(lwn + step));
  MovedMode best{std::exp(lwn), m.root.zeta, total(lwn, lz), 1, {}, true};
  best = settle(total, g, lwn, std::log(factor.zeta), best, n, true);
  if (!shape_only && !(best.chi2 < factor.chi2)) return factor;
  best.F = move_factors(r, m, Root::Pair(best.wn, best.zeta), true);
  return best;
}

MovedMode fit_mode(const DiagnosisRun& r, const Moves& mv, const SharedMode& m, const ModeRange& g,
                   bool shape_only) {
  const Root& from = m.root;
  auto to = [](double lwn, double lz) { return Root::Pair(std::exp(lwn), std::exp(lz)); };
  auto total = [&](double lwn, double lz) { return chi2_moved(r, mv, m, to(lwn, lz), false); };
  const double lz0 = std::log(from.zeta);
  const int grid = std::max(
      1, std::min(kMaxGrid, int(std::ceil((g.hi - g.lo) / std::min(0.01, from.zeta / 3)))));
  double lwn =
      g.hi > g.lo ? minimise_1d([&](double x) { return total(x, lz0); }, g.lo, g.hi, grid) : g.lo;
  MovedMode best{std::exp(lwn), from.zeta, total(lwn, lz0), 1, {}};
  const double lz = minimise_1d([&](double x) { return total(lwn, x); }, g.lz_lo, g.lz_hi, 40);
  const size_t n = points_over(r, m);
  best = settle(total, g, lwn, lz, best, n, false);
  best.F = move_factors(r, m, Root::Pair(best.wn, best.zeta), false);
  return with_residues_kept(r, mv, m, g, best, n, shape_only);
}

// The error metric over the mode's pairs, their current factors with the move F (empty: none).
double error_with(const DiagnosisRun& r, const Moves& mv, const SharedMode& m,
                  const std::vector<std::vector<C>>& F, bool shape_kept) {
  double s = 0;
  size_t n = 0;
  for (size_t j = 0; j < m.pairs.size(); ++j) {
    const size_t k = m.pairs[j];
    const PairFit& p = r.pairs[k];
    for (size_t q = 0; q < p.w.size(); ++q) {
      const C model = p.sim[q] * (F.empty() ? mv.now(k, q) : mv.with(k, q, F[j][q], shape_kept));
      s += std::norm(std::log(model / p.meas[q]));
      ++n;
    }
  }
  return n ? std::sqrt(s / double(n)) : 0.0;
}

// The move f on (or, inverse, off) each of the mode's pairs (Moves), their factors updated.
void apply_factor(DiagnosisRun& r, Moves& mv, const SharedMode& m, const MovedMode& f,
                  bool inverse) {
  for (size_t j = 0; j < m.pairs.size(); ++j) {
    const size_t k = m.pairs[j];
    PairFit& p = r.pairs[k];
    for (size_t q = 0; q < p.w.size(); ++q) {
      const C F = f.F[j][q];
      if (f.residues_kept)
        mv.add[k][q] += inverse ? C(1) - F : F - C(1);
      else
        mv.mult[k][q] *= inverse ? C(1) / F : F;
      p.factor[q] = mv.now(k, q);
    }
  }
}

// A damping change alone: the frequency moved by less than a tenth of the mode's half-power
// band (zeta, relative), or its move does not lower chi2 by one penalty in units of the misfit
// level. The finding is then the pair's damping_error, whose parameter is the damping.
bool damping_only(const DiagnosisRun& r, const Moves& mv, const SharedMode& m, const MovedMode& f) {
  if (f.k < 2) return false;
  if (std::abs(f.wn / m.root.wn - 1) < kBandShare * m.root.zeta) return true;
  const double c_from =
      chi2_with(r, mv, m, move_factors(r, m, Root::Pair(m.root.wn, f.zeta), f.residues_kept),
                f.residues_kept);
  return earned(c_from, f.chi2, points_over(r, m), 1) <= 0;
}

Finding finding_of(const DiagnosisRun& r, const Moves& mv, const SharedMode& m,
                   const MovedMode& fit) {
  Finding f;
  f.scope = m.scope;
  f.input = m.input;
  f.output = m.output;
  if (damping_only(r, mv, m, fit)) {
    f.cause = CauseKind::kDampingError;
    f.parameters = {
        {Param::kWnRadS, m.root.wn}, {Param::kFromZeta, m.root.zeta}, {Param::kToZeta, fit.zeta}};
    if (fit.residues_kept) f.text_parameters["form"] = "residue";
  } else {
    f.cause = CauseKind::kPoleShift;
    f.parameters = {{Param::kFromRadS, m.root.wn},
                    {Param::kToRadS, fit.wn},
                    {Param::kFromZeta, m.root.zeta},
                    {Param::kToZeta, fit.zeta},
                    {Param::kZeta, fit.zeta}};
    if (fit.residues_kept) f.text_parameters["form"] = "residue";
  }
  for (size_t k : m.pairs) f.pairs.push_back(r.pairs[k].pair);
  return f;
}

// chi2 over the pairs of the modes `ms` (each once), their factors as they now are.
double chi2_over(const DiagnosisRun& r, const Moves& mv, const std::vector<SharedMode>& ms) {
  std::vector<size_t> pairs;
  for (const SharedMode& m : ms)
    for (size_t k : m.pairs)
      if (std::find(pairs.begin(), pairs.end(), k) == pairs.end()) pairs.push_back(k);
  double c = 0;
  for (size_t k : pairs) {
    const PairFit& p = r.pairs[k];
    c += pair_log_chi2(p, [&](size_t q) { return p.sim[q] * mv.now(k, q); });
  }
  return c;
}

// Every pair's factor as the moves mv have it.
void restore_factors(DiagnosisRun& r, const Moves& mv) {
  for (size_t k = 0; k < r.pairs.size(); ++k)
    for (size_t q = 0; q < r.pairs[k].factor.size(); ++q) r.pairs[k].factor[q] = mv.now(k, q);
}

// The candidate of `left` whose move lowers chi2 most beyond its penalty and lowers its pairs'
// error (left.size() when none), and its move; a candidate tried that does not is marked unworthy.
template <class Fit>
std::pair<size_t, MovedMode> best_candidate(const DiagnosisRun& r, const Moves& mv,
                                            const std::vector<SharedMode>& left,
                                            std::vector<bool>& worth, const Fit& fit) {
  size_t best = left.size();
  MovedMode best_fit;
  double best_gain = 0;
  for (size_t c = 0; c < left.size(); ++c) {
    if (!worth[c]) continue;
    const SharedMode& m = left[c];
    const double c0 = chi2_with(r, mv, m);
    MovedMode f = fit(m);
    const double gain = earned(c0, f.chi2, points_over(r, m), f.k);
    worth[c] =
        gain > 0 && error_with(r, mv, m, f.F, f.residues_kept) < error_with(r, mv, m, {}, false);
    if (worth[c] && gain > best_gain) best = c, best_fit = std::move(f), best_gain = gain;
  }
  return {best, std::move(best_fit)};
}

// Some moves took the factor form where a mode shape is known.
bool forms_mixed(const std::vector<SharedMode>& taken, const std::vector<MovedMode>& fits) {
  return std::any_of(fits.begin(), fits.end(),
                     [](const MovedMode& f) { return !f.residues_kept; }) &&
         std::any_of(taken.begin(), taken.end(),
                     [](const SharedMode& m) { return !m.residue.empty(); });
}

// The taken move whose removal raises chi2 over its pairs least beyond its penalty (the others as
// they now are), and that gain.
std::pair<size_t, double> least_useful(DiagnosisRun& r, Moves& mv,
                                       const std::vector<SharedMode>& taken,
                                       const std::vector<MovedMode>& fits) {
  size_t worst = taken.size();
  double worst_gain = 0;
  for (size_t j = 0; j < taken.size(); ++j) {
    const double c_with = chi2_with(r, mv, taken[j]);
    apply_factor(r, mv, taken[j], fits[j], true);
    const double c0 = chi2_with(r, mv, taken[j]);
    apply_factor(r, mv, taken[j], fits[j], false);
    const double gain = earned(c0, c_with, points_over(r, taken[j]), fits[j].k);
    if (worst == taken.size() || gain < worst_gain) worst = j, worst_gain = gain;
  }
  return {worst, worst_gain};
}

// The moves the stage takes, applied to the pairs' factors.
struct Pass {
  std::vector<SharedMode> taken;
  std::vector<MovedMode> fits;
  Moves mv;
};

// Whether modes a and b share a pair.
bool share_pairs(const SharedMode& a, const SharedMode& b) {
  return std::any_of(a.pairs.begin(), a.pairs.end(), [&](size_t k) {
    return std::find(b.pairs.begin(), b.pairs.end(), k) != b.pairs.end();
  });
}

// The search for the moves: greedy, backfitted, the forms compared, neighbours taken in the
// other order, the least useful dropped (moves()).
class ModeSearch {
 public:
  ModeSearch(DiagnosisRun& r, std::vector<SharedMode> left)
      : r_(r), all_(left), left_(std::move(left)), mv_(r) {
    for (const SharedMode& m : all_) now_.push_back(m.root);
  }

  Pass run() {
    greedy();
    // Backfitting: each mode fitted again with every other one in place (modes moved towards
    // each other share their band, and the first one taken held part of the next).
    if (taken_.size() > 1) backfit();
    compare_forms();
    other_orders();
    drop_least_useful();
    return {std::move(taken_), std::move(fits_), std::move(mv_)};
  }

 private:
  MovedMode fit(const SharedMode& m) const {
    return fit_mode(r_, mv_, m, range_of(all_, now_, m.id, crossed_, ignore_), shape_only_);
  }
  void take(const SharedMode& m, const MovedMode& f, bool inverse) {
    apply_factor(r_, mv_, m, f, inverse);
    now_[m.id] = inverse ? m.root : Root::Pair(f.wn, f.zeta);
  }
  void refit(size_t j) {
    take(taken_[j], fits_[j], true);
    fits_[j] = fit(taken_[j]);
    take(taken_[j], fits_[j], false);
  }
  // Each taken mode fitted again with the others in place, kBackfitRounds times.
  void backfit() {
    for (int round = 0; round < kBackfitRounds; ++round)
      for (size_t j = 0; j < taken_.size(); ++j) refit(j);
  }

  // While a candidate's move earns its place, the best is taken. A candidate whose move did not
  // earn its place in a round is skipped in the next ones (each round refits every candidate it
  // tries); when none of the others earns its place, every candidate is tried again once before
  // the search stops (a neighbour's move can make one worth it).
  void greedy() {
    std::vector<bool> worth(left_.size(), true);
    bool full = true;
    while (int(taken_.size()) < kMaxModes && !left_.empty()) {
      auto [best, best_fit] =
          best_candidate(r_, mv_, left_, worth, [&](const SharedMode& m) { return fit(m); });
      if (best == left_.size()) {
        if (full) break;
        full = true;
        worth.assign(left_.size(), true);
        continue;
      }
      full = false;
      take(left_[best], best_fit, false);
      taken_.push_back(left_[best]);
      fits_.push_back(std::move(best_fit));
      left_.erase(left_.begin() + long(best));
      worth.erase(worth.begin() + long(best));
    }
  }

  // The forms compared whole: a mode fitted alone beside a neighbour sized wrong may take the
  // factor form, which then holds the neighbour where it is (modes moved with their shapes add;
  // a factor multiplies the neighbour's term too). Every move refitted with its shape kept, the
  // same rounds; kept when chi2 over the moved modes' pairs is lower than the mixed forms'.
  void compare_forms() {
    if (taken_.size() < 2 || !forms_mixed(taken_, fits_)) return;
    const State was = state();
    const double c_mixed = chi2_over(r_, mv_, taken_);
    shape_only_ = true;
    backfit();
    if (!(chi2_over(r_, mv_, taken_) < c_mixed)) restore(was);
  }

  // Neighbours in the other order: a taken mode and its neighbour on either side (a candidate
  // sharing its pairs, none between them, their half-power bands as they now are overlapping:
  // ln of their frequencies' ratio below the sum of their dampings) are fitted again, the
  // one fitted second first, then backfitted together. Where two modes moved towards each
  // other, the first one taken alone covers both peaks and bars the second from its place (each
  // stays on its side of the other). Then the two past each other, either fitted first (the
  // other then bounded on the far side of it), as where two modes moved across each other.
  // Each is kept when chi2 over their pairs is lower by more than the penalty of the parameters
  // it adds.
  void other_orders() {
    for (size_t j = 0; j < taken_.size(); ++j)
      for (const SharedMode* n : neighbours(taken_[j])) {
        const auto q = taken_index(n->id);
        if (q && *q < j) continue;  // tried from the other one
        const size_t a = taken_[j].id, b = n->id;
        try_pair(b, a, false);
        if (crossed_.count({std::min(a, b), std::max(a, b)})) continue;
        try_pair(a, b, true);
        try_pair(b, a, true);
      }
  }

  // The candidates next to m on either side (sharing its pairs, none between them) whose
  // half-power band overlaps m's.
  std::vector<const SharedMode*> neighbours(const SharedMode& m) const {
    const SharedMode* below = nullptr;
    const SharedMode* above = nullptr;
    for (const SharedMode& n : all_) {
      if (n.id == m.id || !share_pairs(m, n)) continue;
      if (n.root.wn < m.root.wn && (!below || n.root.wn > below->root.wn)) below = &n;
      if (n.root.wn > m.root.wn && (!above || n.root.wn < above->root.wn)) above = &n;
    }
    std::vector<const SharedMode*> out;
    const Root& x = now_[m.id];
    for (const SharedMode* n : {below, above})
      if (n && std::abs(std::log(x.wn / now_[n->id].wn)) < x.zeta + now_[n->id].zeta)
        out.push_back(n);
    return out;
  }

  // The moves of modes `first` and `second` taken off and fitted again in that order (crossing:
  // `first` fitted as if `second` were not there, `second` then on its far side), then backfitted
  // together; kept when chi2 over their pairs earns the parameters added, else undone.
  void try_pair(size_t first, size_t second, bool crossing) {
    const State was = state();
    const std::vector<SharedMode> both = {all_[first], all_[second]};
    const double c0 = chi2_over(r_, mv_, both);
    const int k0 = params_of(first) + params_of(second);
    for (size_t id : {first, second}) untake(id);
    if (crossing) crossed_.insert({std::min(first, second), std::max(first, second)});
    for (size_t id : {first, second}) {
      if (crossing) ignore_ = id == first ? std::optional<size_t>(second) : std::nullopt;
      MovedMode f = fit(all_[id]);
      take(all_[id], f, false);
      taken_.push_back(all_[id]);
      fits_.push_back(std::move(f));
    }
    // Backfitted until chi2 over the two falls by less than a thousandth a round.
    for (int round = 0; round < kRounds; ++round) {
      const double c = chi2_over(r_, mv_, both);
      for (size_t j = taken_.size() - 2; j < taken_.size(); ++j) refit(j);
      if (round + 1 >= kBackfitRounds && !(chi2_over(r_, mv_, both) < (1 - 1e-3) * c)) break;
    }
    const int k1 = params_of(first) + params_of(second);
    size_t n = 0;
    for (const SharedMode& m : both) n += points_over(r_, m);
    if (!(earned(c0, chi2_over(r_, mv_, both), n, std::max(0, k1 - k0)) > 0)) restore(was);
  }

  std::optional<size_t> taken_index(size_t id) const {
    for (size_t j = 0; j < taken_.size(); ++j)
      if (taken_[j].id == id) return j;
    return std::nullopt;
  }
  int params_of(size_t id) const {
    const auto j = taken_index(id);
    return j ? fits_[*j].k : 0;
  }
  // The mode's move taken off (when taken), the mode back among those left.
  void untake(size_t id) {
    if (const auto j = taken_index(id)) {
      take(taken_[*j], fits_[*j], true);
      taken_.erase(taken_.begin() + long(*j));
      fits_.erase(fits_.begin() + long(*j));
      return;
    }
    left_.erase(
        std::find_if(left_.begin(), left_.end(), [&](const SharedMode& m) { return m.id == id; }));
  }

  // Each must still earn its place with the others in place, as it did when taken: the least
  // useful is dropped while its removal raises chi2 by no more than its penalty in units of the
  // misfit level (a small move that made up for a neighbour taken before it was refitted), and
  // the rest fitted again.
  void drop_least_useful() {
    while (!taken_.empty()) {
      const auto [worst, worst_gain] = least_useful(r_, mv_, taken_, fits_);
      if (worst_gain > 0) break;
      take(taken_[worst], fits_[worst], true);
      std::erase_if(crossed_, [&](const auto& x) {  // back where the simulation has it
        return x.first == taken_[worst].id || x.second == taken_[worst].id;
      });
      left_.push_back(taken_[worst]);
      taken_.erase(taken_.begin() + long(worst));
      fits_.erase(fits_.begin() + long(worst));
      for (size_t j = 0; j < taken_.size(); ++j) refit(j);
    }
  }

  struct State {
    Moves mv;
    std::vector<MovedMode> fits;
    std::vector<Root> now;
    std::vector<SharedMode> taken, left;
    bool shape_only;
    Crossed crossed;
  };
  State state() const { return {mv_, fits_, now_, taken_, left_, shape_only_, crossed_}; }
  void restore(const State& s) {
    mv_ = s.mv, fits_ = s.fits, now_ = s.now, taken_ = s.taken, left_ = s.left;
    shape_only_ = s.shape_only, crossed_ = s.crossed;
    restore_factors(r_, mv_);
  }

  DiagnosisRun& r_;
  const std::vector<SharedMode> all_;
  std::vector<SharedMode> left_, taken_;
  std::vector<MovedMode> fits_;
  std::vector<Root> now_;  // each candidate's pair as it now is
  Moves mv_;
  bool shape_only_ = false;       // every move with its mode shape kept (compare_forms)
  Crossed crossed_;               // pairs of candidates the search took past each other
  std::optional<size_t> ignore_;  // a candidate the fit under way does not bound by
};

}  // namespace

void modes(DiagnosisRun& r) {
  Pass pass = ModeSearch(r, shared_modes(r)).run();
  // Each finding judged without its own factor on its pairs (the others in place).
  for (size_t j = 0; j < pass.taken.size(); ++j) {
    apply_factor(r, pass.mv, pass.taken[j], pass.fits[j], true);
    r.mode_findings.push_back(finding_of(r, pass.mv, pass.taken[j], pass.fits[j]));
    apply_factor(r, pass.mv, pass.taken[j], pass.fits[j], false);
  }
}

double earned(double c0, double c, size_t n, int k) {
  const double s = std::max(1.0, c / double(std::max<size_t>(n, 1)));
  return (c0 - c) / s - k * std::log(2.0 * double(n));
}

}  // namespace fralab::diag
