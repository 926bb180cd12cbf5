// missing_lead: F = 1 + s/a, a real zero the simulation lacks, corner_rad_s = a (corner.h: the
// search, consistency and primary parameter it shares with missing_lag).
#include "corner.h"

namespace fralab::diag {
namespace {

class MissingLead final : public CornerCause {
 public:
  CauseKind kind() const override { return CauseKind::kMissingLead; }
  const char* name() const override { return "missing_lead"; }
  void extend(Tf& t, const Finding& f) const override {
    t.zeros.push_back(Root::Real(-f.parameters.at(Param::kCornerRadS)));
  }
  std::string explain(const Finding& f) const override {
    return "a +20 dB/decade corner at " + fmt(f.parameters.at(Param::kCornerRadS)) +
           " rad/s with its +90 deg phase";
  }

 protected:
  bool lead() const override { return true; }
};

}  // namespace

const LinearCause& missing_lead_cause() {
  static const MissingLead c;
  return c;
}

}  // namespace fralab::diag
