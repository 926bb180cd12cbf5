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
  NonlinearitySpec s{NonlinearityKind::kHysteresis, 9.24};
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
  NonlinearitySpec s{NonlinearityKind::kDeadband, 2.0};
  for (double a : {1.5, 3.0, 20.0}) {
    Complex sim = simulated_df(s, a);
    EXPECT_NEAR(sim.real(), deadband_describing_function(a, 2.0), 2e-3) << a;
    EXPECT_NEAR(sim.imag(), 0.0, 2e-3) << a;
  }
}

TEST(Nonlinearity, RateLimitAndSaturationBound) {
  NonlinearitySpec r{NonlinearityKind::kRateLimit, 0, 2.0};
  auto nl = make_nonlinearity(r, 0.0, 0.01);
  EXPECT_DOUBLE_EQ(nl->apply(1.0), 0.02);
  EXPECT_DOUBLE_EQ(nl->apply(1.0), 0.04);
  NonlinearitySpec s{NonlinearityKind::kSaturation, 0, 0, 100.0, 120.0};
  auto sat = make_nonlinearity(s, 115.0, 0.01);  // absolute limits around dc = 115
  EXPECT_DOUBLE_EQ(sat->apply(10.0), 5.0);
  EXPECT_DOUBLE_EQ(sat->apply(-30.0), -15.0);
  NonlinearitySpec bad{NonlinearityKind::kSaturation, 0, 0, 0.0, 1.0};
  EXPECT_THROW(make_nonlinearity(bad, 115.0, 0.01), InputError);
}

// The multisine counterpart (multisine_bla). One line: a sinusoid whose phase is random is a time
// shift, and a rate-independent element's BLA is then its describing function (within the
// discretisation: 1024 samples a cycle here).
TEST(Nonlinearity, AMultisineOfOneLineHasTheDescribingFunctionAsItsBla) {
  const NonlinearitySpec backlash{NonlinearityKind::kHysteresis, 0.5},
      deadband{NonlinearityKind::kDeadband, 0.5};
  const auto b = multisine_bla(backlash, {1}, {1.0}, 4);
  EXPECT_NEAR(std::abs(b.g[0] - backlash_describing_function(1.0, 0.5)), 0.0, 2e-3);
  EXPECT_LT(b.var_nl[0], 1e-6);
  const auto d = multisine_bla(deadband, {3}, {2.0}, 4);
  EXPECT_NEAR(std::abs(d.g[0] - deadband_describing_function(2.0, 0.5)), 0.0, 2e-3);
}

// Many lines: far inside the width nothing moves (BLA 0); far beyond it the element is nearly
// the identity (at s = 50 w); between (s = 0.6 w) the BLA depends on the line: the slow lines,
// carried by the large slow motion, pass nearly whole, the fast small ones are eaten by the play
// and lag (the describing function at any single amplitude has no such frequency dependence);
// the distortion varies from one realisation to the next (var_nl > 0).
TEST(Nonlinearity, AMultisinesBlaSpansNothingToTheIdentity) {
  const NonlinearitySpec backlash{NonlinearityKind::kHysteresis, 1.0};
  std::vector<int> lines;
  for (int k = 1; k <= 200; k = std::max(k + 1, int(k * 1.26))) lines.push_back(k);
  const double n = double(lines.size());
  auto at_rms = [&](double s) {
    return multisine_bla(backlash, lines, std::vector<double>(lines.size(), s * std::sqrt(2 / n)),
                         16);
  };
  const auto inside = at_rms(0.02), beyond = at_rms(50), between = at_rms(0.6);
  for (size_t j = 0; j < lines.size(); ++j) {
    EXPECT_LT(std::abs(inside.g[j]), 1e-12);
    EXPECT_NEAR(std::abs(beyond.g[j] - 1.0), 0.0, 0.05);
    EXPECT_GT(between.var_nl[j], 1e-5);
  }
  EXPECT_GT(std::abs(between.g[0] + between.g[1] + between.g[2]) / 3, 0.8);
  EXPECT_LT(std::abs(between.g.back()), 0.4);
  EXPECT_LT(std::arg(between.g.back()) * 180 / std::numbers::pi, -10);
  EXPECT_THROW(multisine_bla({NonlinearityKind::kRateLimit, 0, 1.0}, {1}, {1.0}), InputError);
  EXPECT_THROW(multisine_bla(backlash, {0}, {1.0}), InputError);
  EXPECT_THROW(multisine_bla(backlash, {1, 2}, {1.0}), InputError);
  EXPECT_THROW(multisine_bla(backlash, {kMaxMultisineLine + 1}, {1.0}), InputError);
  EXPECT_THROW(multisine_bla(backlash, {1}, {std::nan("")}), InputError);
}
