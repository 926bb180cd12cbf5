// The noise model of data without sigma (identify/include/fralab/identify/noise_model.h): known
// levels drawn, the same levels estimated; the degrees of freedom a least-squares fit leaves each
// point; the relative model kept when the data show no absolute part.
#include "fralab/identify/noise_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <random>

#include "fralab/core/error.h"
#include "fralab/identify/tfns.h"

namespace fralab {
namespace {

using C = std::complex<double>;

// |G_i| log-spaced over `decades`, complex Gaussian errors of variance a^2 |G|^2 + b^2.
struct Draw {
  std::vector<double> e2, mag2;
  ResidualVariance rv;  // whole points: E|e_i|^2 = a^2 |G_i|^2 + b^2
};
Draw draw(int n, double decades, NoiseModel truth, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::normal_distribution<double> nd(0.0, std::sqrt(0.5));
  Draw d;
  for (int i = 0; i < n; ++i) {
    const double mag = std::pow(10.0, -decades * i / (n - 1));
    const double s = truth.sigma(mag);
    d.e2.push_back(std::norm(C(nd(g), nd(g)) * s));
    d.mag2.push_back(mag * mag);
    d.rv.rel.push_back(mag * mag);
    d.rv.abs.push_back(1.0);
    d.rv.dof.push_back(1.0);
  }
  return d;
}

// Estimates within this fraction of the levels drawn (2000 points: the ML's own spread is ~3 %).
constexpr double kLevelTol = 0.1;

TEST(NoiseModel, BothPartsDrawnAreBothEstimated) {
  const NoiseModel truth{0.01, 2e-4};  // equal where |G| = 0.02, 3 decades of |G|
  const Draw d = draw(2000, 3, truth, 1);
  const NoiseFit f = fit_noise_model(d.e2, d.mag2, d.rv);
  ASSERT_TRUE(f.ok);
  EXPECT_TRUE(f.absolute_part) << f.l_relative << " vs " << f.l_mixed;
  EXPECT_NEAR(f.model.rel, truth.rel, kLevelTol * truth.rel);
  EXPECT_NEAR(f.model.abs, truth.abs, kLevelTol * truth.abs);
}

TEST(NoiseModel, AdditiveNoiseAloneHasNoRelativePart) {
  const NoiseModel truth{0, 1e-3};
  const Draw d = draw(2000, 3, truth, 2);
  const NoiseFit f = fit_noise_model(d.e2, d.mag2, d.rv);
  ASSERT_TRUE(f.absolute_part);
  EXPECT_NEAR(f.model.abs, truth.abs, kLevelTol * truth.abs);
  // Its relative part adds less than a tenth of b's variance even at the largest |G| (1).
  EXPECT_LT(f.model.rel, 0.3 * truth.abs) << f.model.rel;
}

// Relative noise alone: the relative model stands (its level the sse / dof estimate), in all but
// the rare draw the evidence threshold lets through (p ~ 1e-3: none expected of 40).
TEST(NoiseModel, RelativeNoiseKeepsTheRelativeModel) {
  int mixed = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const Draw d = draw(60, 4, NoiseModel{0.02, 0}, seed);
    const NoiseFit f = fit_noise_model(d.e2, d.mag2, d.rv);
    ASSERT_TRUE(f.ok);
    mixed += f.absolute_part;
    double s = 0;
    for (size_t i = 0; i < d.e2.size(); ++i) s += d.e2[i] / d.mag2[i];
    EXPECT_NEAR(f.relative.rel, std::sqrt(s / 60), 1e-12);
    EXPECT_EQ(f.relative.abs, 0);
  }
  EXPECT_EQ(mixed, 0);
}

TEST(NoiseModel, BadInputSaysWhat) {
  const ResidualVariance rv{{1, 1}, {1, 1}, {1, 1}};
  EXPECT_THROW(fit_noise_model({1, 2}, {1}, rv), InputError);
  NoiseFitOptions o;
  o.evidence = NAN;
  EXPECT_THROW(o.validate(), InputError);
  // Nothing usable: not ok, no throw.
  EXPECT_FALSE(fit_noise_model({NAN, 1}, {1, 0}, rv).ok);
}

// What a fit leaves: sum_i dof_i = N - p / 2 for p independent parameters, and with the weights
// 1 / |G|^2 of relative noise the relative factor is |G_i|^2 dof_i; an exactly cancelling pole-zero
// couple adds one direction only (its two columns are one).
TEST(NoiseModel, AFitLeavesThePointsLessHalfItsParameters) {
  std::vector<double> w, W, mag2;
  Tf t;
  t.gain = 2;
  t.zeros = {Root::Real(-30)};
  t.poles = {Root::Real(-2), Root::Pair(15, 0.25)};  // p = 1 + 1 + 3 = 5
  for (int i = 0; i < 40; ++i) {
    w.push_back(0.3 * std::pow(10.0, 3.0 * i / 39));
    mag2.push_back(std::norm(t.at(w.back())));
    W.push_back(1 / mag2.back());
  }
  ResidualVariance rv = residual_variance(w, W, mag2, t);
  double sum = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    sum += rv.dof[i];
    EXPECT_NEAR(rv.rel[i], mag2[i] * rv.dof[i], 1e-12 * mag2[i]);
  }
  EXPECT_NEAR(sum, 40 - 5 / 2.0, 1e-9);
  t.zeros.push_back(Root::Real(-7));
  t.poles.push_back(Root::Real(-7));  // p = 7, rank 6
  rv = residual_variance(w, W, mag2, t);
  sum = 0;
  for (double k : rv.dof) {
    EXPECT_GE(k, 0);
    EXPECT_LE(k, 1);
    sum += k;
  }
  EXPECT_NEAR(sum, 40 - 6 / 2.0, 1e-9);
}

