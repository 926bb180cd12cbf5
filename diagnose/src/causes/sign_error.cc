// sign_error: F = -1, the path's (or sensor's, actuator's) sign inverted in the simulation;
// parameter sign = -1. One candidate when it lowers chi2. Consistent across pairs always (the same
// inversion). Extension: the tf's gain negated.
#include "cause.h"

namespace fralab::diag {
namespace {

class SignError final : public LinearCause {
 public:
  CauseKind kind() const override { return CauseKind::kSignError; }
  const char* name() const override { return "sign_error"; }
  // No continuous parameter: no interval, and resolved against its absence.
  PrimaryParameter primary_parameter(const Finding&) const override {
    return {std::nullopt, std::nullopt};
  }
  void fit(const Model&, const PairFit& p, const DiagnoseOptions&,
           std::vector<Cause>* out) const override {
    Cause c{kind(), {{Param::kSign, -1.0}}, std::vector<C>(p.w.size(), C(-1, 0)), 0, 1, ""};
    c.chi2 = chi2(p, c.F);
    out->push_back(std::move(c));
  }
  bool consistent(const Cause&, const Cause&, const DiagnoseOptions&) const override {
    return true;
  }
  void extend(Tf& t, const Finding&) const override { t.gain = -t.gain; }
  std::string explain(const Finding&) const override {
    return "measured and simulated responses 180 deg apart at every frequency, gains equal: the "
           "sign is inverted";
  }
};

}  // namespace

const LinearCause& sign_error_cause() {
  static const SignError c;
  return c;
}

}  // namespace fralab::diag
