// missing_resonance: a peak F = 1/(s^2/wn^2 + 2 zeta s/wn + 1) (a pole pair the simulation lacks)
// or a notch F = s^2/wn^2 + 2 zeta s/wn + 1 (an antiresonance: a zero pair), wn_rad_s and zeta.
// Search: wn log-spaced over the measured band (41 points) times zeta in {0.02 ... 0.7}, then four
// alternating Brent searches (ln wn +-0.1; zeta within [max(0.002, zeta/2), min(1, 2 zeta)]).
// A notch is reported with "shape": "notch". Consistent across pairs: same shape, wn within
// DiagnoseOptions::consistent_rel.
#include <cmath>

#include "cause.h"
#include "fralab/core/numerics.h"

namespace fralab::diag {
namespace {

class MissingResonance final : public LinearCause {
 public:
  CauseKind kind() const override { return CauseKind::kMissingResonance; }
  const char* name() const override { return "missing_resonance"; }
  // wn_rad_s: the simulation lacks the resonance (its value there is its absence); a frequency
  // stays positive.
  PrimaryParameter primary_parameter(const Finding&) const override {
    return {Param::kWnRadS, std::nullopt};
  }
  IntervalDomain interval_domain() const override { return {true, 1e-6}; }
  void fit(const Model&, const PairFit& p, const DiagnoseOptions&,
           std::vector<Cause>* out) const override {
    const double wlo = p.w.front(), whi = p.w.back();
    for (int notch = 0; notch < 2; ++notch) {
      auto F = [&](double lw, double z) {
        const double wn = std::exp(lw);
        return factor_of(p.w, [&](C s) {
          C d = s * s / (wn * wn) + 2 * z * s / wn + 1.0;
          return notch ? d : 1.0 / d;
        });
      };
      double blw = 0, bz = 0.1, bc = INFINITY;
      for (int k = 0; k <= 40; ++k) {
        double lw = std::log(wlo) + (std::log(whi) - std::log(wlo)) * k / 40;
        for (double z : {0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.7}) {
          double c = chi2(p, F(lw, z));
          if (c < bc) bc = c, blw = lw, bz = z;
        }
      }
      for (int it = 0; it < 4; ++it) {
        blw = detail::brent_minimum([&](double x) { return chi2(p, F(x, bz)); }, blw - 0.1,
                                    blw + 0.1, 24);
        bz = detail::brent_minimum([&](double z) { return chi2(p, F(blw, z)); },
                                   std::max(0.002, bz * 0.5), std::min(1.0, bz * 2), 24);
      }
      Cause c{kind(),     {{Param::kWnRadS, std::exp(blw)}, {Param::kZeta, bz}},
              F(blw, bz), 0,
              2,          notch ? "notch" : "peak"};
      if (notch) c.params[Param::kNotch] = 1;
      c.chi2 = chi2(p, c.F);
      out->push_back(std::move(c));
    }
  }
  bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) const override {
    return a.detail == b.detail && params_within(a, b, {Param::kWnRadS}, opt.consistent_rel);
  }
  void extend(Tf& t, const Finding& f) const override {
    const Root r = Root::Pair(f.parameters.at(Param::kWnRadS), f.parameters.at(Param::kZeta));
    (f.text_parameters.count("shape") ? t.zeros : t.poles).push_back(r);
  }
  std::string explain(const Finding& f) const override {
    return "a resonance at " + fmt(f.parameters.at(Param::kWnRadS)) + " rad/s, damping " +
           fmt(f.parameters.at(Param::kZeta));
  }
};

}  // namespace

const LinearCause& missing_resonance_cause() {
  static const MissingResonance c;
  return c;
}

}  // namespace fralab::diag
