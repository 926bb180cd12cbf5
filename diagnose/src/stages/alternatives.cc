// Stage 5e, simpler alternatives (docs/method/diagnosis.md, "The stages"): a missing resonance
// whose data see mostly its phase (at or beyond the top of the band, or damped near critical)
// fits what a delay, a lag, or a lag and a delay together fit as well. For each missing_resonance
// finding, those three alternatives are fitted over the finding's pairs at its scope, every other
// finding in place: the delay by a grid over [0, delay_max_s] (0.25 ms) then Brent's method, the
// lag by a grid over ln corner from a tenth of the pairs' lowest frequency to 30 times their
// highest, the two together from those by Levenberg-Marquardt (joint.cc's refine), each then sized
// with the findings whose pairs all lie among the resonance's. The finding is replaced by the
// alternative with the lowest BIC over its pairs, chi2 + k ln 2N (k: 2 for the resonance and for
// the lag with the delay, 1 for either alone), when that is lower than the resonance's. A missing
// lag whose corner lies above its pairs' band is replaced by a delay fitted and sized the same way
// when the delay's chi2 is within one ln 2N of the lag's.
#include <algorithm>
#include <cmath>
#include <optional>

#include "stages.h"

namespace fralab::diag {
namespace {

constexpr double kDelayStepS = 0.25e-3;  // the delay's grid
constexpr int kCornerGrid = 120;         // the lag's grid in ln corner

// One finding's place among the others: its pairs and their band, and chi2 over those pairs with
// the finding replaced by other findings at its scope, every other finding in place.
struct Around {
  Around(DiagnosisRun& run, size_t i)
      : r(run), f(run.findings[i]), pairs(fitted_pairs(run, f.pairs)) {
    for (const PairFit* p : pairs)
      for (double w : p->w) w_lo = std::min(w_lo, w), w_hi = std::max(w_hi, w);
    pen = bic_penalty(pairs);
    for (size_t x = 0; x < r.findings.size(); ++x)
      if (x != i) others.push_back(r.findings[x]);
  }
  std::vector<Finding> with(const std::vector<Finding>& extra) const {
    std::vector<Finding> all = others;
    all.insert(all.end(), extra.begin(), extra.end());
    return all;
  }
  double chi2_with(const std::vector<Finding>& extra) const {
    const std::vector<Finding> all = with(extra);
    return chi2_of(r, extended_by(r, all, all.size()), pairs);
  }
  Finding at_scope(CauseKind cause, Param key, double v) const {
    Finding a;
    a.cause = cause;
    a.scope = f.scope;
    a.input = f.input;
    a.output = f.output;
    a.pairs = f.pairs;
    a.parameters[key] = v;
    return a;
  }
  Finding delay(double t) const { return at_scope(CauseKind::kTimeDelay, Param::kDelayS, t); }
  // The other findings whose pairs all lie among f's (indices into `others`).
  std::vector<size_t> inside() const {
    std::vector<size_t> out;
    for (size_t x = 0; x < others.size(); ++x)
      if (!others[x].pairs.empty() &&
          std::all_of(others[x].pairs.begin(), others[x].pairs.end(), [&](const std::string& q) {
            return std::find(f.pairs.begin(), f.pairs.end(), q) != f.pairs.end();
          }))
        out.push_back(x);
    return out;
  }
  Finding lag(double lc) const { return at_scope(CauseKind::kMissingLag, Param::kCornerRadS, lc); }
  // The delay on top of `under` that fits best: a grid over [0, delay_max_s], then Brent's method.
  double best_delay(const std::vector<Finding>& under) const {
    const int grid = int(std::ceil(r.opt.delay_max_s / kDelayStepS));
    return minimise_1d(
        [&](double v) {
          std::vector<Finding> extra = under;
          extra.push_back(delay(v));
          return chi2_with(extra);
        },
        0.0, r.opt.delay_max_s, grid);
  }