// The residuals of a least-squares fit weighted for the noise (additive noise, weights 1, as
// fit_tf's flat over-fit): counted with the variance the fit leaves each point, the level is
// unbiased over 50 draws; counted as whole points it is low by about 1 - p / 2N = 0.81 (6
// parameters, 16 points). (Weighted relatively instead, the fit of additive noise is far from
// linear: its estimate is 0.35-1.3x the level on such draws, which is why fit_tf judges each
// hypothesis with its own over-fit.)
TEST(NoiseModel, TheVarianceAFitLeavesUnbiasesTheLevel) {
  Tf t;
  t.gain = 1.0;
  t.zeros = {Root::Real(-30.0)};
  t.poles = {Root::Real(-2.0), Root::Pair(15.0, 0.25), Root::Real(-150.0)};
  constexpr double kB = 2e-3;  // 0.2 % of the peak: sigma / |G| 0.2 % at DC, ~70 % at the top
  constexpr int kDraws = 50, kN = 16;
  double mean_fit = 0, mean_whole = 0;
  for (int s = 0; s < kDraws; ++s) {
    std::mt19937_64 g(100 + s);
    std::normal_distribution<double> nd(0.0, std::sqrt(0.5));
    std::vector<FrdPoint> pts;
    std::vector<double> w, W(kN, 1.0), mag2;
    for (int i = 0; i < kN; ++i) {
      FrdPoint p;
      p.w = 0.3 * std::pow(10.0, 3.0 * i / (kN - 1));
      const C v = t.at(p.w) + C(nd(g), nd(g)) * kB;
      p.mag = std::abs(v);
      p.phase_deg = std::arg(v) * 180 / M_PI;
      p.sigma = kB;  // weights 1 / kB^2, uniform
      pts.push_back(p);
      w.push_back(p.w);
      mag2.push_back(std::norm(v));
    }
    FitOptions o;
    o.delay = FitOptions::Delay::kNone;
    const Tf fit = refine_tf(pts, t, o).tf;
    std::vector<double> e2;
    for (const FrdPoint& p : pts) e2.push_back(std::norm(p.value() - fit.at(p.w)));
    const ResidualVariance whole{mag2, std::vector<double>(kN, 1.0), std::vector<double>(kN, 1.0)};
    // The variance the model gives the points, over b^2 (a may take a share of it).
    auto level = [&](const NoiseModel& m) {
      double v = 0;
      for (const double m2 : mag2) v += (m.rel * m.rel * m2 + m.abs * m.abs) / (kB * kB) / kN;
      return v;
    };
    mean_fit += level(fit_noise_model(e2, mag2, residual_variance(w, W, mag2, fit)).mixed);
    mean_whole += level(fit_noise_model(e2, mag2, whole).mixed);
  }
  mean_fit /= kDraws, mean_whole /= kDraws;
  EXPECT_NEAR(mean_fit, 1.0, 0.06);
  EXPECT_LT(mean_whole, 0.92) << mean_fit;
}

