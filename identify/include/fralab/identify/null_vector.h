// The smallest right singular vector of a small square upper-triangular matrix: the denominator
// of each SK iteration (tfns.cc) is the one of the triangular factor R of its linearised problem.
//
// x minimises |R x| over |x| = 1. Computed as the eigenvector of R^T R for its smallest
// eigenvalue, then kNullVectorSteps steps of inverse iteration on R itself, x <- R^-1 R^-T x
// (normalised). The eigenvector alone mixes in the direction of a singular value s_j by
// ~eps (s_max / s_j)^2 (R^T R squares the condition); each step multiplies that by
// (s_min / s_j)^2, so the result is as accurate as an SVD of R wherever s_min is separated
// (noise-free data: s_min ~ eps s_max), and within a cluster of singular values near s_min every
// direction has the same |R x| to rounding. Falls back to JacobiSVD when a triangular solve is
// not finite (an exactly singular R). Sign arbitrary.
#pragma once

#include <Eigen/Dense>

namespace fralab {

inline constexpr int kNullVectorSteps = 2;

/// R: square, upper triangular (entries below the diagonal ignored), at least 1 x 1, finite.
Eigen::VectorXd smallest_right_singular_vector(const Eigen::MatrixXd& R);

}  // namespace fralab
