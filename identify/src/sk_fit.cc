#include "sk_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "fralab/core/numerics.h"
#include "fralab/identify/null_vector.h"

namespace fralab::tfns_detail {
namespace {

// An orthonormal polynomial basis on the weighted points (Arnoldi); see tfns.h.
struct Basis {
  MatC Qw;  // weighted values, P x (order + 1): columns orthonormal
  MatR H;   // (order + 1) x order, real
  double nu0 = 1;
  int order = 0;
};

// The points are +-j w_i (conjugate pairs) with equal weights, so for real-coefficient polynomials
// the inner product over all 2M points is 2 Re of the sum over the first M: the process runs on the
// first M points only (y: the M frequencies w_i / ws, the points j y_i; sw: their weights). On the
// imaginary axis with real weights the basis alternates: q_k is real for even k and imaginary for
// odd k (j y times a real vector is imaginary and is orthogonal to every real one), so the process
// runs in real arithmetic on r_k (q_k = r_k or j r_k) and only against columns of q_{k+1}'s kind
// (the others' coefficients are exactly 0).
Basis arnoldi(const std::vector<double>& y, const std::vector<double>& sw, int order) {
  const int P = int(y.size());
  Basis b;
  b.order = order;
  MatR r(P, order + 1);
  b.H = MatR::Zero(order + 1, std::max(order, 1));
  double nrm = 0;
  for (double s : sw) nrm += 2 * s * s;
  b.nu0 = std::sqrt(nrm);
  for (int i = 0; i < P; ++i) r(i, 0) = sw[i] / b.nu0;
  VecR v(P);
  for (int k = 0; k < order; ++k) {
    // z q_k: j y r_k (k even, imaginary) or j y j r_k = -y r_k (k odd, real)
    const double sign = k % 2 ? -1.0 : 1.0;
    for (int i = 0; i < P; ++i) v(i) = sign * (y[i] * r(i, k));
    for (int pass = 0; pass < 2; ++pass) {  // re-orthogonalise: classical Gram-Schmidt twice
      for (int j = (k + 1) % 2; j <= k; j += 2) {
        const double h = 2.0 * r.col(j).dot(v);
        b.H(j, k) += h;
        v -= h * r.col(j);
      }
    }
    const double hn = std::sqrt(2.0) * v.norm();
    b.H(k + 1, k) = hn;
    r.col(k + 1) = v / hn;
  }
  b.Qw.resize(P, order + 1);
  for (int k = 0; k <= order; ++k) {
    if (k % 2) {
      b.Qw.col(k).real().setZero();
      b.Qw.col(k).imag() = r.col(k);
    } else {
      b.Qw.col(k).real() = r.col(k);
      b.Qw.col(k).imag().setZero();
    }
  }
  return b;
}

// Value at s of the polynomial with coefficients c (basis of b, length <= order+1).
C poly_at(const Basis& b, const VecR& c, C s) {
  std::vector<C> q(c.size());
  q[0] = 1.0 / b.nu0;
  C v = c(0) * q[0];
  for (int k = 0; k + 1 < int(c.size()); ++k) {
    C t = s * q[k];
    for (int j = 0; j <= k; ++j) t -= b.H(j, k) * q[j];
    q[k + 1] = t / b.H(k + 1, k);
    v += c(k + 1) * q[k + 1];
  }
  return v;
}

// Roots of sum c_k q_k (degree = c.size() - 1) via the confederate matrix.
std::vector<C> poly_roots(const Basis& b, VecR c) {
  int n = int(c.size()) - 1;
  while (n > 0 && std::abs(c(n)) < 1e-13 * c.norm()) --n;  // deflate a vanishing leading term
  if (n <= 0) return {};
  MatR M = MatR::Zero(n, n);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j <= std::min(k + 1, n - 1); ++j) M(k, j) = b.H(j, k);
  }
  for (int j = 0; j < n; ++j) M(n - 1, j) -= b.H(n, n - 1) * c(j) / c(n);
  Eigen::EigenSolver<MatR> es(M, false);
  std::vector<C> r;
  for (int i = 0; i < n; ++i) r.push_back(es.eigenvalues()(i));
  return r;
}

std::vector<Root> to_roots(const std::vector<C>& lam, double scale) {
  std::vector<Root> out;
  std::vector<bool> used(lam.size(), false);
  for (size_t i = 0; i < lam.size(); ++i) {
    if (used[i]) continue;
    C l = lam[i] * scale;
    if (std::abs(l.imag()) <= 1e-7 * std::abs(l)) {
      out.push_back(Root::Real(l.real()));
      used[i] = true;
      continue;
    }
    // its conjugate
    size_t best = i;
    double bd = 1e300;
    for (size_t j = 0; j < lam.size(); ++j) {
      if (j == i || used[j]) continue;
      double d = std::abs(lam[j] * scale - std::conj(l));
      if (d < bd) bd = d, best = j;
    }
    used[i] = true;
    if (best != i) used[best] = true;
    const double wn = std::abs(l);
    out.push_back(Root::Pair(wn, -l.real() / wn));
  }
  std::sort(out.begin(), out.end(), [](const Root& a, const Root& b) {
    return (a.pair ? a.wn : std::abs(a.real)) < (b.pair ? b.wn : std::abs(b.real));
  });
  return out;
}

constexpr int kSkStall = 3;