  DiagnosisRun& r;
  const Finding f;
  const std::vector<const PairFit*> pairs;
  double w_lo = INFINITY, w_hi = 0, pen = 0;
  std::vector<Finding> others;
};

// A missing resonance replaced by the alternative of lowest BIC over its pairs, when lower than
// its own: a delay, a lag, or a lag and a delay. False when it stays.
bool resonance_alternative(DiagnosisRun& r, size_t i) {
  const Around a(r, i);
  const Finding& f = a.f;
  const double t = a.best_delay({});
  const double lc =
      std::exp(minimise_1d([&](double v) { return a.chi2_with({a.lag(std::exp(v))}); },
                           std::log(a.w_lo / 10), std::log(a.w_hi * 30), kCornerGrid));
  // The lag with the delay: from the lag alone and the delay fitted on top of it, refined
  // together.
  std::vector<Finding> both = a.with({a.lag(lc), a.delay(a.best_delay({a.lag(lc)}))});
  const size_t il = both.size() - 2, id = both.size() - 1;
  refine(r, both, {il, id}, a.pairs, 2);
  struct Alt {
    std::vector<Finding> extra;
    int k;
  };
  const std::vector<Alt> alts{{{a.delay(t)}, 1}, {{a.lag(lc)}, 1}, {{both[il], both[id]}, 2}};
  double best = a.chi2_with({f}) + 2 * a.pen;
  std::optional<std::vector<Finding>> chosen;
  for (const Alt& alt : alts) {
    // A delay stays >= 0 and a lag's corner inside what its search saw.
    bool ok = true;
    for (const Finding& e : alt.extra) {
      if (e.cause == CauseKind::kTimeDelay) ok &= e.parameters.at(Param::kDelayS) >= 0;
      if (e.cause == CauseKind::kMissingLag) {
        const double c = e.parameters.at(Param::kCornerRadS);
        ok &= c >= a.w_lo / 10 && c <= a.w_hi * 30;
      }
    }
    if (!ok) continue;
    // Sized together with the findings on the resonance's pairs alone (a path's lag beside it,
    // fitted with the resonance, is off for the delay that replaces it).
    std::vector<Finding> all = a.with(alt.extra);
    std::vector<size_t> group = a.inside();
    for (size_t k = 0; k < alt.extra.size(); ++k) group.push_back(a.others.size() + k);
    if (group.size() > alt.extra.size()) refine(r, all, group, a.pairs, 1);
    const double bic = chi2_of(r, extended_by(r, all, all.size()), a.pairs) + alt.k * a.pen;
    if (bic < best) best = bic, chosen = std::move(all);
  }
  if (!chosen) return false;
  r.findings = std::move(*chosen);
  return true;
}

// A lag whose corner lies above its pairs' band: the data see its phase, about -w / corner, and
// barely its gain. A delay fits that slope without a corner the data do not hold; it replaces the
// lag when it fits the lag's pairs within one parameter's penalty ln 2N of it (one parameter
// each: the data cannot tell the two apart). False when the lag stays.
bool lag_above_band(DiagnosisRun& r, size_t i) {
  const Around a(r, i);
  if (!(a.f.parameters.at(Param::kCornerRadS) > a.w_hi)) return false;
  const Finding d = a.delay(a.best_delay({}));
  if (!(d.parameters.at(Param::kDelayS) > 0)) return false;
  // Sized together with the findings on the lag's pairs alone, as a resonance's alternatives.
  std::vector<Finding> all = a.with({d});
  std::vector<size_t> group = a.inside();
  group.push_back(all.size() - 1);
  if (group.size() > 1) refine(r, all, group, a.pairs, 1);
  if (!(all.back().parameters.at(Param::kDelayS) > 0)) return false;
  if (!(chi2_of(r, extended_by(r, all, all.size()), a.pairs) <= a.chi2_with({a.f}) + a.pen))
    return false;
  r.findings = std::move(all);
  return true;
}

}  // namespace

bool simpler_alternatives(DiagnosisRun& r) {
  bool changed = false;
  for (size_t i = 0; i < r.findings.size(); ++i) {
    const Finding& f = r.findings[i];
    if (!f.by_value() || f.pairs.empty()) continue;
    if (points_of(fitted_pairs(r, f.pairs)) == 0) continue;
    const bool replaced =
        (f.cause == CauseKind::kMissingResonance && resonance_alternative(r, i)) ||
        (f.cause == CauseKind::kMissingLag && lag_above_band(r, i));
    if (!replaced) continue;
    changed = true;
    i = size_t(-1);  // the list changed: look again from its start
  }
  return changed;
}

}  // namespace fralab::diag
