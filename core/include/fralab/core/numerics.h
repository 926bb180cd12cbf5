// Numerics shared by the identifier, the state model and the diagnosis: a
// one-dimensional minimisation and the error metric fralab reports for models against data.
#pragma once

#include <cmath>
#include <complex>
#include <functional>
#include <numbers>
#include <vector>

namespace fralab::detail {

/// Golden-section search for the minimum of f on [lo, hi] (f assumed unimodal there); returns the
/// midpoint of the final bracket after `iters` reductions by 0.618.
inline double golden(const std::function<double(double)>& f, double lo, double hi, int iters = 40) {
  const double g = (std::sqrt(5.0) - 1) / 2;
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < iters; ++i) {
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(x2);
    }
  }
  return (lo + hi) / 2;
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
