#include "j85_case.h"

#include "fralab/plant/embedded_models.h"

namespace fralab::testing {

RandomCase j85_case(int index) {
  RandomCase c;
  c.name = "j85_" + std::to_string(index);
  c.simulation = load_model_or_embedded("j85_95_sim");
  c.engine = load_model_or_embedded("j85_95");
  auto effect = [&](CauseKind cause, Scope scope, const std::string& in, const std::string& out,
                    Param param, double value, double tol_abs, double tol_rel) {
    HiddenEffect e{};
    e.cause = cause, e.scope = scope, e.input = in, e.output = out, e.param = param;
    e.value = value, e.tol_abs = tol_abs, e.tol_rel = tol_rel;
    c.hidden.push_back(e);
  };
  for (const auto& [in, to] : {std::pair{"BLD", 35.8}, {"A8", 38.2}, {"IGV", 19.9}})
    effect(CauseKind::kPoleShift, Scope::kInput, in, "", Param::kToRadS, to, 0, 0.1);
  effect(CauseKind::kHysteresis, Scope::kInput, "A8", "", Param::kWidth, 9.24, 0, 0.05);
  for (const char* out : {"P3", "P5", "DPP3"})
    effect(CauseKind::kTimeDelay, Scope::kPath, "Wf", out, Param::kDelayS, 0.011, 0.5e-3, 0);
  effect(CauseKind::kMissingLag, Scope::kPath, "Wf", "N", Param::kCornerRadS, 76.7, 0, 0.1);
  effect(CauseKind::kMissingLag, Scope::kPath, "A8", "N", Param::kCornerRadS, 53.9, 0, 0.1);
  return c;
}

}  // namespace fralab::testing
