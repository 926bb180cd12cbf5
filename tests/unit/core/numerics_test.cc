// core/numerics.h: the hot loops' complex quotient and the 1-D minimum search.
#include "fralab/core/numerics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using namespace fralab;
using C = std::complex<double>;

namespace {
// |x - y| / |y| in units of the double epsilon.
double ulps(C x, C y) {
  return std::abs(x - y) / std::abs(y) / std::numeric_limits<double>::epsilon();
}
}  // namespace

// Within a few ulps of the library's a / b over 40 decades of |a| and |b| (both the fast path and
// the scaled fallback), every quadrant.
TEST(Quotient, AgreesWithTheLibraryDivisionToAFewUlps) {
  std::mt19937_64 g(7);
  std::uniform_real_distribution<double> e(-150, 150), ph(-M_PI, M_PI);
  double worst = 0;
  for (int i = 0; i < 20000; ++i) {
    const C a = std::polar(std::pow(10.0, e(g)), ph(g)),
            b = std::polar(std::pow(10.0, e(g)), ph(g));
    worst = std::max(worst, ulps(detail::quotient(a, b), a / b));
  }
  EXPECT_LT(worst, 4.0);
}

// Where |b|^2 or |a|^2 leaves the double range (|b| = 1e200, 1e-200; |a| = 1e250) the naive form
// overflows or underflows to inf, 0 or NaN; the quotient must still be the library's.
TEST(Quotient, OutsideTheSafeRangeFallsBackToTheScaledDivision) {
  const C cases[][2] = {{{1e200, 3e199}, {2e200, -1e200}},
                        {{1e-200, 2e-200}, {3e-200, 1e-200}},
                        {{1e250, -1e250}, {1e100, 1e100}},
                        {{1.0, 2.0}, {1e-160, 1e-160}}};
  for (const auto& c : cases) {
    const C q = detail::quotient(c[0], c[1]), ref = c[0] / c[1];
    ASSERT_TRUE(std::isfinite(q.real()) && std::isfinite(q.imag())) << c[0] << " / " << c[1];
    EXPECT_LT(ulps(q, ref), 4.0) << c[0] << " / " << c[1];
  }
}

// A division by zero is not finite (the fast path's 1 / |b|^2 would be inf times 0 components):
// the callers' finiteness checks must see it.
TEST(Quotient, ByZeroIsNotFinite) {
  volatile double zero = 0.0;  // not folded at compile time
  const C q = detail::quotient(C(1.0, 1.0), C(zero, zero));
  EXPECT_FALSE(std::isfinite(std::abs(q)));
}

// Known minima: a parabola's vertex, cos on [2, 4] (pi), |x - 0.3|^1.5 (no parabola fits its
// tip), each to the precision asked for (2^(1 - bits) of |x|).
TEST(BrentMinimum, FindsKnownMinimaToThePrecisionAskedFor) {
  int evaluations = 0;
  const double v = detail::brent_minimum(
      [&](double x) {
        ++evaluations;
        return (x - 1.234) * (x - 1.234) + 5;
      },
      0.0, 3.0, 40);
  EXPECT_NEAR(v, 1.234, 1e-8);
  EXPECT_LT(evaluations, 20);  // a parabola: Brent's interpolation lands at once
  EXPECT_NEAR(detail::brent_minimum([](double x) { return std::cos(x); }, 2.0, 4.0, 30), M_PI,
              1e-7);
  EXPECT_NEAR(detail::brent_minimum([](double x) { return std::pow(std::abs(x - 0.3), 1.5); }, -1.0,
                                    1.0, 30),
              0.3, 1e-6);
  // A coarse request stops early: 17 bits is 2^-16 of |x|.
  EXPECT_NEAR(detail::brent_minimum([](double x) { return std::cos(x); }, 2.0, 4.0, 17), M_PI,
              M_PI * std::ldexp(1.0, -12));
}
