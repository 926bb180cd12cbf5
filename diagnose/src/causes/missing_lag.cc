// missing_lag: F = 1 / (1 + s/a), a real pole the simulation lacks, corner_rad_s = a (corner.h:
// the search, consistency and primary parameter it shares with missing_lead).
#include "corner.h"

namespace fralab::diag {
namespace {

class MissingLag final : public CornerCause {
 public:
  CauseKind kind() const override { return CauseKind::kMissingLag; }
  const char* name() const override { return "missing_lag"; }
  void extend(Tf& t, const Finding& f) const override {
    t.poles.push_back(Root::Real(-f.parameters.at(Param::kCornerRadS)));
  }
  std::string explain(const Finding& f) const override {
    return "a -20 dB/decade corner at " + fmt(f.parameters.at(Param::kCornerRadS)) +
           " rad/s with its -90 deg phase, absent from the simulation";
  }

 protected:
  bool lead() const override { return false; }
};

}  // namespace

const LinearCause& missing_lag_cause() {
  static const MissingLag c;
  return c;
}

}  // namespace fralab::diag
