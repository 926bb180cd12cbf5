#include "fralab/identify/pole_set_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "fralab/core/error.h"

namespace fralab {

namespace {

using C = std::complex<double>;
using MatR = Eigen::MatrixXd;
using VecR = Eigen::VectorXd;

// The curves in scaled frequency (s = j w / ws), each on its own grid, with square-root weights.
struct Problem {
  int nc = 0, total = 0;  // curves, points over all curves
  double ws = 1, kappa = 0;
  std::vector<std::vector<C>> s;             // [curve][point]
  std::vector<std::vector<double>> spacing;  // local grid spacing, scaled
  const std::vector<std::vector<C>>* g = nullptr;
  std::vector<std::vector<double>> sw;
  int M(int c) const { return int(s[size_t(c)].size()); }
};

int columns(const std::vector<C>& poles) {
  int k = 0;
  for (C p : poles) k += p.imag() == 0 ? 1 : 2;
  return k;
}

// Real-coefficient partial fractions at the points: a real pole's 1/(s - p); a pair's
// 1/(s-p) + 1/(s-conj p) and j/(s-p) - j/(s-conj p) (coefficients c1, c2: residue c1 + j c2).
Eigen::MatrixXcd basis(const std::vector<C>& poles, const std::vector<C>& s) {
  Eigen::MatrixXcd Phi(Eigen::Index(s.size()), columns(poles));
  for (size_t i = 0; i < s.size(); ++i) {
    int k = 0;
    for (const C p : poles) {
      if (p.imag() == 0) {
        Phi(Eigen::Index(i), k++) = 1.0 / (s[i] - p.real());
      } else {
        const C u = 1.0 / (s[i] - p), v = 1.0 / (s[i] - std::conj(p));
        Phi(Eigen::Index(i), k++) = u + v;
        Phi(Eigen::Index(i), k++) = C(0, 1) * (u - v);
      }
    }
  }
  return Phi;
}

// Least squares of a real system with its columns scaled to unit norm.
VecR solve_scaled(const MatR& A, const VecR& b) {
  VecR cn = A.colwise().norm();
  for (Eigen::Index k = 0; k < cn.size(); ++k) cn(k) = cn(k) > 0 ? cn(k) : 1.0;
  const MatR As = A * cn.cwiseInverse().asDiagonal();
  return As.colPivHouseholderQr().solve(b).cwiseQuotient(cn);
}

// Curve c's coefficients (K basis coefficients, then d) by weighted least squares; returns its
// chi^2 (sum W |e|^2) and the coefficients in *x.
double coefficients(const Problem& P, const Eigen::MatrixXcd& Phi, int c, VecR* x) {
  const int M = P.M(c), K = int(Phi.cols());
  MatR A(2 * M, K + 1);
  VecR b(2 * M);
  const auto& g = (*P.g)[size_t(c)];
  const auto& sw = P.sw[size_t(c)];
  for (int i = 0; i < M; ++i) {
    for (int k = 0; k < K; ++k) {
      const C a = sw[size_t(i)] * Phi(i, k);
      A(i, k) = a.real(), A(M + i, k) = a.imag();
    }
    A(i, K) = sw[size_t(i)], A(M + i, K) = 0;
    const C r = sw[size_t(i)] * g[size_t(i)];
    b(i) = r.real(), b(M + i) = r.imag();
  }
  *x = solve_scaled(A, b);
  return (A * *x - b).squaredNorm();
}

// The state-space form of the partial fractions (A, b) in the basis' coefficients' order.
void state_space(const std::vector<C>& poles, MatR* A, VecR* b) {
  const int K = columns(poles);
  *A = MatR::Zero(K, K);
  *b = VecR::Zero(K);
  int k = 0;
  for (const C p : poles) {
    if (p.imag() == 0) {
      (*A)(k, k) = p.real(), (*b)(k) = 1, ++k;
    } else {
      (*A)(k, k) = p.real(), (*A)(k, k + 1) = p.imag();
      (*A)(k + 1, k) = -p.imag(), (*A)(k + 1, k + 1) = p.real();
      (*b)(k) = 2, k += 2;
    }
  }
}

// Stable, pairs by their upper member, real when the imaginary part is rounding.
std::vector<C> tidy_roots(const Eigen::VectorXcd& ev, bool reflect) {
  std::vector<C> out;
  for (Eigen::Index j = 0; j < ev.size(); ++j) {
    C p = ev(j);
    if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) continue;
    if (std::abs(p.imag()) <= 1e-10 * std::abs(p)) p = C(p.real(), 0);
    if (p.imag() < 0) continue;
    if (reflect && p.real() > 0) p = C(-p.real(), p.imag());
    if (reflect && p.real() == 0) p = C(-1e-9 * std::max(std::abs(p), 1e-9), p.imag());
    out.push_back(p);
  }
  return out;
}

// One VF relocation of the poles against every curve (the scaling function's unknowns from each
// curve's equations reduced by QR, stacked with the relaxation row). False when it fails.
bool relocate(const Problem& P, std::vector<C>& poles) {
  const int K = columns(poles);
  MatR stack(P.nc * (K + 1) + 1, K + 1);
  double gscale = 0;
  VecR relax = VecR::Zero(K);
  for (int c = 0; c < P.nc; ++c)
    for (int i = 0; i < P.M(c); ++i)
      gscale += std::norm(P.sw[size_t(c)][size_t(i)] * (*P.g)[size_t(c)][size_t(i)]);
  gscale = std::sqrt(gscale / double(P.total));
  if (!(gscale > 0) || !std::isfinite(gscale)) return false;
  for (int c = 0; c < P.nc; ++c) {
    const int M = P.M(c);
    if (2 * M < 2 * K + 2) return false;
    const Eigen::MatrixXcd Phi = basis(poles, P.s[size_t(c)]);
    const auto& g = (*P.g)[size_t(c)];
    const auto& sw = P.sw[size_t(c)];
    MatR A(2 * M, 2 * K + 2);
    for (int i = 0; i < M; ++i) {
      for (int k = 0; k < K; ++k) {
        const C a = sw[size_t(i)] * Phi(i, k), b = -sw[size_t(i)] * g[size_t(i)] * Phi(i, k);
        A(i, k) = a.real(), A(M + i, k) = a.imag();
        A(i, K + 1 + k) = b.real(), A(M + i, K + 1 + k) = b.imag();
        relax(k) += Phi(i, k).real();
      }
      A(i, K) = sw[size_t(i)], A(M + i, K) = 0;
      const C b = -sw[size_t(i)] * g[size_t(i)];
      A(i, 2 * K + 1) = b.real(), A(M + i, 2 * K + 1) = b.imag();
    }
    VecR cn = A.colwise().norm();
    for (Eigen::Index k = 0; k < cn.size(); ++k) cn(k) = cn(k) > 0 ? cn(k) : 1.0;
    A = A * cn.cwiseInverse().asDiagonal();
    Eigen::HouseholderQR<MatR> qr(A);
    const MatR R = qr.matrixQR().topRows(2 * K + 2).triangularView<Eigen::Upper>();
    // Back in unscaled units for the sigma block.
    stack.block(c * (K + 1), 0, K + 1, K + 1) =
        R.block(K + 1, K + 1, K + 1, K + 1) * cn.tail(K + 1).asDiagonal();
  }
  // Relaxation: Re sum sigma(s_i) over every point = the number of points, weighted like a data
  // row.
  for (int k = 0; k < K; ++k) stack(P.nc * (K + 1), k) = gscale * relax(k) / P.total;
  stack(P.nc * (K + 1), K) = gscale;
  VecR rhs = VecR::Zero(stack.rows());
  rhs(P.nc * (K + 1)) = gscale * std::sqrt(double(P.total));
  const VecR x = solve_scaled(stack, rhs);
  if (!x.allFinite()) return false;
  double dt = x(K);
  if (std::abs(dt) < 1e-8) dt = dt < 0 ? -1e-8 : 1e-8;
  MatR Ass;
  VecR bv;
  state_space(poles, &Ass, &bv);
  const MatR Z = Ass - bv * x.head(K).transpose() / dt;
  Eigen::EigenSolver<MatR> es(Z, false);
  if (es.info() != Eigen::Success) return false;
  std::vector<C> next = tidy_roots(es.eigenvalues(), true);
  if (columns(next) != K) return false;
  poles = next;
  return true;
}

// A model at given poles: coefficients of every curve and the figures.
struct Model {
  std::vector<C> poles;
  std::vector<VecR> x;  // per curve: K coefficients, then d
  std::vector<double> chi2;
  double total = 0, crit = 0, chi2dof = 0;
  int params = 0;
  bool adequate = false;
};

Model evaluate(const Problem& P, const std::vector<C>& poles) {
  Model m;
  m.poles = poles;
  const int K = columns(poles);
  for (int c = 0; c < P.nc; ++c) {
    VecR x;
    m.chi2.push_back(coefficients(P, basis(poles, P.s[size_t(c)]), c, &x));
    m.x.push_back(x);
    m.total += m.chi2.back();
  }
  m.params = K + P.nc * (K + 1);
  const double N = double(P.total);
  m.chi2dof = m.total / std::max(1.0, N - m.params / 2.0);
  m.adequate = m.chi2dof <= 1 + 3 / std::sqrt(N);
  m.crit = m.total + P.kappa * m.params;
  return m;
}

// The weighted residual of a model on curve c per point, smoothed over +-2 points.
std::vector<double> residual_profile(const Problem& P, const Model& m, int c) {
  const Eigen::MatrixXcd Phi = basis(m.poles, P.s[size_t(c)]);
  const int K = int(Phi.cols()), M = P.M(c);
  std::vector<double> e(size_t(M), 0.0);
  for (int i = 0; i < M; ++i) {
    C v = m.x[size_t(c)](K);
    for (int k = 0; k < K; ++k) v += Phi(i, k) * m.x[size_t(c)](k);
    e[size_t(i)] = std::norm(P.sw[size_t(c)][size_t(i)] * ((*P.g)[size_t(c)][size_t(i)] - v));
  }
  std::vector<double> sm(e.size(), 0.0);
  for (int i = 0; i < M; ++i) {
    int n = 0;
    for (int j = std::max(0, i - 2); j <= std::min(M - 1, i + 2); ++j)
      sm[size_t(i)] += e[size_t(j)], ++n;
    sm[size_t(i)] /= n;
  }
  return sm;
}

// New pairs at the largest peaks of the residual over every curve (at least 5 grid spacings
// apart), at most `count`.
std::vector<C> peaks_to_add(const Problem& P, const Model& m, int count) {
  struct Peak {
    double value, b, spacing;
  };
  std::vector<Peak> peaks;
  for (int c = 0; c < P.nc; ++c) {
    const std::vector<double> r = residual_profile(P, m, c);
    const int M = P.M(c);
    for (int i = 0; i < M; ++i) {
      const bool left = i == 0 || r[size_t(i)] >= r[size_t(i - 1)];
      const bool right = i == M - 1 || r[size_t(i)] >= r[size_t(i + 1)];
      if (left && right)
        peaks.push_back(
            {r[size_t(i)], P.s[size_t(c)][size_t(i)].imag(), P.spacing[size_t(c)][size_t(i)]});
    }
  }
  std::sort(peaks.begin(), peaks.end(),
            [](const Peak& a, const Peak& b) { return a.value > b.value; });
  std::vector<Peak> chosen;
  for (const Peak& p : peaks) {
    if (int(chosen.size()) >= count) break;
    bool far = true;
    for (const Peak& q : chosen)
      far = far && std::abs(p.b - q.b) >= 5 * std::max(p.spacing, q.spacing);
    if (far) chosen.push_back(p);
  }
  std::vector<C> out;
  for (const Peak& p : chosen) out.push_back(C(-2 * p.spacing, p.b));
  return out;
}

// The pole whose removal (coefficients refitted) raises chi^2 least, against its penalty; -1 when
// every pole earns its place.
int cheapest_pole(const Problem& P, const Model& m) {
  int best = -1;
  double best_margin = 0;
  for (size_t j = 0; j < m.poles.size(); ++j) {
    std::vector<C> rest = m.poles;
    rest.erase(rest.begin() + long(j));
    if (rest.empty()) continue;
    const Model r = evaluate(P, rest);
    const double margin = (r.total - m.total) - P.kappa * (m.params - r.params);
    if (margin < best_margin) best_margin = margin, best = int(j);
  }
  return best;
}

// The curves as the fit sees them (checked, scaled, square-root weights); "" or what is wrong.
// lo, hi: the band over every curve (rad/s); smallest: the fewest points of a curve.
std::string make_problem(const std::vector<std::vector<double>>& w,
                         const std::vector<std::vector<C>>& g,
                         const std::vector<std::vector<double>>& W, Problem* P, double* lo,
                         double* hi, int* smallest) {
  if (g.empty() || g.size() != W.size() || g.size() != w.size())
    return "no curve, or curves, grids and weights of different counts";
  *lo = INFINITY, *hi = 0;
  int total = 0;
  *smallest = std::numeric_limits<int>::max();
  for (size_t c = 0; c < g.size(); ++c) {
    const auto& wc = w[c];
    if (g[c].size() != wc.size() || W[c].size() != wc.size())
      return "curve " + std::to_string(c) + ": values, weights and grid of different sizes";
    if (wc.size() < 4) return "curve " + std::to_string(c) + ": fewer than 4 points";
    for (size_t i = 0; i < wc.size(); ++i) {
      if (!(wc[i] > 0) || (i > 0 && !(wc[i] > wc[i - 1])))
        return "curve " + std::to_string(c) + ": frequencies must be > 0 and increasing";
    }
    *lo = std::min(*lo, wc.front()), *hi = std::max(*hi, wc.back());
    total += int(wc.size());
    *smallest = std::min(*smallest, int(wc.size()));
  }
  P->nc = int(g.size());
  P->total = total;
  P->g = &g;
  P->ws = std::sqrt(*lo * *hi);
  P->kappa = std::log(2.0 * total);
  for (size_t c = 0; c < g.size(); ++c) {
    const auto& wc = w[c];
    const int M = int(wc.size());
    std::vector<C> sc;
    std::vector<double> spc, sw;
    for (int i = 0; i < M; ++i) {
      sc.push_back(C(0, wc[size_t(i)] / P->ws));
      const double a = i > 0 ? wc[size_t(i)] - wc[size_t(i - 1)] : wc[1] - wc[0];
      const double b = i < M - 1 ? wc[size_t(i + 1)] - wc[size_t(i)] : a;
      spc.push_back(0.5 * (a + b) / P->ws);
      sw.push_back(std::sqrt(std::max(W[c][size_t(i)], 0.0)));
    }
    P->s.push_back(sc);
    P->spacing.push_back(spc);
    P->sw.push_back(sw);
  }
  return "";
}

// Step 1's start: `pairs` pairs spread linearly over [lo, hi] (scaled units), real part -1 %.
std::vector<C> start_poles(const Problem& P, double lo, double hi, int pairs) {
  std::vector<C> poles;
  for (int k = 0; k < pairs; ++k) {
    const double f = (k + 0.5) / pairs;
    const double b = (lo + f * (hi - lo)) / P.ws;
    poles.push_back(C(-b / 100, b));
  }
  return poles;
}

// `times` relocations of p (fewer when one fails: the last that succeeded).
std::vector<C> relocate_times(const Problem& P, std::vector<C> p, int times) {
  for (int r = 0; r < times; ++r) {
    std::vector<C> q = p;
    if (!relocate(P, q)) break;
    p = q;
  }
  return p;
}

}  // namespace

