#include "fralab/identify/vector_fitting.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "fralab/core/error.h"

namespace fralab {

using C = std::complex<double>;

void VectorFitOptions::validate() const {
  if (max_iterations < 1) throw InputError("vector fitting: max_iterations must be >= 1");
  if (!(tolerance > 0)) throw InputError("vector fitting: tolerance must be > 0");
}

VectorFitResult vector_fit_poles(const std::vector<double>& w, const std::vector<C>& g,
                                 const std::vector<double>& W, int n, const VectorFitOptions& o) {
  o.validate();
  VectorFitResult r;
  const int M = int(w.size());
  if (n < 1 || M < n + 1 || g.size() != w.size() || W.size() != w.size()) return r;
  const auto [lo, hi] = std::minmax_element(w.begin(), w.end());
  const double ws = std::sqrt(*lo * *hi);
  // Start poles (scaled frequency).
  std::vector<C> poles;
  const int pairs = n / 2;
  for (int k = 0; k < pairs; ++k) {
    const double f = pairs == 1 ? 0.5 : double(k) / (pairs - 1);
    const double b = std::exp(std::log(*lo / ws) + f * (std::log(*hi / ws) - std::log(*lo / ws)));
    poles.push_back(C(-b / 100, b));
  }
  if (n % 2) poles.push_back(C(-1.0, 0.0));
  std::vector<C> s(M);
  std::vector<double> sw(M);
  double gscale = 0;
  for (int i = 0; i < M; ++i) {
    s[i] = C(0, w[i] / ws);
    sw[i] = std::sqrt(std::max(W[i], 0.0));
    gscale += std::norm(sw[i] * g[i]);
  }
  gscale = std::sqrt(gscale / M);
  if (!(gscale > 0) || !std::isfinite(gscale)) return r;
  for (int it = 1; it <= o.max_iterations; ++it) {
    // Real basis: per real pole one column, per pair (listed once, imag > 0) two.
    const int K = int(poles.size()) +
                  int(std::count_if(poles.begin(), poles.end(), [](C p) { return p.imag() > 0; }));
    Eigen::MatrixXcd Phi(M, K);
    for (int i = 0; i < M; ++i) {
      int k = 0;
      for (const C p : poles) {
        if (p.imag() == 0) {
          Phi(i, k++) = 1.0 / (s[i] - p.real());
        } else {
          const C u = 1.0 / (s[i] - p), v = 1.0 / (s[i] - std::conj(p));
          Phi(i, k++) = u + v;
          Phi(i, k++) = C(0, 1) * (u - v);
        }
      }
    }
    // Unknowns: c (K), d, ct (K), dt. Rows: Re and Im of each point, then the relaxation row.
    const int U = 2 * K + 2;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * M + 1, U);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(2 * M + 1);
    for (int i = 0; i < M; ++i) {
      for (int k = 0; k < K; ++k) {
        const C a = sw[i] * Phi(i, k), b = -sw[i] * g[i] * Phi(i, k);
        A(i, k) = a.real(), A(M + i, k) = a.imag();
        A(i, K + 1 + k) = b.real(), A(M + i, K + 1 + k) = b.imag();
      }
      A(i, K) = sw[i];
      const C b = -sw[i] * g[i];
      A(i, 2 * K + 1) = b.real(), A(M + i, 2 * K + 1) = b.imag();
    }
    // Relaxation: Re sum_i sigma(s_i) = M, weighted like the data rows.
    for (int k = 0; k < K; ++k) {
      double sum = 0;
      for (int i = 0; i < M; ++i) sum += Phi(i, k).real();
      A(2 * M, K + 1 + k) = gscale * sum / M;
    }
    A(2 * M, 2 * K + 1) = gscale;
    rhs(2 * M) = gscale;
    // Column scaling for the conditioning.
    Eigen::VectorXd cn = A.colwise().norm();
    for (int k = 0; k < U; ++k) cn(k) = cn(k) > 0 ? cn(k) : 1.0;
    const Eigen::MatrixXd As = A * cn.cwiseInverse().asDiagonal();
    const Eigen::VectorXd x = As.colPivHouseholderQr().solve(rhs).cwiseQuotient(cn);
    if (!x.allFinite()) return r;
    double dt = x(2 * K + 1);
    if (std::abs(dt) < 1e-8) dt = dt < 0 ? -1e-8 : 1e-8;
    // New poles: eig(A - b ct^T / dt).
    Eigen::MatrixXd Ass = Eigen::MatrixXd::Zero(K, K);
    Eigen::VectorXd bv = Eigen::VectorXd::Zero(K);
    int k = 0;
    for (const C p : poles) {
      if (p.imag() == 0) {
        Ass(k, k) = p.real();
        bv(k) = 1;
        ++k;
      } else {
        Ass(k, k) = p.real(), Ass(k, k + 1) = p.imag();
        Ass(k + 1, k) = -p.imag(), Ass(k + 1, k + 1) = p.real();
        bv(k) = 2;
        k += 2;
      }
    }
    const Eigen::MatrixXd Z = Ass - bv * x.segment(K + 1, K).transpose() / dt;
    Eigen::EigenSolver<Eigen::MatrixXd> es(Z, false);
    if (es.info() != Eigen::Success) return r;
    std::vector<C> next;
    for (int j = 0; j < K; ++j) {
      C p = es.eigenvalues()(j);
      if (p.imag() < 0) continue;  // the pair is listed by its upper member
      if (std::abs(p.imag()) <= 1e-10 * std::abs(p)) p = C(p.real(), 0);
      if (p.real() > 0) p = C(-p.real(), p.imag());
      if (p.real() == 0) p = C(-1e-6 * std::max(std::abs(p), 1e-6), p.imag());
      next.push_back(p);
    }
    // Real eigenvalues come singly; a complex one's conjugate was skipped.
    double moved = 0;
    const bool same_shape = next.size() == poles.size();
    if (same_shape) {
      std::vector<C> a = next, b = poles;
      auto key = [](C p) { return std::abs(p); };
      std::sort(a.begin(), a.end(), [&](C x1, C x2) { return key(x1) < key(x2); });
      std::sort(b.begin(), b.end(), [&](C x1, C x2) { return key(x1) < key(x2); });
      for (size_t j = 0; j < a.size(); ++j)
        moved = std::max(moved, std::abs(a[j] - b[j]) / std::max(std::abs(b[j]), 1e-12));
    }
    poles = next;
    r.iterations = it;
    if (same_shape && moved < o.tolerance) break;
  }
  for (const C p : poles) {
    r.poles.push_back(p * ws);
    if (p.imag() > 0) r.poles.push_back(std::conj(p) * ws);
  }
  r.ok = int(r.poles.size()) == n;
  return r;
}

}  // namespace fralab
