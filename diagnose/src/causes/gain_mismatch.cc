// gain_mismatch: F = k (real, > 0), gain_db = 20 log10 k; fitted in closed form (weighted least
// squares over real k). Consistent across pairs within DiagnoseOptions::consistent_gain_db.
#include <cmath>

#include "cause.h"

namespace fralab::diag {
namespace {

class GainMismatch final : public LinearCause {
 public:
  CauseKind kind() const override { return CauseKind::kGainMismatch; }
  const char* name() const override { return "gain_mismatch"; }
  // gain_db, 0 dB in the simulation; its interval's bracket starts at least 1e-3 dB wide.
  PrimaryParameter primary_parameter(const Finding&) const override {
    return {Param::kGainDb, 0.0};
  }
  IntervalDomain interval_domain() const override { return {false, 1e-3}; }
  void fit(const Model&, const PairFit& p, const DiagnoseOptions&,
           std::vector<Cause>* out) const override {
    double num = 0, den = 0;
    for (size_t i = 0; i < p.w.size(); ++i) {
      C s = p.sim[i] * p.factor[i];
      const double v = 1 / (p.sig[i] * p.sig[i]);
      num += v * (std::conj(s) * p.meas[i]).real();
      den += v * std::norm(s);
    }
    const double k = num / den;
    if (!(k > 0)) return;
    Cause c{
        kind(), {{Param::kGainDb, 20 * std::log10(k)}}, std::vector<C>(p.w.size(), C(k, 0)), 0, 1,
        ""};
    c.chi2 = chi2(p, c.F);
    out->push_back(std::move(c));
  }
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const override {
    return std::abs(a.params.at(Param::kGainDb) - b.params.at(Param::kGainDb)) <=
           opt.consistent_gain_db;
  }
  void extend(Tf& t, const Finding& f) const override {
    t.gain *= std::pow(10.0, f.parameters.at(Param::kGainDb) / 20);
  }
  std::string explain(const Finding& f) const override {
    return "flat gain offset of " + fmt(f.parameters.at(Param::kGainDb)) + " dB, no phase";
  }
};

}  // namespace

const LinearCause& gain_mismatch_cause() {
  static const GainMismatch c;
  return c;
}

}  // namespace fralab::diag
