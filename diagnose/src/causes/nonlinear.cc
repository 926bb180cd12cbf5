#include "nonlinear.h"

#include <cmath>
#include <numbers>
#include <sstream>

#include "fralab/plant/nonlinearity.h"

namespace fralab::diag {

C nl_describing_function(CauseKind kind, double width, double y) {
  const bool backlash = kind == CauseKind::kHysteresis;
  auto out_amp = [&](double a) {
    return backlash ? std::abs(backlash_describing_function(a, width)) * a
                    : deadband_describing_function(a, width) * a;
  };
  double lo = width / 2, hi = width / 2 + 2 * y + 1e-12;
  while (out_amp(hi) < y) hi *= 2;
  for (int i = 0; i < 80; ++i) {
    double m = (lo + hi) / 2;
    (out_amp(m) < y ? lo : hi) = m;
  }
  const double a = (lo + hi) / 2;
  return backlash ? backlash_describing_function(a, width)
                  : C(deadband_describing_function(a, width), 0);
}

Cause fit_nonlinearity(const PairFit& p, const std::vector<size_t>& low, const std::vector<C>& base,
                       const std::vector<C>& lin, double* c0) {
  const size_t N = p.w.size();
  Cause best;
  auto low_chi2 = [&](const std::vector<C>& f) {
    double c = 0;
    for (size_t q : low)
      c += std::norm(p.meas[q] - p.sim[q] * base[q] * lin[q] * f[q]) / (p.sig[q] * p.sig[q]);
    return c;
  };
  for (CauseKind kind : {CauseKind::kHysteresis, CauseKind::kDeadband}) {
    auto F = [&](double width) {
      std::vector<C> F(N, 1.0);
      for (size_t q = 0; q < N; ++q)
        F[q] = nl_describing_function(kind, width, p.amp[q] * std::abs(p.meas[q]));
      return F;
    };
    const double a = p.amp[low[0]];
    double width = minimise_1d([&](double x) { return low_chi2(F(x)); }, 1e-4 * a, 1.9 * a, 200);
    double c = low_chi2(F(width));
    if (c < best.chi2) best = Cause{kind, {{"width", width}}, F(width), c, 1, ""};
  }
  *c0 = low_chi2(std::vector<C>(N, 1.0));
  return best;
}

std::string explain_nonlinearity(const PairFit& p, const Cause& nl, const std::vector<size_t>& low,
                                 double mean_h3, double corner_rad_s, double low_fraction) {
  constexpr double kPi = std::numbers::pi;
  std::ostringstream ex;
  const C n0 = nl.F[low[0]];
  ex << "odd harmonics in the position (3rd at " << fmt(100 * mean_h3, 2)
     << " % of the fundamental); below " << fmt(low_fraction * corner_rad_s / (2 * kPi), 2)
     << " Hz the actuator lags " << fmt(-std::arg(n0) * 180 / kPi, 3) << " deg with gain "
     << fmt(std::abs(n0), 3) << " at +-" << fmt(p.amp[low[0]], 3) << " (describing function of a "
     << to_string(nl.cause) << " of width " << fmt(nl.params.at("width"), 3) << ")";
  return ex.str();
}

}  // namespace fralab::diag
