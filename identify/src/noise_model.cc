#include "fralab/identify/noise_model.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>

#include "fralab/core/error.h"
#include "fralab/core/numerics.h"

namespace fralab {

double NoiseModel::sigma(double mag) const { return std::hypot(rel * mag, abs); }

void NoiseFitOptions::validate() const {
  if (!(evidence >= 0) || !std::isfinite(evidence))
    throw InputError("noise model: evidence must be a finite number >= 0, not " +
                     std::to_string(evidence));
}

namespace {

// The fraction of a point's degrees of freedom a fit must leave it for its residual to count.
constexpr double kMinDof = 0.2;

// The usable points' squared residuals r and variance factors (ur relative to mref, the
// geometric mean of the squared magnitudes; ua absolute).
struct UsablePoints {
  std::vector<double> r, ur, ua;
  double mref = 0;  // 0: no magnitude to scale by
};

// The usable points: finite, with at least kMinDof of their degrees of freedom left by the fit.
// The variance factors are a linearisation at a least-squares optimum; an over-fit by SK is near
// one, not at it, and where it absorbed a point almost whole (dof ~ 0) the residual it left is
// its distance from that optimum, not noise: an over-fit of 29 parameters to the 34 points of
// the J85 lab's A8:P3 (sigma stripped) left 0.2-8 % of the variance to its 10 points above
// 100 rad/s, and their residuals, 10-80x what that predicts, set b 50x too high.
UsablePoints usable_points(const std::vector<double>& e2, const std::vector<double>& mag2,
                           const ResidualVariance& rv) {
  UsablePoints u;
  double lm = 0;
  int nm = 0;
  for (const double m : mag2)
    if (m > 0 && std::isfinite(m)) lm += std::log(m), ++nm;
  if (nm == 0) return u;
  u.mref = std::exp(lm / nm);
  for (size_t i = 0; i < e2.size(); ++i) {
    if (!(std::isfinite(e2[i]) && mag2[i] > 0 && std::isfinite(mag2[i]) && rv.rel[i] >= 0 &&
          rv.abs[i] >= 0 && std::isfinite(rv.rel[i]) && std::isfinite(rv.abs[i])))
      continue;
    if (!(rv.dof[i] >= kMinDof) || (rv.rel[i] < 1e-9 * mag2[i] && rv.abs[i] < 1e-9)) continue;
    u.r.push_back(e2[i]);
    u.ur.push_back(rv.rel[i] / u.mref);
    u.ua.push_back(rv.abs[i]);
  }
  return u;
}

// The shape (c, s) with the least profile(c, s) over the mixed ones, starting from the relative
// (1, 0) at l_best: tan(phi) = 10^x two decades beyond the range of ur_i / ua_i (either part
// is then negligible at every point), and the ends (phi = 0, pi/2) themselves. l_best becomes
// the least.
std::pair<double, double> best_shape(const UsablePoints& u,
                                     const std::function<double(double, double)>& profile,
                                     double& l_best) {
  double qmin = INFINITY, qmax = 0;
  for (size_t i = 0; i < u.r.size(); ++i) {
    if (!(u.ur[i] > 0 && u.ua[i] > 0)) continue;
    qmin = std::min(qmin, u.ur[i] / u.ua[i]), qmax = std::max(qmax, u.ur[i] / u.ua[i]);
  }
  double c = 1, s = 0;
  if (qmax > 0) {
    const double x_lo = std::log10(qmin) - 2, x_hi = std::log10(qmax) + 2;
    auto at_x = [&](double x) {
      const double t = std::pow(10.0, x);
      return profile(1 / std::hypot(1.0, t), t / std::hypot(1.0, t));
    };
    constexpr double kStep = 0.25;  // decades
    double bx = x_lo, bl = INFINITY;
    for (double x = x_lo; x <= x_hi + 1e-9; x += kStep) {
      const double l = at_x(x);
      if (l < bl) bl = l, bx = x;
    }
    const double x_best = detail::brent_minimum(at_x, bx - kStep, bx + kStep, 30);
    const double t = std::pow(10.0, x_best);
    if (const double l = at_x(x_best); l < l_best)
      l_best = l, c = 1 / std::hypot(1.0, t), s = t / std::hypot(1.0, t);
  }
  if (const double l = profile(0, 1); l < l_best) l_best = l, c = 0, s = 1;
  return {c, s};
}

}  // namespace

NoiseFit fit_noise_model(const std::vector<double>& e2, const std::vector<double>& mag2,
                         const ResidualVariance& rv, const NoiseFitOptions& o) {
  o.validate();
  NoiseFit f;
  if (e2.size() != mag2.size() || e2.size() != rv.rel.size() || e2.size() != rv.abs.size() ||
      e2.size() != rv.dof.size())
    throw InputError("noise model: residuals, magnitudes and variance factors differ in length");
  const UsablePoints u = usable_points(e2, mag2, rv);
  if (u.mref == 0) return f;
  const std::vector<double>&r = u.r, &ur = u.ur, &ua = u.ua;
  const double mref = u.mref;
  const double n = double(r.size());
  if (r.size() < 2) return f;
  // L profiled over the scale, for the shape (c, s): vhat_i = scale (c ur_i + s ua_i).
  auto profile = [&](double c, double s, double* scale) -> double {
    double num = 0, logs = 0;
    for (size_t i = 0; i < r.size(); ++i) {
      const double v = std::max(c * ur[i] + s * ua[i], 1e-300);
      num += r[i] / v;
      logs += std::log(v);
    }
    const double sc = num / n;
    if (scale) *scale = sc;
    if (!(sc > 0)) return -double(INFINITY);  // residuals exactly 0: a perfect fit, any shape
    return n * std::log(sc) + logs + n;
  };
  auto model_of = [&](double c, double s) {
    double sc = 0;
    profile(c, s, &sc);
    return NoiseModel{std::sqrt(sc * c / mref), std::sqrt(sc * s)};
  };
  f.l_relative = profile(1, 0, nullptr);
  f.relative = model_of(1, 0);
  double l_best = f.l_relative;
  const auto [c, s] = best_shape(
      u, [&](double cc, double ss) { return profile(cc, ss, nullptr); }, l_best);
  f.l_mixed = l_best;
  f.mixed = model_of(c, s);
  f.absolute_part = f.l_relative - f.l_mixed >= o.evidence && f.mixed.abs > 0;
  f.model = f.absolute_part ? f.mixed : f.relative;
  f.ok = std::isfinite(f.model.rel) && std::isfinite(f.model.abs);
  return f;
}

namespace {

// The model's tangent space at w_i, rows scaled by sqrt(W_i) (real parts rows 0..N-1, imaginary
// parts N..2N-1): G, and per root G / F (a pair also G (jw / wn) / F).
Eigen::MatrixXd weighted_tangent(const std::vector<double>& w, const std::vector<double>& W,
                                 const Tf& model) {
  using C = std::complex<double>;
  const int N = int(w.size());
  int p = 1;
  for (const Root& z : model.zeros) p += z.order();
  for (const Root& q : model.poles) p += q.order();
  Eigen::MatrixXd A(2 * N, p);
  for (int i = 0; i < N; ++i) {
    const double sw = std::sqrt(W[i]);
    const C G = model.at(w[i]);
    int col = 0;
    auto put = [&](C v) {
      A(i, col) = sw * v.real();
      A(N + i, col) = sw * v.imag();
      ++col;
    };
    put(G);
    for (const auto* roots : {&model.zeros, &model.poles}) {
      for (const Root& r : *roots) {
        const C GF = detail::quotient(G, r.factor_jw(w[i]));
        put(GF);
        if (r.pair) put(GF * C(0.0, w[i] / r.wn));
      }
    }
  }
  return A;
}

// Each column of A to unit norm (a zero column stays).
void normalise_columns(Eigen::MatrixXd& A) {
  for (int j = 0; j < A.cols(); ++j) {
    const double nrm = A.col(j).norm();
    if (nrm > 0 && std::isfinite(nrm)) A.col(j) /= nrm;
  }
}

constexpr double kRankThreshold = 1e-10;

}  // namespace

ResidualVariance residual_variance(const std::vector<double>& w, const std::vector<double>& W,
                                   const std::vector<double>& mag2, const Tf& model) {
  const int N = int(w.size());
  ResidualVariance rv;
  rv.rel = mag2;
  rv.abs.assign(size_t(N), 1.0);
  rv.dof.assign(size_t(N), 1.0);
  Eigen::MatrixXd A = weighted_tangent(w, W, model);
  normalise_columns(A);  // scale-free
  if (!A.allFinite()) return rv;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(kRankThreshold);
  const int rank = int(qr.rank());
  if (rank == 0) return rv;
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(2 * N, rank);
  Eigen::MatrixXd P = -Q * Q.transpose();
  P.diagonal().array() += 1.0;
  // Row l's noise variance per unit a^2 (relative) and b^2 (absolute), times W_l: D_l / 2.
  Eigen::VectorXd dr(2 * N), da(2 * N);
  for (int l = 0; l < 2 * N; ++l) {
    const int i = l % N;
    dr(l) = W[i] * mag2[i] / 2;
    da(l) = W[i] / 2;
  }
  const Eigen::MatrixXd P2 = P.array().square().matrix();
  const Eigen::VectorXd er = P2 * dr, ea = P2 * da;
  for (int i = 0; i < N; ++i) {
    rv.rel[size_t(i)] = (er(i) + er(N + i)) / W[i];
    rv.abs[size_t(i)] = (ea(i) + ea(N + i)) / W[i];
    rv.dof[size_t(i)] = std::clamp((P(i, i) + P(N + i, N + i)) / 2, 0.0, 1.0);
  }
  return rv;
}

Restricted restricted_likelihood(const std::vector<double>& w, const std::vector<double>& e2,
                                 const std::vector<double>& u, const Tf& model) {
  Restricted out;
  const int N = int(w.size());
  if (int(e2.size()) != N || int(u.size()) != N)
    throw InputError("restricted likelihood: frequencies, residuals and shape differ in length");
  std::vector<double> W(w.size());
  for (int i = 0; i < N; ++i) {
    if (!(u[i] > 0 && std::isfinite(u[i]) && std::isfinite(e2[i]))) return out;
    W[size_t(i)] = 2 / u[i];  // the real rows' variances are u_i / 2
  }
  Eigen::MatrixXd A = weighted_tangent(w, W, model);
  const Eigen::VectorXd norms = A.colwise().norm().transpose();
  normalise_columns(A);
  if (!A.allFinite()) return out;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(kRankThreshold);
  const int r = int(qr.rank());
  if (!(2 * N > r)) return out;
  // ln det(A^T U^-1 A) over the rank's pivots: their R diagonal and the norms of their columns.
  double logdet = 0;
  for (int k = 0; k < r; ++k) {
    const double nrm = norms(qr.colsPermutation().indices()(k));
    logdet += 2 * std::log(std::abs(qr.matrixQR()(k, k))) + (nrm > 0 ? 2 * std::log(nrm) : 0.0);
  }
  double q = 0, lu = 0;
  for (int i = 0; i < N; ++i) q += e2[size_t(i)] / u[size_t(i)], lu += std::log(u[size_t(i)]);
  const double s = q / (N - r / 2.0);
  if (!(s > 0)) return out;
  // With V = s U: ln det(A^T V^-1 A) = ln det(A^T U^-1 A) - r ln s.
  out.m2l = 2 * (N * std::log(s) + lu) + 2 * q / s + logdet - r * std::log(s);
  out.scale = s;
  out.rank = r;
  return out;
}

}  // namespace fralab
