// Internal to the diagnosis: the interface every cause of the catalogue implements, one unit per
// cause in diagnose/src/causes/ (docs/method/diagnosis.md, "The catalogue"). A unit says all the
// diagnosis needs to know of its cause: its word in diagnosis.json, its primary parameter (whose
// 1-sigma interval is reported and whose simulated value decides whether the data resolve it), the
// domain that interval is searched in, and how a finding of it extends a model.
//
// A linear cause (LinearCause) is a factor F(s; theta) multiplying the simulated response
// (diagnose.h states each factor and its parameters), fitted pair by pair; a finding of it extends
// the actuator, the sensor or the paths its scope covers. The nonlinear causes (hysteresis,
// deadband: describing functions, nonlinear.h), the measurement coupling (measurement_coupling.h)
// and a missing path (missing_path.h) are fitted jointly over several pairs by the functions
// beside this file, and extend the model in their own way.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "../pair_fit.h"
#include "fralab/core/tf.h"
#include "fralab/plant/model.h"

namespace fralab::diag {

/// Where a pole pair's damping is searched, per pair (pole_shift, damping_error) and in the joint
/// refinement.
inline constexpr double kDampingSearchMin = 0.002, kDampingSearchMax = 2.0;

/// A finding's primary parameter (nullopt when the cause has no continuous parameter, as a sign
/// error or a whole missing path) and its value in the simulation: nullopt when the simulation
/// lacks what the finding adds, so that "the simulation's value" is the finding's absence.
struct PrimaryParameter {
  std::optional<Param> key;
  std::optional<double> simulated;
};

/// Where the interval search brackets the primary parameter: a scale (a corner, a frequency, a
/// width) stays positive; `floor` is the least first step of the bracket, in the parameter's units.
struct IntervalDomain {
  bool positive = false;
  double floor = 1e-6;
};

/// A parameter besides the primary one that the data may resolve (a moved pair's damping): its
/// 1-sigma interval is reported; `fitted`: the data resolve it, so the joint refinement and the
/// decision of a finding's place count it as free. A scale: its interval stays positive.
struct SecondaryParameter {
  Param key;
  bool fitted = false;
};

class CauseUnit {
 public:
  virtual ~CauseUnit() = default;
  virtual CauseKind kind() const = 0;
  /// The cause's word, the `cause` of diagnosis.json. Part of the format: add, never rename.
  virtual const char* name() const = 0;
  virtual PrimaryParameter primary_parameter(const Finding& f) const = 0;
  virtual IntervalDomain interval_domain() const { return {}; }
  virtual std::vector<SecondaryParameter> secondary_parameters(const Finding&) const { return {}; }
  /// Brings the parameters a finding reports but does not fit (a moved pair's zeta, = to_zeta) in
  /// step with those fitted, once the later stages have moved them.
  virtual void settle(Finding&) const {}
  /// Extends the model by the finding.
  virtual void apply(Model& m, const Finding& f) const = 0;
  /// Whether two fits of this cause on different pairs are the same effect (scope grouping). A
  /// cause fitted jointly over several pairs is never grouped.
  virtual bool consistent(const Cause&, const Cause&, const DiagnoseOptions&) const {
    return false;
  }
  /// What the residual shows, for the report (scope is added by the caller).
  virtual std::string explain(const Finding& f) const = 0;
};

class LinearCause : public CauseUnit {
 public:
  /// Fits the cause to what remains of the pair (p.factor applied) and appends its candidates
  /// (none, one, or one per simulated pole), each with chi2 and F filled in.
  virtual void fit(const Model& sim, const PairFit& p, const DiagnoseOptions& opt,
                   std::vector<Cause>* out) const = 0;
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const override = 0;
  /// Extends a transfer function (path, actuator or sensor) by the finding's factor.
  virtual void extend(Tf& t, const Finding& f) const = 0;
  /// Whether `t` holds what the finding changes: a cause that moves a simulated root (pole_shift,
  /// damping_error) holds when `t` has that root; a factor (a lag, a gain, a delay), always.
  virtual bool acts_on(const Tf&, const Finding&) const { return true; }
  /// Extends by scope: a finding of the actuator pair u_X:X alone extends X's actuator; one of an
  /// output its sensor, unless it moves a root the sensor does not hold (a plant's mode moved at
  /// one output): then every path into the output; else every path the scope covers
  /// (docs/method/diagnosis.md, "Scope").
  void apply(Model& m, const Finding& f) const final;
};

/// The linear causes in the order candidates are tried (a tie in BIC goes to the first).
const std::vector<const LinearCause*>& linear_catalogue();
/// Every cause: the linear catalogue, then the causes fitted jointly.
const std::vector<const CauseUnit*>& cause_units();
/// The unit of a cause (nullptr: none, which no CauseKind is).
const CauseUnit* cause_unit(CauseKind kind);

/// |v - u| <= tol_rel |v| for every key of `a` in `keys` (both must carry it).
bool params_within(const Cause& a, const Cause& b, const std::vector<Param>& keys, double tol_rel);

}  // namespace fralab::diag