void PoleSetFitOptions::validate() const {
  auto bad = [](const std::string& m) { throw InputError("pole set fit: " + m); };
  if (max_poles < 1 || max_poles > 400) bad("max_poles must be in [1, 400]");
  if (start_pairs < 1) bad("start_pairs must be >= 1");
  if (relocations < 1) bad("relocations must be >= 1");
  if (max_rounds < 0) bad("max_rounds must be >= 0");
}

C PoleSetFit::at(size_t c, double w) const {
  const C s(0, w);
  C v = d[c];
  for (size_t k = 0; k < poles.size(); ++k) {
    const C p = poles[k], r = residues[c][k];
    if (p.imag() == 0)
      v += r.real() / (s - p.real());
    else
      v += r / (s - p) + std::conj(r) / (s - std::conj(p));
  }
  return v;
}

Tf PoleSetFit::to_tf(size_t c) const {
  Tf t;
  if (poles.empty()) {
    t.gain = d[c];
    return t;
  }
  // In scaled units (the largest pole's modulus) for the eigenproblem.
  double sc = 0;
  for (C p : poles) sc = std::max(sc, std::abs(p));
  std::vector<C> ps;
  for (C p : poles) ps.push_back(p / sc);
  MatR A;
  VecR b;
  state_space(ps, &A, &b);
  const int K = int(A.rows());
  VecR cv(K);
  int k = 0;
  for (size_t j = 0; j < ps.size(); ++j) {
    const C r = residues[c][j] / sc;  // r / (s - p) = (r / sc) / (s/sc - p/sc)
    if (ps[j].imag() == 0) {
      cv(k++) = r.real();
    } else {
      cv(k++) = r.real(), cv(k++) = r.imag();
    }
  }
  MatR S = MatR::Zero(K + 1, K + 1), E = MatR::Zero(K + 1, K + 1);
  S.topLeftCorner(K, K) = A;
  S.topRightCorner(K, 1) = b;
  S.bottomLeftCorner(1, K) = cv.transpose();
  S(K, K) = d[c];
  E.topLeftCorner(K, K).setIdentity();
  Eigen::GeneralizedEigenSolver<MatR> ges(S, E, false);
  Eigen::VectorXcd zs(K + 1);
  int nz = 0;
  for (int j = 0; j <= K; ++j) {
    const C a = ges.alphas()(j);
    const double be = ges.betas()(j);
    if (std::abs(be) > 1e-10 * std::max(std::abs(a), 1.0) && std::abs(a / be) < 1e6)
      zs(nz++) = a / be;
  }
  const std::vector<C> zeros = tidy_roots(zs.head(nz), false);
  const C g0 = at(c, 0.0);
  t.gain = g0.real();
  for (C p : poles) {
    if (p.imag() == 0)
      t.poles.push_back(Root::Real(p.real()));
    else
      t.poles.push_back(Root::Pair(std::abs(p), -p.real() / std::abs(p)));
  }
  for (C z : zeros) {
    z *= sc;
    if (std::abs(z) < 1e-12 * sc) z = C(-1e-9 * sc, 0);
    if (z.imag() == 0)
      t.zeros.push_back(Root::Real(z.real()));
    else
      t.zeros.push_back(Root::Pair(std::abs(z), -z.real() / std::abs(z)));
  }
  return t;
}

