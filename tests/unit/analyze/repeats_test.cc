// analyze/repeats.h: repeated windows of one step combined by inverse-variance weighting.
#include "fralab/analyze/repeats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>

namespace fralab {
namespace {

FrdPoint point(double mag, double phase_deg, double sigma, int n_cycles, int step = 3) {
  FrdPoint p;
  p.w = 2 * M_PI * 1.5;
  p.mag = mag;
  p.phase_deg = phase_deg;
  p.sigma = sigma;
  p.coherence = 0.9;
  p.n_cycles = n_cycles;
  p.step = step;
  p.input = "u";
  return p;
}

Frd curve(std::vector<FrdPoint> pts) { return Frd{"u:y", std::move(pts), ""}; }

TEST(Repeats, TwoWindowsCombineByInverseVariance) {
  // w = 100 and 25: G = (100 * 1 + 25 * 2) / 125 = 1.2, sigma = 1 / sqrt(125).
  const Frd m = merge_repeated(curve({point(1.0, 0, 0.1, 4)}), curve({point(2.0, 0, 0.2, 12)}));
  ASSERT_EQ(m.points.size(), 1u);
  EXPECT_NEAR(m.points[0].mag, 1.2, 1e-12);
  EXPECT_NEAR(m.points[0].phase_deg, 0.0, 1e-12);
  EXPECT_NEAR(m.points[0].sigma, 1 / std::sqrt(125.0), 1e-15);
  EXPECT_EQ(m.points[0].n_cycles, 16);
  EXPECT_NEAR(m.points[0].coherence, 0.9, 1e-15);
}

TEST(Repeats, TheMeanIsOfComplexValuesOnTheFirstWindowsPhaseBranch) {
  // Equal sigma: the plain mean of e^{j 0} and e^{j 90 deg} = (1 + j) / 2, |.| = 1/sqrt 2, 45 deg.
  Frd m = merge_repeated(curve({point(1.0, 0, 0.1, 4)}), curve({point(1.0, 90, 0.1, 4)}));
  ASSERT_EQ(m.points.size(), 1u);
  EXPECT_NEAR(m.points[0].mag, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(m.points[0].phase_deg, 45.0, 1e-12);
  // A curve unwrapped to -350 deg stays there (not +10).
  m = merge_repeated(curve({point(1.0, -350, 0.1, 4)}), curve({point(1.0, 10, 0.1, 4)}));
  EXPECT_NEAR(m.points[0].phase_deg, -350.0, 1e-9);
}

TEST(Repeats, OnlyValidWindowsOfOneStepAtOneFrequencyAreCombined) {
  FrdPoint other_step = point(2.0, 0, 0.1, 4, 4);
  FrdPoint other_w = point(2.0, 0, 0.1, 4);
  other_w.w *= 1.001;
  FrdPoint invalid = point(5.0, 0, 0.1, 4);
  invalid.valid = false;
  FrdPoint no_sigma = point(5.0, 0, -1, 4);
  const Frd m = merge_repeated(curve({point(1.0, 0, 0.1, 4)}),
                               curve({other_step, other_w, invalid, no_sigma}));
  ASSERT_EQ(m.points.size(), 5u);  // nothing combined, everything kept, ascending w
  for (size_t i = 0; i + 1 < m.points.size(); ++i) EXPECT_LE(m.points[i].w, m.points[i + 1].w);
  EXPECT_EQ(m.points[0].mag, 1.0);
  // Three windows of one step, the later two within one curve: one point.
  const Frd three = merge_repeated(
      curve({}), curve({point(1.0, 0, 0.1, 4), point(1.0, 0, 0.1, 4), point(4.0, 0, 0.1, 8)}));
  ASSERT_EQ(three.points.size(), 1u);
  EXPECT_NEAR(three.points[0].mag, 2.0, 1e-12);
  EXPECT_NEAR(three.points[0].sigma, 0.1 / std::sqrt(3.0), 1e-15);
  EXPECT_EQ(three.points[0].n_cycles, 16);
}

TEST(Repeats, CurvesOfDifferentPairsAreRefused) {
  Frd other = curve({});
  other.pair = "u:z";
  EXPECT_THROW(merge_repeated(curve({}), other), InputError);
}

}  // namespace
}  // namespace fralab
