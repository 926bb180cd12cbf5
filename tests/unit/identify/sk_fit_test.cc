// The Sanathanan-Koerner iteration (sk_fit.h) on data of a known transfer function: exact data give
// the truth's roots and gain, the response fitted is the one given (delay removed), the first
// iteration's weights come from the starting denominator, and the error it reports is that of the
// model it returns.
#include "sk_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <vector>

#include "fit_data.h"
#include "test_util.h"

using namespace fralab;
using namespace fralab::tfns_detail;
using fralab::testing::root_error;
using fralab::testing::worst_error;

namespace {

// Noise-free data of the truth fit to its roots within this (relative location) and its gain
// within this (relative): the iteration is exact there, what remains is rounding.
constexpr double kRootTol = 1e-8;
// sum W |g - N/D|^2 with W = 1/|g|^2 on exact data: every point within 1e-9 relative.
constexpr double kExactSse = 1e-16;

// 2.5 (1 + s/4) / ((1 + s/1.5)(s^2/400 + 0.3 s/20 + 1)): a lag, a lead and a resonance.
Tf truth() {
  Tf t;
  t.gain = 2.5;
  t.zeros = {Root::Real(-4.0)};
  t.poles = {Root::Real(-1.5), Root::Pair(20.0, 0.15)};
  return t;
}

// 41 points log-spaced over 0.1-300 rad/s of `t`, relative weights W = 1/|G|^2 (no sigma), each
// point with complex noise of relative standard deviation `rel_noise` (seeded).
Data data_of(const Tf& t, double rel_noise = 0, uint64_t seed = 1) {
  uint64_t state = seed;
  auto uniform = [&] {  // a 64-bit LCG: the same draws on every machine
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double(state >> 11) + 0.5) * 0x1.0p-53;
  };
  auto normal = [&] {  // Box-Muller
    return std::sqrt(-2 * std::log(uniform())) * std::cos(2 * std::numbers::pi * uniform());
  };
  Data d;
  for (int i = 0; i <= 40; ++i) {
    const double w = 0.1 * std::pow(3000.0, i / 40.0);
    C g = t.at(w);
    g += C(normal(), normal()) * (rel_noise * std::abs(g) / std::sqrt(2.0));
    d.w.push_back(w);
    d.g.push_back(g);
    d.W.push_back(1.0 / std::norm(g));
    d.sigma.push_back(-1);
  }
  return d;
}

// Scaling frequency as the fit uses it: the geometric mean of the band's ends.
double ws_of(const Data& d) { return std::sqrt(d.w.front() * d.w.back()); }

std::vector<C> locations(const std::vector<Root>& roots) {
  std::vector<C> out;
  for (const Root& r : roots)
    for (const C l : r.locations()) out.push_back(l);
  return out;
}

}  // namespace

// Exact data at the truth's orders (3, 1): its poles and zero in order of frequency within 1e-8,
// its gain within 1e-8, an error at rounding level; the first iteration solves it and the second
// sees no change (e_phi within c_phi), so the iteration stops at 2. The scaling frequency is only
// a scaling: 30 times off, the same answer.
TEST(SkFit, ExactDataGiveTheTruthsRootsAndGain) {
  const Tf t = truth();
  const Data d = data_of(t);
  for (const double ws : {ws_of(d), 30 * ws_of(d)}) {
    const Sk sk = sk_fit(d, d.g, 3, 1, ws, FitOptions{});
    ASSERT_TRUE(sk.ok) << ws;
    EXPECT_LT(worst_error(sk.tf.poles, t.poles), kRootTol) << ws;
    EXPECT_LT(worst_error(sk.tf.zeros, t.zeros), kRootTol) << ws;
    EXPECT_NEAR(sk.tf.gain, t.gain, kRootTol * t.gain) << ws;
    EXPECT_EQ(sk.tf.delay_s, 0.0);
    EXPECT_LT(sk.sse, kExactSse) << ws;
    EXPECT_EQ(sk.iterations, 2) << ws;
    EXPECT_LE(sk.e_phi, FitOptions{}.c_phi) << ws;
  }
}

