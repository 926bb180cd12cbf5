// Stage 7, earns its place (docs/method/diagnosis.md, "The stages"). With an independent validation
// measurement: a finding removed from the extended model must raise its pairs' validation error.
// The one that helps least is dropped (and said why) until every remaining one does; then the
// extended model must beat the simulation on the validation data as a whole, or the least useful
// finding goes too. Without validation data, on the fitting data: a finding removed from the
// extended model must raise chi2 over its pairs by more than its parameters' BIC penalty
// (k ln 2N, N its pairs' points: an effect the noise alone would fit does not pass), and must
// raise its pairs' error (a finding whose removal lowers the error is never reported); the one
// that helps least goes first, one at a time, until every remaining one passes both.
#include <algorithm>
#include <cmath>

#include "stages.h"

namespace fralab::diag {
namespace {

// A finding's free parameters: its primary one (a sign error's discrete choice counts as one), each
// other the data resolve, and for a path the simulation lacks its fitted gain, delay, poles and
// zeros (a pair counting two).
int free_parameters(const Finding& f) {
  const CauseUnit& unit = *cause_unit(f.cause);
  int k = 1;
  for (const SecondaryParameter& sp : unit.secondary_parameters(f)) k += sp.fitted ? 1 : 0;
  if (f.tf) {
    k = 2;
    for (const std::vector<Root>* roots : {&f.tf->poles, &f.tf->zeros})
      for (const Root& x : *roots) k += x.pair ? 2 : 1;
  }
  return k;
}

void earn_place_by_validation(DiagnosisRun& r) {
  std::vector<Finding>& findings = r.findings;
  for (;;) {
    const Model full = extended_by(r, findings, findings.size());
    const bool worse_overall = error_over(r, full, {}, true) > error_over(r, r.sim, {}, true);
    int worst = -1;
    double worst_gain = INFINITY, worst_with = 0, worst_without = 0;
    for (size_t i = 0; i < findings.size(); ++i) {
      const double e_with = error_over(r, full, findings[i].pairs, true);
      const double e_without = error_over(r, extended_by(r, findings, i), findings[i].pairs, true);
      const double gain = e_without - e_with;
      if ((gain <= 0 || worse_overall) && gain < worst_gain) {
        worst = int(i), worst_gain = gain, worst_with = e_with, worst_without = e_without;
      }
    }
    if (worst < 0) break;
    r.d.dropped.push_back({findings[worst], "does not lower the validation error on its pairs (" +
                                                fmt(worst_without) + " without it, " +
                                                fmt(worst_with) + " with it)"});
    findings.erase(findings.begin() + worst);
  }
}

// chi2 of model m over the measured pairs `which` (the fitting data, sigma_eff as fitted), and
// their points.
std::pair<double, size_t> chi2_over(const DiagnosisRun& r, const Model& m,
                                    const std::vector<std::string>& which) {
  const std::vector<const PairFit*> pairs = fitted_pairs(r, which);
  return {chi2_of(r, m, pairs), points_of(pairs)};
}

void earn_place_by_criterion(DiagnosisRun& r) {
  std::vector<Finding>& findings = r.findings;
  for (;;) {
    const Model full = extended_by(r, findings, findings.size());
    int worst = -1;
    double worst_gain = INFINITY;
    std::string why;
    for (size_t i = 0; i < findings.size(); ++i) {
      const Finding& f = findings[i];
      const Model without = extended_by(r, findings, i);
      const auto [c_with, n] = chi2_over(r, full, f.pairs);
      const double c_without = chi2_over(r, without, f.pairs).first;
      const double penalty = free_parameters(f) * std::log(2.0 * double(std::max<size_t>(n, 1)));
      const double e_with = error_over(r, full, f.pairs, false);
      const double e_without = error_over(r, without, f.pairs, false);
      const double gain = e_without - e_with;
      const bool by_chi2 = c_without - c_with > penalty, by_error = gain > 0;
      if ((by_chi2 && by_error) || gain >= worst_gain) continue;
      worst = int(i), worst_gain = gain;
      why = !by_error ? "does not lower the error on its pairs (" + fmt(e_without) +
                            " without it, " + fmt(e_with) + " with it)"
                      : "does not lower chi2 on its pairs by more than its parameters' penalty (" +
                            fmt(c_without) + " without it, " + fmt(c_with) + " with it, needs " +
                            fmt(penalty) + " less)";
    }
    if (worst < 0) break;
    r.d.dropped.push_back({findings[size_t(worst)], why});
    findings.erase(findings.begin() + worst);
  }
}

}  // namespace

void earn_place(DiagnosisRun& r) {
  bool have_val = false;
  for (const auto& mp : r.data) have_val |= !mp.validation.points.empty();
  if (have_val)
    earn_place_by_validation(r);
  else
    earn_place_by_criterion(r);
}

}  // namespace fralab::diag