PoleSetFit fit_pole_set(const std::vector<double>& w, const std::vector<std::vector<C>>& g,
                        const std::vector<std::vector<double>>& W, const PoleSetFitOptions& o) {
  for (size_t c = 0; c < g.size(); ++c) {
    if (g[c].size() != w.size() || (c < W.size() && W[c].size() != w.size())) {
      o.validate();
      PoleSetFit out;
      out.message = "curve " + std::to_string(c) + " is not on the common grid";
      return out;
    }
  }
  return fit_pole_set(std::vector<std::vector<double>>(g.size(), w), g, W, o);
}

PoleSetFit fit_pole_set(const std::vector<std::vector<double>>& w,
                        const std::vector<std::vector<C>>& g,
                        const std::vector<std::vector<double>>& W, const PoleSetFitOptions& o) {
  o.validate();
  PoleSetFit out;
  Problem P;
  double lo = 0, hi = 0;
  int smallest = 0;
  out.message = make_problem(w, g, W, &P, &lo, &hi, &smallest);
  if (!out.message.empty()) return out;
  const int max_poles = std::min(o.max_poles, smallest - 2);
  // 1. Start pairs spread linearly over the band.
  std::vector<C> poles =
      start_poles(P, lo, hi, std::max(1, std::min(o.start_pairs, max_poles / 2)));
  if (max_poles < 2) poles = {C(-1, 0)};
  auto relocated = [&](std::vector<C> p) { return relocate_times(P, std::move(p), o.relocations); };
  Model cur = evaluate(P, relocated(poles)), best = cur;
  int stall = 0;
  for (int round = 0; round < o.max_rounds && !cur.adequate; ++round) {
    const int order = columns(cur.poles);
    if (order + 2 > max_poles) break;
    const int room = (max_poles - order) / 2;
    const int count = std::max(1, std::min(room, std::max(1, order / 8)));
    std::vector<C> next = cur.poles;
    for (C p : peaks_to_add(P, cur, count)) next.push_back(p);
    out.added += columns(next) - order;
    cur = evaluate(P, relocated(next));
    ++out.rounds;
    const double gain = (best.crit - cur.crit) / std::max(std::abs(best.crit), 1e-300);
    stall = gain < 0.01 ? stall + 1 : 0;
    if (cur.crit < best.crit) best = cur;
    if (stall >= 2) break;
  }
  // 5. Skimming.
  for (int j = cheapest_pole(P, best); j >= 0; j = cheapest_pole(P, best)) {
    std::vector<C> rest = best.poles;
    rest.erase(rest.begin() + j);
    Model r = evaluate(P, rest);
    const Model moved = evaluate(P, relocated(rest));
    if (moved.crit < r.crit) r = moved;
    if (!(r.crit < best.crit)) break;
    out.skimmed += columns(best.poles) - columns(r.poles);
    best = r;
  }
  // 6. Polish: more relocations of the chosen set, the best by the criterion kept (a relocation
  // need not lower it: VF is a fixed point, not a descent).
  {
    std::vector<C> q = best.poles;
    for (int r = 0; r < 3 * o.relocations; ++r) {
      if (!relocate(P, q)) break;
      Model m = evaluate(P, q);
      if (m.crit < best.crit) best = m;
    }
  }
  // The result in rad/s.
  out.order = columns(best.poles);
  const int K = out.order;
  for (C p : best.poles) out.poles.push_back(p * P.ws);
  for (int c = 0; c < P.nc; ++c) {
    std::vector<C> rs;
    int k = 0;
    for (C p : best.poles) {
      if (p.imag() == 0)
        rs.push_back(C(best.x[size_t(c)](k++) * P.ws, 0));
      else
        rs.push_back(C(best.x[size_t(c)](k), best.x[size_t(c)](k + 1)) * P.ws), k += 2;
    }
    out.residues.push_back(rs);
    out.d.push_back(best.x[size_t(c)](K));
    out.chi2.push_back(best.chi2[size_t(c)]);
  }
  out.chi2_total = best.total;
  out.chi2_per_dof = best.chi2dof;
  out.status = best.adequate ? PoleSetFit::Status::kAdequate : PoleSetFit::Status::kNotAdequate;
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "%s: %d poles for %d curve(s), chi2/dof %.3g; %d rounds, %d added, %d skimmed",
                best.adequate ? "adequate" : "not adequate", out.order, P.nc, out.chi2_per_dof,
                out.rounds, out.added, out.skimmed);
  out.message = buf;
  return out;
}

std::vector<C> relocated_poles(const std::vector<double>& w, const std::vector<std::vector<C>>& g,
                               const std::vector<std::vector<double>>& W, int pairs,
                               int relocations) {
  Problem P;
  double lo = 0, hi = 0;
  int smallest = 0;
  const std::vector<std::vector<double>> ws(g.size(), w);
  if (pairs < 1 || !make_problem(ws, g, W, &P, &lo, &hi, &smallest).empty() ||
      2 * pairs > smallest - 2)
    return {};
  std::vector<C> out;
  for (C p : relocate_times(P, start_poles(P, lo, hi, pairs), relocations)) out.push_back(p * P.ws);
  return out;
}

}  // namespace fralab