// The response fitted is `g` (the data with the delay taken out), not the data's own values: the
// data carry a 10 ms delay, g is the delay-free truth, and the truth comes out within 1e-8; the
// delayed values themselves are no rational function of order (3, 1), far from the truth.
TEST(SkFit, FitsTheResponseItIsGivenNotTheDelayedData) {
  Tf delayed = truth();
  delayed.delay_s = 0.01;
  const Data d = data_of(delayed);
  const std::vector<C> g = data_of(truth()).g;
  const Sk sk = sk_fit(d, g, 3, 1, ws_of(d), FitOptions{});
  ASSERT_TRUE(sk.ok);
  EXPECT_LT(worst_error(sk.tf.poles, truth().poles), kRootTol);
  EXPECT_LT(worst_error(sk.tf.zeros, truth().zeros), kRootTol);
  EXPECT_LT(sk.sse, kExactSse);
  const Sk on_delayed = sk_fit(d, d.g, 3, 1, ws_of(d), FitOptions{});
  EXPECT_GT(on_delayed.sse, 1e6 * kExactSse);
}

// The first iteration's weights are W / |D0|^2 with D0 the starting poles' polynomial (D0(0) = 1):
// e_phi of one iteration is the change of the denominator from D0, so starting from the truth's
// own poles on exact data it is at rounding level (1e-10), and from D0 = 1 it is of order one.
TEST(SkFit, TheFirstIterationStartsFromTheGivenDenominator) {
  constexpr double kNoChange = 1e-10;
  const Tf t = truth();
  const Data d = data_of(t);
  FitOptions one;
  one.max_iterations = 1;
  const std::vector<C> poles = locations(t.poles);
  const Sk from_truth = sk_fit(d, d.g, 3, 1, ws_of(d), one, &poles);
  ASSERT_TRUE(from_truth.ok);
  EXPECT_EQ(from_truth.iterations, 1);
  EXPECT_LT(from_truth.e_phi, kNoChange);
  EXPECT_LT(worst_error(from_truth.tf.poles, t.poles), kRootTol);
  const Sk from_one = sk_fit(d, d.g, 3, 1, ws_of(d), one);
  ASSERT_TRUE(from_one.ok);
  EXPECT_GT(from_one.e_phi, 0.1);
  // Started from poles elsewhere (a decade off), the exact data still give the truth.
  const std::vector<C> off = {C(-15.0, 0.0), C(-3, 150), C(-3, -150)};
  const Sk from_off = sk_fit(d, d.g, 3, 1, ws_of(d), FitOptions{}, &off);
  ASSERT_TRUE(from_off.ok);
  EXPECT_LT(worst_error(from_off.tf.poles, t.poles), kRootTol);
}

// On noisy data (1 % relative, seeded) the error reported is the returned model's own: the score
// of its roots and gain equals sse to 1e-9 (the polynomials and their roots are the same model);
// roots = false returns the same iterate's sse bit for bit, and no roots. The roots are the
// truth's within 2 % (41 points at 1 % noise).
TEST(SkFit, TheErrorReportedIsThatOfTheModelReturned) {
  constexpr double kSameModel = 1e-9, kNoisyRootTol = 0.02;
  const Tf t = truth();
  const Data d = data_of(t, 0.01, 7);
  const Sk sk = sk_fit(d, d.g, 3, 1, ws_of(d), FitOptions{});
  ASSERT_TRUE(sk.ok);
  EXPECT_GT(sk.sse, 1e-6);  // noise: not an exact fit
  EXPECT_NEAR(score(d, sk.tf).sse, sk.sse, kSameModel * sk.sse);
  EXPECT_LT(worst_error(sk.tf.poles, t.poles), kNoisyRootTol);
  EXPECT_LT(worst_error(sk.tf.zeros, t.zeros), kNoisyRootTol);
  const Sk bare = sk_fit(d, d.g, 3, 1, ws_of(d), FitOptions{}, nullptr, false);
  ASSERT_TRUE(bare.ok);
  EXPECT_EQ(bare.sse, sk.sse);
  EXPECT_EQ(bare.iterations, sk.iterations);
  EXPECT_TRUE(bare.tf.poles.empty());
  EXPECT_TRUE(bare.tf.zeros.empty());
}
