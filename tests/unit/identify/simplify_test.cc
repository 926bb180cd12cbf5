// What the identifier refuses in a model (simplify.h): a light pair only where the grid resolves
// it, cancelling dipoles measured against the roots' damping when they are light, and the grid's
// delay ambiguity (delay_search.h).
#include "simplify.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "delay_search.h"

namespace fralab::tfns_detail {
namespace {

std::vector<double> linspace(double lo, double hi, int n) {
  std::vector<double> w;
  for (int i = 0; i < n; ++i) w.push_back(lo + (hi - lo) * i / (n - 1));
  return w;
}

std::vector<double> logspace(double lo, double hi, int per_decade) {
  std::vector<double> w;
  const int k = int(std::round(std::log10(hi / lo) * per_decade));
  for (int i = 0; i <= k; ++i) w.push_back(lo * std::pow(10.0, double(i) / per_decade));
  return w;
}

Tf with_poles(std::vector<Root> poles, std::vector<Root> zeros = {}) {
  Tf t;
  t.poles = std::move(poles);
  t.zeros = std::move(zeros);
  return t;
}

// A pair of zeta 1e-5 at 1 rad/s: its half-power half-width is 1e-5. Two points within twice that
// resolve it; a grid that steps over it does not.
TEST(Simplify, ALightPairStandsOnlyWhereTheGridResolvesIt) {
  const Tf t = with_poles({Root::Pair(1.0, 1e-5)});
  EXPECT_FALSE(nonphysical(t, linspace(1 - 1.5e-4, 1 + 1.5e-4, 201)));  // spacing 1.5e-6
  EXPECT_TRUE(nonphysical(t, linspace(1 - 1.5e-4, 1 + 1.5e-4, 11)));    // spacing 3e-5
  EXPECT_TRUE(nonphysical(t, {1 - 1e-5, 1.1}));  // one point on the peak is not two
  EXPECT_FALSE(nonphysical(t, {1 - 1e-5, 1 + 1e-5}));
  // A stepped sine's log grid (10 points a decade): no pair below 1e-3 is resolved, a light zero
  // pair neither.
  EXPECT_TRUE(nonphysical(with_poles({Root::Pair(1.0, 5e-4)}), logspace(0.01, 100, 10)));
  EXPECT_TRUE(
      nonphysical(with_poles({Root::Real(-1)}, {Root::Pair(1.0, -5e-4)}), logspace(0.01, 100, 10)));
  EXPECT_FALSE(nonphysical(with_poles({Root::Pair(1.0, 2e-3)}), logspace(0.01, 100, 10)));
}

// A notch resonator: the zero pair 3 % as damped as the pole pair at the same frequency, a 30 dB
// dip, is no cancelling couple; a zero within 1 % of the pole's real part is (it changes the
// response by 1 % at most), and remove_dipoles takes it out. Between non-light roots, 1e-3 of the
// modulus as before.
TEST(Simplify, ALightDipoleIsMeasuredAgainstItsDamping) {
  const auto w = linspace(1 - 5e-5, 1 + 5e-5, 1001);  // spacing 1e-7: the zero resolved too
  EXPECT_FALSE(nonphysical(with_poles({Root::Pair(1.0, 1e-5)}, {Root::Pair(1.0, 3e-7)}), w));
  Tf cancel = with_poles({Root::Pair(1.0, 1e-5), Root::Real(-1)}, {Root::Pair(1.0, 1.001e-5)});
  EXPECT_TRUE(nonphysical(cancel, w));
  EXPECT_TRUE(remove_dipoles(cancel));
  EXPECT_EQ(cancel.zeros.size(), 0u);
  ASSERT_EQ(cancel.poles.size(), 1u);
  EXPECT_FALSE(cancel.poles[0].pair);
  const auto grid = logspace(0.01, 100, 10);
  EXPECT_TRUE(nonphysical(with_poles({Root::Real(-2.0)}, {Root::Real(-2.001)}), grid));
  EXPECT_FALSE(nonphysical(with_poles({Root::Real(-2.0)}, {Root::Real(-2.01)}), grid));
  EXPECT_TRUE(nonphysical(with_poles({Root::Pair(3.0, 0.1)}, {Root::Pair(3.001, 0.1)}), grid));
}

// The longest delay a grid tells apart: 2 pi over its median spacing; a uniform grid's exactly.
TEST(Simplify, TheDelayAmbiguityIsTwoPiOverTheMedianSpacing) {
  EXPECT_DOUBLE_EQ(delay_ambiguity(linspace(1, 50, 50)), 2 * std::numbers::pi);
  EXPECT_NEAR(
      delay_ambiguity(linspace(2 * std::numbers::pi * 1.4e11, 2 * std::numbers::pi * 2.2e11, 801)),
      1e-8, 1e-17);  // a VNA's 100 MHz grid: 10 ns
  // One close pair of points does not change it; unsorted points are sorted first.
  EXPECT_DOUBLE_EQ(delay_ambiguity({5, 1, 3, 3.001, 7, 9}), 2 * std::numbers::pi / 2);
  EXPECT_TRUE(std::isinf(delay_ambiguity({4.0})));
}

}  // namespace
}  // namespace fralab::tfns_detail
