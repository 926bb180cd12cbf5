// Stage 7, earns its place (docs/method/diagnosis.md, "The stages"): on the independent validation
// measurement, a finding removed from the extended model must raise its pairs' validation error.
// The one that helps least is dropped (and said why) until every remaining one does; then the
// extended model must beat the simulation on the validation data as a whole, or the least useful
// finding goes too. Without validation data every finding stays.
#include <cmath>

#include "stages.h"

namespace fralab::diag {

void earn_place(DiagnosisRun& r) {
  bool have_val = false;
  for (const auto& mp : r.data) have_val |= !mp.validation.points.empty();
  if (!have_val) return;
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

}  // namespace fralab::diag
