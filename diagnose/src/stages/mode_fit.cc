// Stage 3b's fits (mode_fit.h): a mode's move by a grid and Brent's method in the factor form
// and with the mode shape kept, the moves on the pairs' factors, and chi2 in the logarithm.
#include "mode_fit.h"

#include <functional>

#include "../causes/mode_residues.h"
#include "fralab/core/numerics.h"

namespace fralab::diag::mode {

namespace {

// The mode's move to `to` at point q of its j-th pair: the factor D_from / D_to, or with the
// path's mode shape kept (mode_residues.h; m.residue not empty).
C move_factor(const SharedMode& m, size_t j, size_t q, double w, const Root& to, bool shape_kept) {
  const C s(0, w);
  return shape_kept ? residue_move_factor(m.rational[j][q], m.root, to, m.residue[j], s)
                    : m.from_factor[j][q] / to.factor(s);
}

}  // namespace

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

namespace {

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

}  // namespace

// chi2 over the mode's pairs with the move F on top of their factors (none: their factors as
// they are).
double chi2_with(const DiagnosisRun& r, const Moves& mv, const SharedMode& m,
                 const std::vector<std::vector<C>>& F, bool shape_kept) {
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

namespace {

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

}  // namespace

// The points over the mode's pairs.
size_t points_over(const DiagnosisRun& r, const SharedMode& m) {
  size_t n = 0;
  for (size_t k : m.pairs) n += r.pairs[k].w.size();
  return n;
}

namespace {

// The minimum of f over [a, b] by Brent's method; a when the interval is empty.
double brent_in(const std::function<double(double)>& f, double a, double b) {
  return b - a > 1e-12 ? detail::brent_minimum(f, a, b, kBrentBits) : a;
}

}  // namespace

namespace {

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

}  // namespace

namespace {

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

}  // namespace

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

bool share_pairs(const SharedMode& a, const SharedMode& b) {
  return std::any_of(a.pairs.begin(), a.pairs.end(), [&](size_t k) {
    return std::find(b.pairs.begin(), b.pairs.end(), k) != b.pairs.end();
  });
}

ModeRange range_of(const std::vector<SharedMode>& all, const std::vector<Root>& now, size_t id,
                   const Crossed& crossed, std::optional<size_t> ignore) {
  const SharedMode& m = all[id];
  const double lw0 = std::log(m.root.wn);
  ModeRange g{lw0 - kSearchRel, lw0 + kSearchRel, std::log(m.root.zeta / kZetaSpan),
              std::log(m.root.zeta * kZetaSpan)};
  bool past = false;  // some neighbour bounds it on the other side
  for (const SharedMode& n : all) {
    if (n.id == id || n.id == ignore || !share_pairs(m, n)) continue;
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

namespace {

// The pairs of the modes `ms`, each once.
std::vector<size_t> pairs_of(const std::vector<SharedMode>& ms) {
  std::vector<size_t> pairs;
  for (const SharedMode& m : ms)
    for (size_t k : m.pairs)
      if (std::find(pairs.begin(), pairs.end(), k) == pairs.end()) pairs.push_back(k);
  return pairs;
}

}  // namespace

size_t points_over(const DiagnosisRun& r, const std::vector<SharedMode>& ms) {
  size_t n = 0;
  for (size_t k : pairs_of(ms)) n += r.pairs[k].w.size();
  return n;
}

// chi2 over the pairs of the modes `ms` (each once), their factors as they now are.
double chi2_over(const DiagnosisRun& r, const Moves& mv, const std::vector<SharedMode>& ms) {
  double c = 0;
  for (size_t k : pairs_of(ms)) {
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

}  // namespace fralab::diag::mode
