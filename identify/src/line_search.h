// One-dimensional minimisation shared by the identifier and the diagnosis (internal header).
#pragma once

#include <cmath>
#include <functional>

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

}  // namespace fralab::detail
