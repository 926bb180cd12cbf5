// Numerics shared by the identifier, the state model and the diagnosis: a one-dimensional
// minimisation (Boost.Math's Brent), the hot loops' complex quotient, and the error metric fralab
// reports for models against data.
#pragma once

#include <boost/math/tools/minima.hpp>
#include <cmath>
#include <complex>
#include <cstdint>
#include <functional>
#include <numbers>
#include <vector>

namespace fralab::detail {

/// The minimum of f on [lo, hi] (f assumed unimodal there) by Brent's method: Boost.Math's
/// brent_find_minima, golden-section steps with parabolic interpolation (8-15 evaluations on smooth
/// functions where a plain golden section takes 20-40). Returns the x
/// found, to 2^(1 - bits) relative to |x| (plus a quarter of that absolute, near 0), after at most
/// max_evaluations evaluations of f.
inline double brent_minimum(const std::function<double(double)>& f, double lo, double hi,
                            int bits = 30, std::uintmax_t max_evaluations = 100) {
  return boost::math::tools::brent_find_minima(f, lo, hi, bits, max_evaluations).first;
}

/// a / b for the hot loops: a conj(b) / |b|^2 with one real division where nothing can overflow
/// or underflow (|b|^2 in [1e-300, 1e300], |a|^2 below 1e300), else the library's a / b (scaled,
/// and C99's rules for infinities). Within rounding of a / b (a few ulps), 2-3x faster: a / b of
/// std::complex<double> is a call to libgcc's __divdc3, ~10 % of a fit's time.
inline std::complex<double> quotient(std::complex<double> a, std::complex<double> b) {
  const double nb = std::norm(b);
  if (nb > 1e-300 && nb < 1e300 && std::norm(a) < 1e300) return a * std::conj(b) * (1.0 / nb);
  return a / b;
}

/// rms over i of |ln(model_i / measured_i)| (nepers and radians combined, phase wrapped to
/// (-pi, pi]); points where either value is 0 are skipped; 0 when none remains.
inline double rms_log_error(const std::vector<std::complex<double>>& model,
                            const std::vector<std::complex<double>>& measured) {
  double s = 0;
  int n = 0;
  for (size_t i = 0; i < model.size() && i < measured.size(); ++i) {
    if (std::abs(model[i]) == 0 || std::abs(measured[i]) == 0) continue;
    const std::complex<double> l = std::log(model[i] / measured[i]);
    s += std::norm(std::complex<double>(l.real(), std::remainder(l.imag(), 2 * std::numbers::pi)));
    ++n;
  }
  return n ? std::sqrt(s / n) : 0.0;
}

}  // namespace fralab::detail
