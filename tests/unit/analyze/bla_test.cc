// The best linear approximation over realisations (analyze/bla.h): the closed form on three
// points, a linear plant's spread that is noise alone, and what is left as it is.
#include "fralab/analyze/bla.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

namespace fralab {
namespace {

using Complex = std::complex<double>;

FrdPoint point(Complex v, double w, double sigma, const std::string& input = "a") {
  FrdPoint p;
  p.w = w;
  p.mag = std::abs(v);
  p.phase_deg = std::arg(v) * 180 / std::numbers::pi;
  p.sigma = sigma;
  p.input = input;
  p.coherence = 0.9;
  p.nl_rel = 0.01;
  return p;
}

// Three realisations 1, 1 + 0.3j, 1 - 0.3j with noise sigma 0.01 each: G_BLA = 1, var_total =
// (0 + 0.09 + 0.09) / (3 * 2) = 0.03, var_noise = 3e-4 / 9, var_nl = their difference.
TEST(Bla, TheClosedFormOnThreeRealisations) {
  const auto out = best_linear_approximation(
      {point({1, 0}, 2, 0.01), point({1, 0.3}, 2, 0.01), point({1, -0.3}, 2, 0.01)});
  ASSERT_EQ(out.size(), 1u);
  const FrdPoint& b = out[0];
  EXPECT_NEAR(b.mag, 1.0, 1e-15);
  EXPECT_NEAR(b.phase_deg, 0.0, 1e-12);
  EXPECT_NEAR(b.sigma, std::sqrt(0.03), 1e-15);
  EXPECT_NEAR(b.sigma_noise, std::sqrt(3e-4 / 9), 1e-15);
  EXPECT_NEAR(b.sigma_nl, std::sqrt(0.03 - 3e-4 / 9), 1e-15);
  EXPECT_EQ(b.realisations, 3);
  EXPECT_NEAR(b.coherence, 0.9, 1e-15);
  EXPECT_NEAR(b.nl_rel, 0.01, 1e-15);
}

// A linear plant: realisations differ by noise only. Over 200 lines of 4 realisations each, the
// spread's variance over the noise's is X = chi2_6 / 6 per line (6 real degrees of freedom), so
// (sigma_noise^2 + sigma_nl^2) / sigma_noise^2 = max(X, 1) averages E max(X, 1) = 1.224 (scipy),
// standard deviation over 200 lines 0.035; the mean covers the truth as a complex Gaussian with
// that sigma should (1 - 1/e of the time within one sigma).
TEST(Bla, ALinearPlantsSpreadIsItsNoise) {
  std::mt19937_64 g(3);
  std::normal_distribution<double> n(0.0, std::sqrt(0.5));
  std::vector<FrdPoint> pts;
  const int lines = 200, R = 4;
  for (int k = 1; k <= lines; ++k) {
    const Complex truth = 2.0 / Complex(1, 0.1 * k);
    const double s = 0.02 * std::abs(truth);
    for (int r = 0; r < R; ++r) pts.push_back(point(truth + s * Complex(n(g), n(g)), k, s));
  }
  const auto out = best_linear_approximation(pts);
  ASSERT_EQ(out.size(), size_t(lines));
  double ratio = 0;
  int within = 0;
  for (const FrdPoint& b : out) {
    const Complex truth = 2.0 / Complex(1, 0.1 * b.w);
    EXPECT_NEAR(b.sigma_noise, 0.02 * std::abs(truth) / 2, 1e-12);  // sigma / sqrt(R)
    ratio += (b.sigma_noise * b.sigma_noise + b.sigma_nl * b.sigma_nl) /
             (b.sigma_noise * b.sigma_noise) / lines;
    within += std::abs(b.value() - truth) < b.sigma_noise;
  }
  EXPECT_NEAR(ratio, 1.224, 0.1);
  EXPECT_NEAR(double(within) / lines, 0.632, 0.08);
}

// Single realisations, invalid points and points without sigma pass through in their order (equal
// w keep the analyser's order); different inputs on the same line are not mixed.
TEST(Bla, WhatIsNotSeveralRealisationsIsLeftAsItIs) {
  FrdPoint bad = point({1, 0}, 1, 0.1);
  bad.valid = false;
  FrdPoint nosigma = point({2, 0}, 1, -1);
  const auto out =
      best_linear_approximation({point({3, 0}, 1, 0.1, "a"), point({5, 0}, 1, 0.1, "b"), bad,
                                 nosigma, point({1, 0}, 3, 0.1, "a"), point({3, 0}, 3, 0.1, "a")});
  ASSERT_EQ(out.size(), 5u);
  int combined = 0;
  for (const FrdPoint& p : out) {
    if (p.realisations == 2) {
      ++combined;
      EXPECT_EQ(p.w, 3);
      EXPECT_NEAR(p.mag, 2.0, 1e-15);
    } else {
      EXPECT_EQ(p.realisations, 0);
      EXPECT_LT(p.sigma_nl, 0);
    }
  }
  EXPECT_EQ(combined, 1);
  EXPECT_EQ(out[0].input, "a");
  EXPECT_EQ(out[1].input, "b");
  EXPECT_FALSE(out[2].valid);
  EXPECT_LT(out[3].sigma, 0);
  for (size_t i = 1; i < out.size(); ++i) EXPECT_LE(out[i - 1].w, out[i].w);
}

}  // namespace
}  // namespace fralab