// One SK iteration's columns in basis b, stacked [Re; Im]: Q1 = sqrt(2) AN, AN the numerator's
// (the Arnoldi vectors -q_k, k = 0..m), and AD the denominator's (g_i q_k, k = 0..n).
void sk_columns(const Basis& b, const std::vector<C>& g, int n, int m, MatR* Q1, MatR* AD) {
  const int M = int(g.size());
  Q1->resize(2 * M, m + 1);
  AD->resize(2 * M, n + 1);
  for (int i = 0; i < M; ++i) {
    for (int k = 0; k <= m; ++k) {
      C q = -std::sqrt(2.0) * b.Qw(i, k);
      (*Q1)(i, k) = q.real();
      (*Q1)(M + i, k) = q.imag();
    }
    for (int k = 0; k <= n; ++k) {
      C q = g[i] * b.Qw(i, k);
      (*AD)(i, k) = q.real();
      (*AD)(M + i, k) = q.imag();
    }
  }
}

}  // namespace

// SK iteration at orders (n, m) on data g (delay already removed), scaled frequency. The first
// iteration's weights are W_i / |D0(s_i)|^2 with D0 = 1, or with D0 the polynomial of `den_start`
// (poles in rad/s, D0(0) = 1: vector fitting's poles).
Sk sk_fit(const Data& d, const std::vector<C>& g, int n, int m, double ws, const FitOptions& o,
          const std::vector<C>* den_start, bool roots) {
  const int M = int(d.w.size());
  std::vector<double> y(M);
  for (int i = 0; i < M; ++i) y[i] = d.w[i] / ws;
  std::vector<double> phi(d.W);
  std::vector<C> dprev(M, 1.0);
  if (den_start) {
    for (int i = 0; i < M; ++i) {
      for (const C p : *den_start) dprev[i] *= (C(0, d.w[i]) - p) / (-p);
      phi[i] = d.W[i] / std::norm(dprev[i]);
    }
  }
  Sk r;
  double best_sse = 1e300;
  int it_best = 0;
  Basis best_basis;
  VecR best_num, best_den;
  const int order = std::max(n, m);
  for (int it = 1; it <= o.max_iterations; ++it) {
    std::vector<double> sw(M);
    for (int i = 0; i < M; ++i) sw[i] = std::sqrt(phi[i]);
    Basis b = arnoldi(y, sw, order);
    MatR Q1, AD;
    sk_columns(b, g, n, m, &Q1, &AD);
    // AN's columns are the Arnoldi vectors stacked [Re; Im]: orthogonal with norm 1/sqrt(2) in the
    // real inner product (the basis' inner product is 2 Re sum conj(u) v). So Q1 = sqrt(2) AN spans
    // N's range exactly, and N is eliminated without a factorisation.
    const MatR Q1tAD = Q1.transpose().lazyProduct(AD);
    MatR ADp = AD - Q1.lazyProduct(Q1tAD);
    // The smallest right singular vector of ADp is that of its small triangular factor R, the
    // upper triangle of the QR's top rows (null_vector.h reads only that; a JacobiSVD takes 1.6x
    // the time at n = 10, 2x at n = 14, BM_NullVector*).
    Eigen::HouseholderQR<MatR> qd(ADp);
    VecR a = smallest_right_singular_vector(qd.matrixQR().topRows(n + 1));
    VecR bb = -std::sqrt(2.0) * (Q1tAD * a);  // the least-squares N for this D: AN^+ = 2 AN^T
    const C d0 = poly_at(b, a, 0.0), n0 = poly_at(b, bb, 0.0);
    if (std::abs(d0) == 0.0 || !std::isfinite(std::abs(d0))) break;  // the best so far, if any
    std::vector<C> dk(M);
    double eph = 0, sse = 0;
    const Eigen::VectorXcd dvs = b.Qw.leftCols(n + 1) * a.cast<C>();
    const Eigen::VectorXcd nvs = b.Qw.leftCols(m + 1) * bb.cast<C>();
    for (int i = 0; i < M; ++i) {
      const C dv = dvs(i), nv = nvs(i);
      dk[i] = detail::quotient(dv / sw[i], d0);
      eph += std::sqrt(std::norm(dprev[i] - dk[i]) / std::norm(dprev[i]));
      sse += d.W[i] * std::norm(g[i] - detail::quotient(nv, dv));
    }
    eph /= M;
    r.iterations = it;
    r.e_phi = eph;
    // SK is a fixed-point iteration, not a descent: keep the iterate with the lowest real error.
    // Its roots are computed once, for the iterate returned.
    if (sse < best_sse && std::isfinite(sse)) {
      best_sse = sse;
      it_best = it;
      best_basis = std::move(b);
      best_num = bb;
      best_den = a;
      r.tf.gain = (n0 / d0).real();
      r.ok = std::isfinite(r.tf.gain);
    }
    // Converged, out of iterations, or stalled: an iteration that oscillates without lowering the
    // real error for kSkStall iterations will not converge (noise, a wrong delay); the
    // output-error refinement continues from the best iterate.
    if ((it > 1 && eph <= o.c_phi) || it == o.max_iterations || it - it_best >= kSkStall) break;
    for (int i = 0; i < M; ++i) phi[i] = d.W[i] / std::norm(dk[i]);
    dprev = dk;
  }
  r.sse = best_sse;
  if (r.ok && roots) {
    r.tf.zeros = to_roots(poly_roots(best_basis, best_num), ws);
    r.tf.poles = to_roots(poly_roots(best_basis, best_den), ws);
  }
  return r;
}

}  // namespace fralab::tfns_detail
