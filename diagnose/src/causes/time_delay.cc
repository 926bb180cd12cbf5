// time_delay: F = e^{-s tau}, delay_s = tau, searched over DiagnoseOptions' delay range (a grid
// then Brent's method). Consistent across pairs within max(consistent_delay_s, consistent_rel).
#include <algorithm>
#include <cmath>

#include "cause.h"

namespace fralab::diag {
namespace {

constexpr double kGridStepS = 0.25e-3;  // the grid before Brent's method (9 deg at 100 Hz)

class TimeDelay final : public LinearCause {
 public:
  CauseKind kind() const override { return CauseKind::kTimeDelay; }
  const char* name() const override { return "time_delay"; }
  // delay_s, 0 in the simulation (an added delay); its interval's bracket starts at least 10 us
  // wide.
  PrimaryParameter primary_parameter(const Finding&) const override {
    return {Param::kDelayS, 0.0};
  }
  IntervalDomain interval_domain() const override { return {false, 1e-5}; }
  void fit(const Model&, const PairFit& p, const DiagnoseOptions& opt,
           std::vector<Cause>* out) const override {
    auto F = [&](double tau) { return factor_of(p.w, [&](C s) { return std::exp(-s * tau); }); };
    const double tau =
        minimise_1d([&](double t) { return chi2(p, F(t)); }, opt.delay_min_s, opt.delay_max_s,
                    int(std::ceil((opt.delay_max_s - opt.delay_min_s) / kGridStepS)));
    Cause c{kind(), {{Param::kDelayS, tau}}, F(tau), 0, 1, ""};
    c.chi2 = chi2(p, c.F);
    out->push_back(std::move(c));
  }
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const override {
    const double v = a.params.at(Param::kDelayS), u = b.params.at(Param::kDelayS);
    return std::abs(v - u) <= std::max(opt.consistent_delay_s, opt.consistent_rel * std::abs(v));
  }
  void extend(Tf& t, const Finding& f) const override {
    t.delay_s = std::max(0.0, t.delay_s + f.parameters.at(Param::kDelayS));
  }
  std::string explain(const Finding& f) const override {
    return "phase residual linear in w (" + fmt(-f.parameters.at(Param::kDelayS) * 1e3) +
           " ms slope), gain residual flat";
  }
};

}  // namespace

const LinearCause& time_delay_cause() {
  static const TimeDelay c;
  return c;
}

}  // namespace fralab::diag
