// The linear catalogue: its order (BIC ties go to the first) and lookup by kind.
#include <cmath>

#include "cause.h"

namespace fralab::diag {

const std::vector<const LinearCause*>& linear_catalogue() {
  static const std::vector<const LinearCause*> v{&gain_mismatch_cause(),     &time_delay_cause(),
                                                 &missing_lag_cause(),       &missing_lead_cause(),
                                                 &missing_resonance_cause(), &pole_shift_cause(),
                                                 &damping_error_cause(),     &sign_error_cause()};
  return v;
}

const LinearCause* linear_cause(CauseKind kind) {
  for (const LinearCause* c : linear_catalogue())
    if (c->kind() == kind) return c;
  return nullptr;
}

bool params_within(const Cause& a, const Cause& b, const std::vector<std::string>& keys,
                   double tol_rel) {
  for (const std::string& k : keys) {
    const auto ia = a.params.find(k), ib = b.params.find(k);
    if (ia == a.params.end()) continue;
    if (ib == b.params.end()) return false;
    if (std::abs(ia->second - ib->second) > tol_rel * std::abs(ia->second)) return false;
  }
  return true;
}

}  // namespace fralab::diag