// The restricted likelihood, each hypothesis with its own least-squares fit (the true structure
// refined with weights 1 / |g|^2 for relative noise, 1 for absolute): 2 % relative noise and
// additive noise of 0.2 % of the peak, 20 draws each, the true shape preferred by more than
// fit_tf's margin (2 x evidence = 10 in -2 l) in every draw whose two fits have one rank (19 and
// 20), and its scale the level drawn (mean within 10 %).
TEST(NoiseModel, TheRestrictedLikelihoodPrefersTheNoisesOwnShape) {
  Tf t;
  t.gain = 1.0;
  t.zeros = {Root::Real(-30.0)};
  t.poles = {Root::Real(-2.0), Root::Pair(15.0, 0.25), Root::Real(-150.0)};
  constexpr int kDraws = 20, kN = 40;
  const double margin = 2 * NoiseFitOptions{}.evidence;
  for (const bool additive : {false, true}) {
    const double level = additive ? 2e-3 : 0.02;
    int preferred = 0;
    double scale = 0;
    for (int s = 0; s < kDraws; ++s) {
      std::mt19937_64 g(300 + s);
      std::normal_distribution<double> nd(0.0, std::sqrt(0.5));
      std::vector<FrdPoint> rel, flat;
      std::vector<double> w, mag2, ones(kN, 1.0);
      for (int i = 0; i < kN; ++i) {
        FrdPoint p;
        p.w = 0.3 * std::pow(10.0, 3.0 * i / (kN - 1));
        const C g0 = t.at(p.w);
        const C v = g0 + C(nd(g), nd(g)) * (additive ? level : level * std::abs(g0));
        p.mag = std::abs(v);
        p.phase_deg = std::arg(v) * 180 / M_PI;
        rel.push_back(p);
        p.sigma = 1e-3;  // uniform weights (sigma below 0.3 |g| at enough points to be a response)
        flat.push_back(p);
        w.push_back(p.w);
        mag2.push_back(std::norm(v));
      }
      FitOptions o;
      o.delay = FitOptions::Delay::kNone;
      o.estimate_noise = false;
      const Tf fr = refine_tf(rel, t, o).tf, fa = refine_tf(flat, t, o).tf;
      std::vector<double> er, ea;
      for (int i = 0; i < kN; ++i) {
        er.push_back(std::norm(rel[size_t(i)].value() - fr.at(w[size_t(i)])));
        ea.push_back(std::norm(rel[size_t(i)].value() - fa.at(w[size_t(i)])));
      }
      const Restricted hr = restricted_likelihood(w, er, mag2, fr);
      const Restricted ha = restricted_likelihood(w, ea, ones, fa);
      // As fit_tf: compared at equal ranks (a relative fit of draw 15 ran its pole at 150 rad/s
      // off to 2e11, where the data cannot place it: rank 5).
      if (hr.rank == ha.rank)
        preferred += additive ? hr.m2l - ha.m2l > margin : ha.m2l - hr.m2l > margin;
      scale += std::sqrt(additive ? ha.scale : hr.scale) / level / kDraws;
    }
    std::printf("%s noise: its shape preferred in %d of %d draws, level %.3f of the drawn\n",
                additive ? "additive" : "relative", preferred, kDraws, scale);
    EXPECT_GE(preferred, kDraws - 1) << (additive ? "additive" : "relative");
    EXPECT_NEAR(scale, 1.0, 0.1) << (additive ? "additive" : "relative");
  }
  EXPECT_THROW(restricted_likelihood({1, 2}, {1}, {1, 1}, t), InputError);
}

// The restricted likelihood's value, by hand for a model of one parameter (a real gain g0: its
// tangent is the column g0 in the real rows, A^T V^-1 A = sum_i 2 g0^2 / (s u_i)), the scale
// profiled to s = sum e2 / u / (N - 1/2).
TEST(NoiseModel, TheRestrictedLikelihoodOfAGainIsItsFormula) {
  Tf t;
  t.gain = 0.7;
  const std::vector<double> w{1, 2, 3, 4, 5}, e2{0.1, 0.4, 0.2, 0.05, 0.3}, u{1, 2, 0.5, 1, 3};
  double q = 0, lu = 0, a = 0;
  for (size_t i = 0; i < w.size(); ++i)
    q += e2[i] / u[i], lu += std::log(u[i]), a += 2 * 0.49 / u[i];
  const double s = q / (5 - 0.5);
  const double m2l = 2 * (5 * std::log(s) + lu) + 2 * q / s + std::log(a / s);
  const Restricted r = restricted_likelihood(w, e2, u, t);
  EXPECT_EQ(r.rank, 1);
  EXPECT_NEAR(r.scale, s, 1e-14 * s);
  EXPECT_NEAR(r.m2l, m2l, 1e-12 * std::abs(m2l));
}

}  // namespace
}  // namespace fralab
