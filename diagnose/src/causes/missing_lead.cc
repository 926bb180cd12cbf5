// missing_lead: F = 1 + s/a, a real zero the simulation lacks, corner_rad_s = a
// (corner.h: the search). Consistent across pairs within DiagnoseOptions::consistent_rel.
#include "corner.h"

namespace fralab::diag {
namespace {

class MissingLead final : public LinearCause {
 public:
  CauseKind kind() const override { return CauseKind::kMissingLead; }
  void fit(const Model&, const PairFit& p, const DiagnoseOptions& opt,
           std::vector<Cause>* out) const override {
    out->push_back(fit_corner(kind(), true, p, opt));
  }
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const override {
    return params_within(a, b, {"corner_rad_s"}, opt.consistent_rel);
  }
  void extend(Tf& t, const Finding& f) const override {
    t.zeros.push_back(Root::Real(-f.parameters.at("corner_rad_s")));
  }
  std::string explain(const Finding& f) const override {
    return "a +20 dB/decade corner at " + fmt(f.parameters.at("corner_rad_s")) +
           " rad/s with its +90 deg phase";
  }
};

}  // namespace

const LinearCause& missing_lead_cause() {
  static const MissingLead c;
  return c;
}

}  // namespace fralab::diag
