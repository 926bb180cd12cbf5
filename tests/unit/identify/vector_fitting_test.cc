#include "fralab/identify/vector_fitting.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <random>

#include "fralab/core/error.h"
#include "fralab/core/tf.h"

using namespace fralab;
using C = std::complex<double>;

namespace {

struct Data {
  std::vector<double> w, W;
  std::vector<C> g;
};

// tf sampled at M log-spaced frequencies over [lo, hi] rad/s, relative complex noise `noise`,
// weights 1 / |G|^2.
Data sample(const Tf& tf, double lo, double hi, int M, double noise = 0, unsigned seed = 1) {
  Data d;
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (int i = 0; i < M; ++i) {
    const double w = lo * std::pow(hi / lo, double(i) / (M - 1));
    const C g = tf.at(w);
    d.w.push_back(w);
    d.g.push_back(g * (1.0 + noise / std::sqrt(2.0) * C(n01(rng), n01(rng))));
    d.W.push_back(1.0 / std::norm(g));
  }
  return d;
}

// The true poles (both members of a pair) of tf, in rad/s.
std::vector<C> true_poles(const Tf& tf) {
  std::vector<C> v;
  for (const Root& r : tf.poles)
    for (const C p : r.locations()) v.push_back(p);
  return v;
}

// Largest relative distance from a true pole to the nearest fitted one.
double worst_pole_error(const std::vector<C>& truth, const std::vector<C>& fit) {
  double worst = 0;
  for (const C t : truth) {
    double best = INFINITY;
    for (const C f : fit) best = std::min(best, std::abs(f - t) / std::abs(t));
    worst = std::max(worst, best);
  }
  return worst;
}

Tf six_poles() {
  Tf t;
  t.gain = 3.0;
  t.poles = {Root::Real(-0.8), Root::Pair(7.0, 0.08), Root::Real(-45.0), Root::Pair(260.0, 0.4),
             Root::Pair(30.0, 0.6)};
  t.zeros = {Root::Real(-4.0), Root::Pair(120.0, 0.3)};
  return t;
}

}  // namespace

TEST(VectorFitting, NoiseFreeDataGiveThePolesExactly) {
  const Tf tf = six_poles();  // 7 poles over 2.5 decades, one light resonance, 3 zeros
  const Data d = sample(tf, 0.1, 1000.0, 60);
  const VectorFitResult r = vector_fit_poles(d.w, d.g, d.W, tf.den_order());
  ASSERT_TRUE(r.ok);
  ASSERT_EQ(int(r.poles.size()), tf.den_order());
  EXPECT_LT(worst_pole_error(true_poles(tf), r.poles), 1e-8);
  for (const C p : r.poles) EXPECT_LT(p.real(), 0.0);
}

TEST(VectorFitting, AnUnstablePoleIsReflected) {
  Tf tf;
  tf.gain = 1.0;
  tf.poles = {Root::Real(-2.0), Root::Pair(20.0, 0.2)};
  Data d = sample(tf, 0.1, 300.0, 40);
  // 1/(s - 2): the same magnitude as 1/(s + 2), the phase mirrored; VF's zeros of sigma land on
  // +2 and are reflected, so every returned pole is stable.
  for (size_t i = 0; i < d.w.size(); ++i) d.g[i] *= (C(0, d.w[i]) + 2.0) / (C(0, d.w[i]) - 2.0);
  const VectorFitResult r = vector_fit_poles(d.w, d.g, d.W, 3);
  ASSERT_TRUE(r.ok);
  for (const C p : r.poles) EXPECT_LT(p.real(), 0.0);
  EXPECT_LT(worst_pole_error({C(-2.0, 0.0)}, r.poles), 1e-6);
}

// At 1 % noise, over 40 noise draws (not one chosen draw: a single seed met 2 % where others gave
// 3-7 %): the worst pole of each fit, nearly always the 260 rad/s pair (zeta 0.4) next to a zero
// pair at 120, lies within 2 % in the median draw and within 5 % in 90 % of them. Measured: median
// 1.3 %, p90 3.5 %, worst 6.7 %.
TEST(VectorFitting, OnePercentNoiseKeepsThePolesWithinTwoPercentInTheMedianDraw) {
  constexpr int kDraws = 40;
  constexpr double kMedianTol = 0.02, kP90Tol = 0.05;
  const Tf tf = six_poles();
  std::vector<double> worst;
  for (unsigned seed = 1; seed <= kDraws; ++seed) {
    const Data d = sample(tf, 0.1, 1000.0, 60, 0.01, seed);
    const VectorFitResult r = vector_fit_poles(d.w, d.g, d.W, tf.den_order());
    ASSERT_TRUE(r.ok) << "draw " << seed;
    worst.push_back(worst_pole_error(true_poles(tf), r.poles));
  }
  std::sort(worst.begin(), worst.end());
  EXPECT_LT(worst[kDraws / 2], kMedianTol);
  EXPECT_LT(worst[kDraws * 9 / 10 - 1], kP90Tol);
}

TEST(VectorFitting, TooFewPointsOrBadOptionsSaySo) {
  const Data d = sample(six_poles(), 0.1, 1000.0, 5);
  EXPECT_FALSE(vector_fit_poles(d.w, d.g, d.W, 7).ok);  // 5 points for 7 poles
  EXPECT_FALSE(vector_fit_poles(d.w, d.g, d.W, 0).ok);
  VectorFitOptions o;
  o.max_iterations = 0;
  EXPECT_THROW(vector_fit_poles(d.w, d.g, d.W, 2, o), InputError);
  o = {};
  o.tolerance = -1;
  EXPECT_THROW(o.validate(), InputError);
}
