#include "fralab/plant/nonlinearity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "test_util.h"

using namespace fralab;
using fralab::testing::sine_phasor;

namespace {

// First harmonic of the element's steady response to A sin(w t), relative to A.
Complex simulated_df(const NonlinearitySpec& s, double a) {
  auto nl = make_nonlinearity(s, 0.0, 1e-4);
  const int per = 4000;
  std::vector<double> y;
  for (int k = 0; k < 3 * per; ++k)
    y.push_back(nl->apply(a * std::sin(2 * std::numbers::pi * k / per)));
  return sine_phasor(y, 2 * std::numbers::pi, 1.0 / per, per, 2 * per) / a;
}

}  // namespace

TEST(Nonlinearity, BacklashMatchesItsDescribingFunction) {
  NonlinearitySpec s{"hysteresis", 9.24};
  for (double a : {5.0, 10.0, 40.0}) {
    Complex sim = simulated_df(s, a), df = backlash_describing_function(a, 9.24);
    EXPECT_NEAR(std::abs(sim - df), 0.0, 2e-3) << a;
  }
  // The J85 exhaust actuator: -30 degrees at +-5 % of 200 in^2 (Section II).
  EXPECT_NEAR(std::arg(backlash_describing_function(10.0, 9.24)) * 180 / std::numbers::pi, -30.0,
              0.1);
  EXPECT_EQ(backlash_describing_function(4.0, 9.24), Complex(0.0, 0.0));  // never leaves the play
}

TEST(Nonlinearity, DeadbandMatchesItsDescribingFunction) {
  NonlinearitySpec s{"deadband", 2.0};
  for (double a : {1.5, 3.0, 20.0}) {
    Complex sim = simulated_df(s, a);
    EXPECT_NEAR(sim.real(), deadband_describing_function(a, 2.0), 2e-3) << a;
    EXPECT_NEAR(sim.imag(), 0.0, 2e-3) << a;
  }
}

TEST(Nonlinearity, RateLimitAndSaturationBound) {
  NonlinearitySpec r{"rate_limit", 0, 2.0};
  auto nl = make_nonlinearity(r, 0.0, 0.01);
  EXPECT_DOUBLE_EQ(nl->apply(1.0), 0.02);
  EXPECT_DOUBLE_EQ(nl->apply(1.0), 0.04);
  NonlinearitySpec s{"saturation", 0, 0, 100.0, 120.0};
  auto sat = make_nonlinearity(s, 115.0, 0.01);  // absolute limits around dc = 115
  EXPECT_DOUBLE_EQ(sat->apply(10.0), 5.0);
  EXPECT_DOUBLE_EQ(sat->apply(-30.0), -15.0);
  NonlinearitySpec bad{"saturation", 0, 0, 0.0, 1.0};
  EXPECT_THROW(make_nonlinearity(bad, 115.0, 0.01), InputError);
}
