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

namespace {

// Start poles on the scaled frequency axis: n / 2 light pairs (damping 0.01) spread
// logarithmically over [lo, hi] / ws, and a real pole at -1 for an odd n.
std::vector<C> initial_poles(double lo, double hi, double ws, int n) {
  std::vector<C> poles;
  const int pairs = n / 2;
  for (int k = 0; k < pairs; ++k) {
    const double f = pairs == 1 ? 0.5 : double(k) / (pairs - 1);
    const double b = std::exp(std::log(lo / ws) + f * (std::log(hi / ws) - std::log(lo / ws)));
    poles.push_back(C(-b / 100, b));
  }
  if (n % 2) poles.push_back(C(-1.0, 0.0));
  return poles;
}

// The real partial-fraction basis at the points s: per real pole 1 / (s - p), per pair (listed
// once, imag > 0) u + v and j (u - v) with u = 1 / (s - p), v = 1 / (s - conj p).
Eigen::MatrixXcd real_basis(const std::vector<C>& s, const std::vector<C>& poles) {
  const int K = int(poles.size()) +
                int(std::count_if(poles.begin(), poles.end(), [](C p) { return p.imag() > 0; }));
  Eigen::MatrixXcd Phi(int(s.size()), K);
  for (int i = 0; i < int(s.size()); ++i) {
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
  return Phi;
}

// The relaxed pole-identification least squares (Gustavsen 2006): unknowns c (K), d, ct (K), dt;
// rows Re and Im of sw (Phi c + d - g (Phi ct + dt)) = 0 at each point, then the relaxation row
// Re sum_i sigma(s_i) = M, weighted like the data rows by gscale. Solved with its columns scaled
// to unit norm; non-finite where the solve fails.
Eigen::VectorXd relaxed_solution(const Eigen::MatrixXcd& Phi, const std::vector<C>& g,
                                 const std::vector<double>& sw, double gscale) {
  const int M = int(Phi.rows()), K = int(Phi.cols()), U = 2 * K + 2;
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
  for (int k = 0; k < K; ++k) {
    double sum = 0;
    for (int i = 0; i < M; ++i) sum += Phi(i, k).real();
    A(2 * M, K + 1 + k) = gscale * sum / M;
  }
  A(2 * M, 2 * K + 1) = gscale;
  rhs(2 * M) = gscale;
  Eigen::VectorXd cn = A.colwise().norm();
  for (int k = 0; k < U; ++k) cn(k) = cn(k) > 0 ? cn(k) : 1.0;
  const Eigen::MatrixXd As = A * cn.cwiseInverse().asDiagonal();
  return As.colPivHouseholderQr().solve(rhs).cwiseQuotient(cn);
}

// The zeros of sigma, the next poles: eig(A - b ct^T / dt) in the real basis' state form, flipped
// into the left half plane (a pole on the axis moved just left of it), each pair by its upper
// member. False where the eigen-solver fails.
bool sigma_zeros(const std::vector<C>& poles, const Eigen::VectorXd& x, std::vector<C>* next) {
  const int K = int(x.size() - 2) / 2;
  double dt = x(2 * K + 1);
  if (std::abs(dt) < 1e-8) dt = dt < 0 ? -1e-8 : 1e-8;
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
  if (es.info() != Eigen::Success) return false;
  next->clear();
  for (int j = 0; j < K; ++j) {
    C p = es.eigenvalues()(j);
    if (p.imag() < 0) continue;  // the pair is listed by its upper member
    if (std::abs(p.imag()) <= 1e-10 * std::abs(p)) p = C(p.real(), 0);
    if (p.real() > 0) p = C(-p.real(), p.imag());
    if (p.real() == 0) p = C(-1e-6 * std::max(std::abs(p), 1e-6), p.imag());
    next->push_back(p);
  }
  return true;
}

// The largest relative move between two pole sets of one size, each sorted by modulus.
double largest_move(std::vector<C> a, std::vector<C> b) {
  double moved = 0;
  auto key = [](C p) { return std::abs(p); };
  std::sort(a.begin(), a.end(), [&](C x1, C x2) { return key(x1) < key(x2); });
  std::sort(b.begin(), b.end(), [&](C x1, C x2) { return key(x1) < key(x2); });
  for (size_t j = 0; j < a.size(); ++j)
    moved = std::max(moved, std::abs(a[j] - b[j]) / std::max(std::abs(b[j]), 1e-12));
  return moved;
}

}  // namespace

VectorFitResult vector_fit_poles(const std::vector<double>& w, const std::vector<C>& g,
                                 const std::vector<double>& W, int n, const VectorFitOptions& o) {
  o.validate();
  VectorFitResult r;
  const int M = int(w.size());
  if (n < 1 || M < n + 1 || g.size() != w.size() || W.size() != w.size()) return r;
  const auto [lo, hi] = std::minmax_element(w.begin(), w.end());
  const double ws = std::sqrt(*lo * *hi);
  std::vector<C> poles = initial_poles(*lo, *hi, ws, n);
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
    const Eigen::VectorXd x = relaxed_solution(real_basis(s, poles), g, sw, gscale);
    if (!x.allFinite()) return r;
    std::vector<C> next;
    if (!sigma_zeros(poles, x, &next)) return r;
    // Real eigenvalues come singly; a complex one's conjugate was skipped.
    const bool same_shape = next.size() == poles.size();
    const double moved = same_shape ? largest_move(next, poles) : 0;
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
