// The catalogue: every cause's unit, the order linear candidates are tried in (BIC ties go to the
// first), and lookup by kind. A new cause is its own unit (causes/<cause>.cc), its accessor
// declared and listed here (docs/development.md, "Adding a cause to the diagnosis"). Beside it,
// what every linear unit shares: where a finding's factor goes, and the consistency test.
#include <cmath>

#include "cause.h"
#include "fralab/core/pair_id.h"

namespace fralab::diag {

// Each cause's unit (diagnose/src/causes/<cause>.cc).
const LinearCause& gain_mismatch_cause();
const LinearCause& time_delay_cause();
const LinearCause& missing_lag_cause();
const LinearCause& missing_lead_cause();
const LinearCause& missing_resonance_cause();
const LinearCause& pole_shift_cause();
const LinearCause& damping_error_cause();
const LinearCause& sign_error_cause();
const CauseUnit& hysteresis_cause();
const CauseUnit& deadband_cause();
const CauseUnit& measurement_coupling_cause();
const CauseUnit& missing_path_cause();
const CauseUnit& state_parameter_cause();

const std::vector<const LinearCause*>& linear_catalogue() {
  static const std::vector<const LinearCause*> v{&gain_mismatch_cause(),     &time_delay_cause(),
                                                 &missing_lag_cause(),       &missing_lead_cause(),
                                                 &missing_resonance_cause(), &pole_shift_cause(),
                                                 &damping_error_cause(),     &sign_error_cause()};
  return v;
}

const std::vector<const CauseUnit*>& cause_units() {
  static const std::vector<const CauseUnit*> v = [] {
    std::vector<const CauseUnit*> all(linear_catalogue().begin(), linear_catalogue().end());
    for (const CauseUnit* u :
         {&hysteresis_cause(), &deadband_cause(), &measurement_coupling_cause(),
          &missing_path_cause(), &state_parameter_cause()})
      all.push_back(u);
    return all;
  }();
  return v;
}

const CauseUnit* cause_unit(CauseKind kind) {
  for (const CauseUnit* c : cause_units())
    if (c->kind() == kind) return c;
  return nullptr;
}

void LinearCause::apply(Model& m, const Finding& f) const {
  if (f.scope == Scope::kInput && f.output.empty() && f.pairs.size() == 1 &&
      PairId::parse(f.pairs[0]).command && PairId::parse(f.pairs[0]).input == f.input) {
    ModelInput& in = m.inputs[m.input_index(f.input)];
    if (!in.actuator) in.actuator = Tf{};
    extend(*in.actuator, f);
    return;
  }
  if (f.scope == Scope::kOutput) {
    ModelOutput& out = m.outputs[m.output_index(f.output)];
    if (out.sensor && acts_on(*out.sensor, f)) return extend(*out.sensor, f);
    if (acts_on(Tf{}, f)) {  // a factor: the sensor takes it
      if (!out.sensor) out.sensor = Tf{};
      return extend(*out.sensor, f);
    }
  }
  for (auto& p : m.paths) {
    const bool covered = f.scope == Scope::kPlant ||
                         (f.scope == Scope::kInput && p.input == f.input) ||
                         (f.scope == Scope::kOutput && p.output == f.output) ||
                         (f.scope == Scope::kPath && p.input == f.input && p.output == f.output);
    if (covered) extend(p.tf, f);
  }
}

bool params_within(const Cause& a, const Cause& b, const std::vector<Param>& keys, double tol_rel) {
  for (const Param k : keys) {
    const auto ia = a.params.find(k), ib = b.params.find(k);
    if (ia == a.params.end()) continue;
    if (ib == b.params.end()) return false;
    if (std::abs(ia->second - ib->second) > tol_rel * std::abs(ia->second)) return false;
  }
  return true;
}

}  // namespace fralab::diag
