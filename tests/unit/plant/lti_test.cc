#include "fralab/plant/lti.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "test_util.h"

using namespace fralab;
using fralab::testing::sine_phasor;

namespace {

Tf p3_wf_95() {  // Table 9, 95 %, Pade replaced by the delay (docs/formats.md §1 example)
  Tf t;
  t.gain = 0.0308;
  t.zeros = {Root::Real(-10.8), Root::Pair(50.1, 0.013)};
  t.poles = {Root::Real(-2.83), Root::Pair(49.6, 0.021)};
  return t;
}

std::vector<double> run(FohLti& s, const std::vector<double>& u) {
  std::vector<double> y;
  for (double v : u) y.push_back(s.step(v));
  return y;
}

}  // namespace

// The FOH-exactness claim: for a ramp input the samples equal the analytic continuous response.
TEST(FohLti, RampResponseOfFirstOrderLagIsExactAtTheSamples) {
  const double tau = 0.37, h = 1e-3;
  Tf t;
  t.poles = {Root::Real(-1.0 / tau)};
  FohLti s(t, h);
  for (int k = 0; k <= 3000; ++k) {
    double y = s.step(k * h);
    double tt = k * h;
    ASSERT_NEAR(y, tt - tau * (1 - std::exp(-tt / tau)), 1e-12) << k;
  }
}

TEST(FohLti, ModalAndCascadeFormsAgree) {
  Tf t = p3_wf_95();
  FohLti a(t, 1e-3, FohLti::Form::kModal), b(t, 1e-3, FohLti::Form::kCascade);
  std::mt19937 g(3);
  std::normal_distribution<double> n;
  for (int k = 0; k < 5000; ++k) {
    double u = n(g);
    ASSERT_NEAR(a.step(u), b.step(u), 1e-11) << k;
  }
}

TEST(FohLti, RepeatedPolesUseTheCascadeAndStayExact) {
  Tf t;  // 1/(s/2+1)^2: ramp response t - 2 tau + (t + 2 tau) e^{-t/tau}, tau = 0.5
  t.poles = {Root::Real(-2.0), Root::Real(-2.0)};
  FohLti s(t, 1e-3);
  EXPECT_EQ(s.form(), FohLti::Form::kCascade);
  const double tau = 0.5;
  for (int k = 0; k <= 2000; ++k) {
    double tt = k * 1e-3;
    ASSERT_NEAR(s.step(tt), tt - 2 * tau + (tt + 2 * tau) * std::exp(-tt / tau), 1e-11);
  }
}

TEST(FohLti, SinusoidalSteadyStateIsTheExactFohImageSum) {
  const double h = 1e-3;
  Tf t = p3_wf_95();
  for (double f : {0.5, 8.0, 40.0}) {
    const double w = 2 * std::numbers::pi * f;
    FohLti s(t, h);
    std::vector<double> u;
    const size_t settle = 20000, n = size_t(std::round(20 / f / h));  // 20 whole cycles
    for (size_t k = 0; k < settle + n; ++k) u.push_back(std::sin(w * k * h));
    auto y = run(s, u);
    Complex g = sine_phasor(y, w, h, settle, n) / sine_phasor(u, w, h, settle, n);
    // The exact sampled response: the FOH images sum_m G(j(w + m ws)) sinc^2((w + m ws) h / 2).
    const double ws = 2 * std::numbers::pi / h;
    Complex expect = 0.0;
    for (int m = -20000; m <= 20000; ++m) {  // tail beyond: < 1e-7 relative
      double v = w + m * ws, x = v * h / 2;
      expect += t.at(v) * std::pow(std::sin(x) / x, 2);
    }
    EXPECT_NEAR(std::abs(g) / std::abs(expect), 1.0, 1e-6) << f;
    EXPECT_NEAR(std::arg(g / expect), 0.0, 1e-6) << f;
  }
}

TEST(FohLti, IntegerDelayShiftsByExactlyDSamples) {
  Tf t;
  t.delay_s = 7e-3;  // 7 samples at 1 kHz
  FohLti s(t, 1e-3);
  std::mt19937 g(1);
  std::uniform_real_distribution<double> d(-1, 1);
  std::vector<double> u(200);
  for (auto& v : u) v = d(g);
  auto y = run(s, u);
  for (size_t k = 0; k < u.size(); ++k) EXPECT_EQ(y[k], k >= 7 ? u[k - 7] : 0.0) << k;
}

TEST(FohLti, FractionalDelayIsExactOnTheInterpolatedInput) {
  // delay 2.3 samples: y[k] = 0.7 u[k-2] + 0.3 u[k-3] (the FOH signal delayed exactly).
  Tf t;
  t.delay_s = 2.3e-3;
  FohLti s(t, 1e-3);
  std::vector<double> u(100);
  for (size_t k = 0; k < u.size(); ++k) u[k] = std::sin(0.37 * k) + 0.1 * k;
  auto y = run(s, u);
  for (size_t k = 3; k < u.size(); ++k)
    EXPECT_NEAR(y[k], 0.7 * u[k - 2] + 0.3 * u[k - 3], 1e-12) << k;
  // And through dynamics: the ratio of a delayed and an undelayed lag at a sinusoid is e^{-jwd}.
  Tf lag;
  lag.poles = {Root::Real(-30.0)};
  Tf lagd = lag;
  lagd.delay_s = 0.0113;
  FohLti a(lag, 1e-3), b(lagd, 1e-3);
  const double w = 2 * std::numbers::pi * 17.0;
  std::vector<double> ya, yb, uu;
  for (int k = 0; k < 6000; ++k) {
    double v = std::sin(w * k * 1e-3);
    uu.push_back(v);
    ya.push_back(a.step(v));
    yb.push_back(b.step(v));
  }
  size_t n = size_t(std::round(50 / 17.0 / 1e-3));
  Complex r = sine_phasor(yb, w, 1e-3, 3000, n) / sine_phasor(ya, w, 1e-3, 3000, n);
  // Exact up to the FOH images (see lti.h): F(ws - w) |G(ws)/G(w)| ~ 3e-4 * 0.017 here.
  EXPECT_NEAR(std::abs(r), 1.0, 3e-5);
  EXPECT_NEAR(std::arg(r), -w * 0.0113, 3e-5);
}

TEST(FohLti, ImproperTfIsRefusedWithAReason) {
  Tf t;
  t.zeros = {Root::Real(-1.0)};
  try {
    FohLti s(t, 1e-3);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("improper"));
  }
}
