#include "fralab/identify/null_vector.h"

#include <gtest/gtest.h>

#include "test_util.h"

using namespace fralab;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using fralab::testing::graded_triangular_factor;

namespace {

Eigen::JacobiSVD<MatrixXd> svd_of(const MatrixXd& R) {
  return Eigen::JacobiSVD<MatrixXd>(R, Eigen::ComputeFullV);
}

}  // namespace

// Against JacobiSVD on random triangular factors of orders 1-15: the same residual |R x| (the
// smallest singular value) to 1e-10 of it, the same direction to 1e-8, a unit vector.
TEST(NullVector, MatchesTheSvdOnRandomTriangularFactors) {
  constexpr double kResidualTol = 1e-10, kAngleTol = 1e-8;
  for (int k = 1; k <= 15; ++k) {
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const MatrixXd R = graded_triangular_factor(60, k, 100 * k + seed, 4);
      const auto svd = svd_of(R);
      const double smin = svd.singularValues()(k - 1);
      const VectorXd x = smallest_right_singular_vector(R);
      ASSERT_EQ(x.size(), k);
      EXPECT_NEAR(x.norm(), 1.0, 1e-14);
      EXPECT_NEAR((R * x).norm(), smin, kResidualTol * smin) << "k " << k << " seed " << seed;
      EXPECT_NEAR(std::abs(x.dot(svd.matrixV().col(k - 1))), 1.0, kAngleTol)
          << "k " << k << " seed " << seed;
    }
  }
}

// A null direction at s_min ~ 1e-18 s_max (columns over eight decades, the last a combination of
// the others to 1e-10): |R x| within 1e-6 of the SVD's s_min. The eigenvector of R^T R alone
// (no inverse-iteration step) leaves ~2e-16 s_max, hundreds of times s_min.
TEST(NullVector, ReachesTheSvdsResidualOnANearlySingularGradedFactor) {
  constexpr double kRelTol = 1e-6;
  for (int k : {4, 8, 15}) {
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const MatrixXd R = graded_triangular_factor(60, k, seed, 8, true, 1e-10);
      const double smin = svd_of(R).singularValues()(k - 1);
      const VectorXd x = smallest_right_singular_vector(R);
      EXPECT_NEAR((R * x).norm(), smin, kRelTol * smin) << "k " << k << " seed " << seed;
    }
  }
}

// An exactly singular R (a zero on the diagonal, so a triangular solve divides by zero): the
// SVD's answer, a finite null vector.
TEST(NullVector, AnExactlySingularFactorFallsBackToTheSvd) {
  MatrixXd R = graded_triangular_factor(40, 6, 7, 4);
  R(2, 2) = 0;
  R.row(2).setZero();
  const VectorXd x = smallest_right_singular_vector(R);
  ASSERT_TRUE(x.allFinite());
  EXPECT_NEAR(x.norm(), 1.0, 1e-14);
  EXPECT_LE((R * x).norm(), 1e-14 * R.norm());
}

// Equal singular values (R orthogonal times a constant): every unit vector is a minimiser; the
// result is one, with the residual equal to that constant.
TEST(NullVector, InAClusterAnyUnitVectorIsAMinimiser) {
  const MatrixXd R = 3.0 * MatrixXd::Identity(5, 5);
  const VectorXd x = smallest_right_singular_vector(R);
  EXPECT_NEAR(x.norm(), 1.0, 1e-14);
  EXPECT_NEAR((R * x).norm(), 3.0, 1e-14);
}
