// Internal to the identify library: the data every piece of the TFNS fit works on (fit_tf's
// points, weighted), and the score of a model against them. Not installed.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <complex>
#include <utility>
#include <vector>

#include "fralab/core/tf.h"

namespace fralab::tfns_detail {

using C = std::complex<double>;
using MatR = Eigen::MatrixXd;
using VecR = Eigen::VectorXd;
using MatC = Eigen::MatrixXcd;

// The valid points of a fit, sorted by frequency, with their weights W_i (1 / sigma_i^2 with sigma,
// else 1 / |G_i|^2).
struct Data {
  std::vector<double> w;  // rad/s
  std::vector<C> g;       // measured ratio
  std::vector<double> W;  // weights
  std::vector<double> sigma;
  bool has_sigma = false;
  double chi2_slack = 1;  // > 1 when sigma is estimated: the estimate's own uncertainty
  double max_delay = INFINITY;
};

struct Score {
  double sse = 0;    // sum W |e|^2
  double e_n = 0;    // sse / sum W |G|^2
  double chi2 = -1;  // with sigma: sum |e|^2/sigma^2
};

/// The model's error on the data: sse = sum W_i |G_i - t(j w_i)|^2 (delay included), e_n = sse /
/// sum W |G|^2, chi2 = sum |e|^2 / sigma^2 with sigma (else -1).
Score score(const Data& d, const Tf& t);

/// The rms and largest |G_i - t(j w_i)| / |G_i| over the points (the result's figures).
std::pair<double, double> rel_errors(const Data& d, const Tf& t);

}  // namespace fralab::tfns_detail
