// Stage 5e, simpler alternatives (docs/method/diagnosis.md, "The stages"): a missing resonance
// whose data see mostly its phase (at or beyond the top of the band, or damped near critical)
// fits what a delay, a lag, or a lag and a delay together fit as well. For each missing_resonance
// finding, those three alternatives are fitted over the finding's pairs at its scope, every other
// finding in place: the delay by a grid over [0, delay_max_s] (0.25 ms) then Brent's method, the
// lag by a grid over ln corner from a tenth of the pairs' lowest frequency to 30 times their
// highest, the two together from those by Levenberg-Marquardt (joint.cc's refine). The finding is
// replaced by the alternative with the lowest BIC over its pairs, chi2 + k ln 2N (k: 2 for the
// resonance and for the lag with the delay, 1 for either alone), when that is lower than the
// resonance's.
#include <algorithm>
#include <cmath>

#include "stages.h"

namespace fralab::diag {
namespace {

constexpr double kDelayStepS = 0.25e-3;  // the delay's grid
constexpr int kCornerGrid = 120;         // the lag's grid in ln corner

}  // namespace

bool simpler_alternatives(DiagnosisRun& r) {
  bool changed = false;
  for (size_t i = 0; i < r.findings.size(); ++i) {
    const Finding f = r.findings[i];
    if (f.cause != CauseKind::kMissingResonance || f.tf || !f.text_parameters.empty() ||
        f.pairs.empty())
      continue;
    const std::vector<const PairFit*> pairs = fitted_pairs(r, f.pairs);
    if (points_of(pairs) == 0) continue;
    double w_lo = INFINITY, w_hi = 0;
    for (const PairFit* p : pairs)
      for (double w : p->w) w_lo = std::min(w_lo, w), w_hi = std::max(w_hi, w);
    const double pen = bic_penalty(pairs);
    std::vector<Finding> others;
    for (size_t x = 0; x < r.findings.size(); ++x)
      if (x != i) others.push_back(r.findings[x]);
    auto with = [&](const std::vector<Finding>& extra) {
      std::vector<Finding> all = others;
      all.insert(all.end(), extra.begin(), extra.end());
      return all;
    };
    auto chi2_with = [&](const std::vector<Finding>& extra) {
      const std::vector<Finding> all = with(extra);
      return chi2_of(r, extended_by(r, all, all.size()), pairs);
    };
    auto at_scope = [&](CauseKind cause, const std::string& key, double v) {
      Finding a;
      a.cause = cause;
      a.scope = f.scope;
      a.input = f.input;
      a.output = f.output;
      a.pairs = f.pairs;
      a.parameters[key] = v;
      return a;
    };
    auto delay = [&](double t) { return at_scope(CauseKind::kTimeDelay, "delay_s", t); };
    auto lag = [&](double lc) { return at_scope(CauseKind::kMissingLag, "corner_rad_s", lc); };
    const int delay_grid = int(std::ceil(r.opt.delay_max_s / kDelayStepS));
    const double t = minimise_1d([&](double v) { return chi2_with({delay(v)}); }, 0.0,
                                 r.opt.delay_max_s, delay_grid);
    const double lc = std::exp(minimise_1d([&](double v) { return chi2_with({lag(std::exp(v))}); },
                                           std::log(w_lo / 10), std::log(w_hi * 30), kCornerGrid));
    // The lag with the delay: from the lag alone and the delay fitted on top of it, refined
    // together.
    const double t_on_lag = minimise_1d(
        [&](double v) {
          return chi2_with({lag(lc), delay(v)});
        },
        0.0, r.opt.delay_max_s, delay_grid);
    std::vector<Finding> both = with({lag(lc), delay(t_on_lag)});
    const size_t il = both.size() - 2, id = both.size() - 1;
    refine(r, both, {il, id}, pairs, 2);
    struct Alt {
      std::vector<Finding> extra;
      int k;
    };
    const std::vector<Alt> alts{{{delay(t)}, 1}, {{lag(lc)}, 1}, {{both[il], both[id]}, 2}};
    double best = chi2_with({f}) + 2 * pen;
    const Alt* chosen = nullptr;
    for (const Alt& a : alts) {
      // A delay stays >= 0 and a lag's corner inside what its search saw.
      bool ok = true;
      for (const Finding& e : a.extra) {
        if (e.cause == CauseKind::kTimeDelay) ok &= e.parameters.at("delay_s") >= 0;
        if (e.cause == CauseKind::kMissingLag) {
          const double c = e.parameters.at("corner_rad_s");
          ok &= c >= w_lo / 10 && c <= w_hi * 30;
        }
      }
      if (!ok) continue;
      const double bic = chi2_with(a.extra) + a.k * pen;
      if (bic < best) best = bic, chosen = &a;
    }
    if (!chosen) continue;
    r.findings = with(chosen->extra);
    changed = true;
    i = size_t(-1);  // the list changed: look again from its start
  }
  return changed;
}

}  // namespace fralab::diag
