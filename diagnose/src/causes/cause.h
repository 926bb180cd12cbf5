// Internal to the diagnosis: the interface every linear cause of the catalogue implements, one
// file per cause in diagnose/src/causes/. A linear cause is a factor F(s; theta) multiplying the
// simulated response (diagnose.h states each factor and its parameters); the nonlinear causes
// (hysteresis, deadband: describing functions) and the measurement coupling are fitted jointly
// over several pairs and live in nonlinear.h and coupling.h beside this file.
#pragma once

#include <string>
#include <vector>

#include "../pair_fit.h"
#include "fralab/core/tf.h"
#include "fralab/plant/model.h"

namespace fralab::diag {

class LinearCause {
 public:
  virtual ~LinearCause() = default;
  virtual CauseKind kind() const = 0;
  /// Fits the cause to what remains of the pair (p.factor applied) and appends its candidates
  /// (none, one, or one per simulated pole), each with chi2 and F filled in.
  virtual void fit(const Model& sim, const PairFit& p, const DiagnoseOptions& opt,
                   std::vector<Cause>* out) const = 0;
  /// Whether two fits of this cause on different pairs are the same effect (scope grouping).
  virtual bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const = 0;
  /// Extends a transfer function (path, actuator or sensor) by the finding's factor.
  virtual void extend(Tf& t, const Finding& f) const = 0;
  /// What the residual shows, for the report (scope is added by the caller).
  virtual std::string explain(const Finding& f) const = 0;
};

/// The catalogue in the order candidates are tried (a tie in BIC goes to the first).
const std::vector<const LinearCause*>& linear_catalogue();
/// The unit of one linear cause; nullptr for hysteresis, deadband and measurement_coupling.
const LinearCause* linear_cause(CauseKind kind);

/// |v - u| <= tol_rel |v| for every key of `a` in `keys` (both must carry it).
bool params_within(const Cause& a, const Cause& b, const std::vector<std::string>& keys,
                   double tol_rel);

// Each cause's unit (diagnose/src/causes/<cause>.cc).
const LinearCause& gain_mismatch_cause();
const LinearCause& time_delay_cause();
const LinearCause& missing_lag_cause();
const LinearCause& missing_lead_cause();
const LinearCause& missing_resonance_cause();
const LinearCause& pole_shift_cause();
const LinearCause& damping_error_cause();
const LinearCause& sign_error_cause();

}  // namespace fralab::diag
