#include "fralab/identify/null_vector.h"

namespace fralab {

Eigen::VectorXd smallest_right_singular_vector(const Eigen::MatrixXd& R) {
  const auto U = R.triangularView<Eigen::Upper>();
  const Eigen::MatrixXd Ru = U;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Ru.transpose() * Ru);
  Eigen::VectorXd x = es.eigenvectors().col(0);  // eigenvalues ascending
  bool finite = es.info() == Eigen::Success;
  for (int s = 0; s < kNullVectorSteps && finite; ++s) {
    U.transpose().solveInPlace(x);
    x /= x.norm();
    U.solveInPlace(x);
    x /= x.norm();
    finite = x.allFinite();
  }
  if (finite) return x;
  Eigen::JacobiSVD<Eigen::MatrixXd, Eigen::NoQRPreconditioner> svd(Ru, Eigen::ComputeFullV);
  return svd.matrixV().col(Ru.cols() - 1);
}

}  // namespace fralab
