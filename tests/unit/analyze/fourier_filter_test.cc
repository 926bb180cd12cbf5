#include "fralab/analyze/fourier_filter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace fralab;

TEST(FourierFilter, ExtractsTheFundamentalAndRejectsDcAndHarmonics) {
  // 7 whole cycles in 1000 samples; x = 3 sin(phi) - 2 cos(phi) + DC + 2nd and 3rd harmonics.
  const size_t n = 1000;
  const double dphi = 2 * std::numbers::pi * 7 / n, phi0 = 0.3;
  std::vector<double> x(n);
  for (size_t k = 0; k < n; ++k) {
    double p = phi0 + k * dphi;
    x[k] = 15279.0 + 3 * std::sin(p) - 2 * std::cos(p) + 0.7 * std::sin(2 * p + 1) +
           0.4 * std::cos(3 * p);
  }
  Reference r = make_reference(n, phi0, dphi);
  Complex p = fourier_phasor(x.data(), r, 0, n);
  EXPECT_NEAR(p.real(), 3.0, 1e-10);   // A1: the sin(phi) component
  EXPECT_NEAR(p.imag(), -2.0, 1e-10);  // B1: the cos(phi) component
  EXPECT_NEAR(std::abs(fourier_phasor(x.data(), make_reference(n, phi0, dphi, 2), 0, n)), 0.7,
              1e-10);
  EXPECT_NEAR(std::abs(fourier_phasor(x.data(), make_reference(n, phi0, dphi, 3), 0, n)), 0.4,
              1e-10);
}

TEST(FourierFilter, PhaseConventionLagIsNegative) {
  // E2 = sin(phi - 0.5): lags E1 = sin(phi) by 0.5 rad; arg(P2/P1) = -0.5.
  const size_t n = 4000;
  const double dphi = 2 * std::numbers::pi * 10 / n;
  std::vector<double> a(n), b(n);
  for (size_t k = 0; k < n; ++k) {
    a[k] = std::sin(k * dphi);
    b[k] = 2 * std::sin(k * dphi - 0.5);
  }
  Reference r = make_reference(n, 0.0, dphi);
  Complex ratio = fourier_phasor(b.data(), r, 0, n) / fourier_phasor(a.data(), r, 0, n);
  EXPECT_NEAR(std::abs(ratio), 2.0, 1e-12);
  EXPECT_NEAR(std::arg(ratio), -0.5, 1e-12);
}

TEST(FourierFilter, RecurrenceStaysWithin1e12OfDirectSinCos) {
  // A long window: 400 cycles in 2e6 samples (the most cycles a default step integrates).
  const size_t n = 2000000;
  const double dphi = 2 * std::numbers::pi * 400 / double(n), phi0 = 1.1;
  Reference r = make_reference(n, phi0, dphi);
  double worst = 0;
  for (size_t k = 0; k < n; k += 997) {
    const long double a = (long double)phi0 + (long double)k * (long double)dphi;
    worst = std::max(worst, double(std::fabs((long double)r.c[k] - cosl(a))));
    worst = std::max(worst, double(std::fabs((long double)r.s[k] - sinl(a))));
  }
  EXPECT_LT(worst, 1e-12);
}
