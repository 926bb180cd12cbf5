#include "output_error.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "fralab/core/numerics.h"

namespace fralab::tfns_detail {
namespace {

// ---- output-error refinement -------------------------------------------------------------------
struct Param {
  Tf shape;  // structure (which roots are real / pairs)
  double g0;
  bool free_delay;
  double fixed_delay;
  double max_delay = INFINITY;  // a free delay stays in [0, max_delay]
  int size() const {
    int k = 1 + (free_delay ? 1 : 0);
    for (const Root& z : shape.zeros) k += z.order();
    for (const Root& p : shape.poles) k += p.order();
    return k;
  }
  VecR pack(const Tf& t) const {
    VecR x(size());
    int k = 0;
    x(k++) = t.gain / g0;
    for (const Root& z : t.zeros) {
      if (z.pair) {
        x(k++) = std::log(z.wn);
        x(k++) = z.zeta;
      } else {
        x(k++) = 1.0 / z.real;
      }
    }
    for (const Root& p : t.poles) {
      if (p.pair) {
        x(k++) = std::log(p.wn);
        x(k++) = std::log(p.zeta);
      } else {
        x(k++) = std::log(-p.real);
      }
    }
    if (free_delay) x(k++) = t.delay_s;
    return x;
  }
  Tf unpack(const VecR& x) const {
    Tf t = shape;
    int k = 0;
    t.gain = x(k++) * g0;
    for (Root& z : t.zeros) {
      if (z.pair) {
        z.wn = std::exp(x(k++));
        z.zeta = x(k++);
      } else {
        z.real = 1.0 / x(k++);
      }
    }
    for (Root& p : t.poles) {
      // Bounded away from the imaginary axis: exp() of a runaway parameter must not underflow to 0.
      if (p.pair) {
        p.wn = std::exp(x(k++));
        p.zeta = std::max(std::exp(x(k++)), 1e-9);
      } else {
        p.real = -std::max(std::exp(x(k++)), 1e-12);
      }
    }
    t.delay_s = free_delay ? std::min(std::abs(x(k++)), max_delay) : fixed_delay;
    return t;
  }
};

// Residuals sqrt(W_i) (G_i - G_a(j w_i)) (real and imaginary rows) with the exact Jacobian: every
// parameter enters through one factor F, so dG_a/dx = +-G_a (dF/dx) / F.
void split_overdamped(std::vector<Root>& v);

struct OeFunctor {
  const Data* d;
  const Param* p;
  std::vector<double> sw;  // sqrt(W_i)
  OeFunctor(const Data* dd, const Param* pp) : d(dd), p(pp), sw(dd->W.size()) {
    for (size_t i = 0; i < sw.size(); ++i) sw[i] = std::sqrt(d->W[i]);
  }
  int inputs() const { return p->size(); }
  int values() const { return 2 * int(d->w.size()); }
  int operator()(const VecR& x, VecR& f) const {
    Tf t = p->unpack(x);
    const int M = int(d->w.size());
    for (int i = 0; i < M; ++i) {
      C e = (d->g[i] - t.at(d->w[i])) * sw[i];
      f(i) = e.real();
      f(M + i) = e.imag();
    }
    return 0;
  }
  int df(const VecR& x, MatR& J) const {
    Tf t = p->unpack(x);
    const int M = int(d->w.size());
    for (int i = 0; i < M; ++i) {
      const C s(0.0, d->w[i]);
      const C G = t.at(d->w[i]);
      const double swi = sw[i];
      int k = 0;
      auto put = [&](C dG) {  // de/dx = -sqrt(W) dG/dx
        J(i, k) = -swi * dG.real();
        J(M + i, k) = -swi * dG.imag();
        ++k;
      };
      put(G / x(0));
      // d/dx of a factor F over F, times G (for a zero; minus for a pole), with s = j w:
      // a pair's dF/d ln wn = -2 s^2/wn^2 - 2 zeta s/wn = 2 w^2/wn^2 - j 2 zeta w/wn; the zero's
      // dF/dzeta = 2 s/wn = j 2 w/wn; the pole's dF/d ln zeta = zeta dF/dzeta; a real root's dF/du
      // = -s (zero, u = 1/r) and dF/d ln|r| = s/r (pole). One division by F per root.
      const double w = d->w[i];
      for (const Root& z : t.zeros) {
        const C GF = detail::quotient(G, z.factor_jw(w));
        if (z.pair) {
          const double a = w / z.wn;
          put(GF * C(2.0 * a * a, -2.0 * z.zeta * a));
          put(GF * C(0.0, 2.0 * a));
        } else {
          put(GF * C(0.0, -w));
        }
      }
      for (const Root& q : t.poles) {
        const C GF = -detail::quotient(G, q.factor_jw(w));
        if (q.pair) {
          const double a = w / q.wn;
          put(GF * C(2.0 * a * a, -2.0 * q.zeta * a));
          put(GF * C(0.0, 2.0 * q.zeta * a));
        } else {
          put(GF * C(0.0, w / q.real));
        }
      }
      if (p->free_delay)
        put(std::abs(x(k)) >= p->max_delay ? C(0.0) : -s * G * (x(k) >= 0 ? 1.0 : -1.0));
    }
    return 0;
  }
};

// Real roots (nonzero) taken in order of value, each two neighbours of one sign as a pair with
// wn = sqrt(r1 r2), zeta = -(r1 + r2) / (2 wn) (|zeta| >= 1): the same factors.
void merge_real_roots(std::vector<Root>& v) {
  std::vector<double> reals;
  std::vector<Root> out;
  for (const Root& r : v) {
    if (!r.pair && r.real != 0) {
      reals.push_back(r.real);
    } else {
      out.push_back(r);
    }
  }
  std::sort(reals.begin(), reals.end());
  size_t i = 0;
  while (i < reals.size()) {
    if (i + 1 < reals.size() && (reals[i] < 0) == (reals[i + 1] < 0)) {
      const double wn = std::sqrt(reals[i] * reals[i + 1]);
      out.push_back(Root::Pair(wn, -(reals[i] + reals[i + 1]) / (2 * wn)));
      i += 2;
    } else {
      out.push_back(Root::Real(reals[i]));
      ++i;
    }
  }
  v = out;
}

// LM from `start`. max_evaluations > 0 caps the residual evaluations (a screening refinement of a
// candidate: most converge within a few tens; a start that wanders is continued only if it wins);
// 0: the full budget, 200 (p + 1). *budget_hit tells whether the cap stopped it.
// Stops early when the objective has stalled: sum W |e|^2 lowered by less than kStallChi2 (with
// sigma: in chi^2 units, nothing a criterion can see) or by less than kStallRel of itself (without)
// over kStallSteps steps. A root running off along a flat valley (two real poles packed as a pair,
// zeta -> 1500 and one pole -> 1e7 rad/s) otherwise crawls on to the whole budget: on the random
// benchmark's seed 4 at 0.5 % noise such crawls are 3/4 of the time, and stopping them changes no
// fit's order. A tenth of a chi^2 unit over ten steps moves a parameter by at most ~0.3 of its
// sigma; against 0.01 it gives the same orders on seeds 1-5 in less time (BM_Order3Fit100Points
// 3.2 ms against 4.5 ms).
constexpr int kStallSteps = 10;
constexpr double kStallChi2 = 0.1, kStallRel = 1e-4;

// MINPACK's Levenberg-Marquardt (lmder and lmpar, More 1978: a trust region ||D h|| <= delta,
// D the running maximum of J's column norms, the first bound 100 ||D x0|| cut to the first step,
// the damping par found by Newton's method on ||D h(par)|| = delta) with each step solved from the
// normal equations (J^T J + par D^2) h = -J^T r by Cholesky. Eigen's port of MINPACK takes the
// same steps from a pivoted QR of the 2N x p Jacobian at every step, half of a refinement's time:
// on the random benchmark (seeds 1-5) the normal equations take 5-20 % less time per fit at the
// median and 15-25 % at p90, with the same orders everywhere. They square J's condition number,
// so a converged optimum is polished by one Gauss-Newton step solved by QR of J itself
// (noise-free data stay at machine precision). Stops: the relative reductions (actual and
// predicted) below ftol, the trust region below xtol of ||D x||, the stall rule above, or max_fev
// residual evaluations.
enum class LmStop { kConverged, kStalled, kBudget, kBadStart };
struct Lmpar {
  double par = 0;
  VecR h;
};
// The damping par >= 0 and step h with ||D h|| within 10 % of delta, or par = 0 and the
// Gauss-Newton step when that is shorter (MINPACK's lmpar on the normal equations).
Lmpar lmpar(const MatR& A, const VecR& g, const VecR& diag, double delta, double par0) {
  constexpr double kDwarf = std::numeric_limits<double>::min();
  Lmpar out;
  const Eigen::LLT<MatR> gn(A);
  const bool singular = gn.info() != Eigen::Success;
  out.h = singular ? VecR(A.completeOrthogonalDecomposition().solve(-g)) : VecR(gn.solve(-g));
  if (!out.h.allFinite()) out.h.setZero();
  VecR dx = diag.cwiseProduct(out.h);
  double dxnorm = dx.norm(), fp = dxnorm - delta;
  if (fp <= 0.1 * delta) return out;  // the Gauss-Newton step fits the trust region
  double parl = 0;
  if (!singular) {  // Newton's lower bound
    const VecR wa = gn.matrixL().solve(VecR(diag.cwiseProduct(dx) / dxnorm));
    parl = fp / delta / wa.squaredNorm();
  }
  const double gnorm = g.cwiseQuotient(diag).norm();
  double paru = gnorm / delta;
  if (paru == 0) paru = kDwarf / std::min(delta, 0.1);
  double par = std::clamp(par0, parl, paru);
  if (par == 0) par = gnorm / dxnorm;
  for (int it = 1;; ++it) {
    if (par == 0) par = std::max(kDwarf, 1e-3 * paru);
    MatR Ap = A;
    Ap.diagonal() += par * diag.cwiseAbs2();
    const Eigen::LLT<MatR> llt(Ap);
    out.h = llt.solve(-g);
    out.par = par;
    if (llt.info() != Eigen::Success || !out.h.allFinite()) {
      out.h.setZero();
      return out;
    }
    dx = diag.cwiseProduct(out.h);
    dxnorm = dx.norm();
    if (dxnorm == 0) break;  // a zero gradient: no step to scale
    const double temp = fp;
    fp = dxnorm - delta;
    if (std::abs(fp) <= 0.1 * delta || (parl == 0 && fp <= temp && temp < 0) || it == 10) break;
    const VecR wa = llt.matrixL().solve(VecR(diag.cwiseProduct(dx) / dxnorm));
    const double parc = fp / delta / wa.squaredNorm();
    if (fp > 0) parl = std::max(parl, par);
    if (fp < 0) paru = std::min(paru, par);
    par = std::max(parl, par + parc);
  }
  return out;
}

// MINPACK's trust-region update after a step of ratio = actual / predicted reduction: shrink the
// region (and raise par) when the step did poorly (ratio <= 0.25; fnorm1 the residual's norm after
// it, fnorm before), widen it (and halve par) when it did well.
void update_trust_region(double ratio, double actred, double dirder, double fnorm1, double fnorm,
                         double pnorm, double& delta, double& par) {
  if (ratio <= 0.25) {
    double temp = actred >= 0 ? 0.5 : 0.5 * dirder / (dirder + 0.5 * actred);
    if (!(0.1 * fnorm1 < fnorm) || temp < 0.1) temp = 0.1;
    delta = temp * std::min(delta, pnorm / 0.1);
    par /= temp;
  } else if (par == 0 || ratio >= 0.75) {
    delta = pnorm / 0.5;
    par *= 0.5;
  }
}

// MINPACK's tests: the relative reduction (actual and predicted) or the region's size below the
// tolerances, or below what double precision resolves.
bool lm_converged(double actred, double prered, double ratio, double delta, double xnorm) {
  constexpr double kXtol = 1e-12, kFtol = 1e-14;
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  return (std::abs(actred) <= kFtol && prered <= kFtol && 0.5 * ratio <= 1) ||
         delta <= kXtol * xnorm ||
         (std::abs(actred) <= kEps && prered <= kEps && 0.5 * ratio <= 1) || delta <= kEps * xnorm;
}

LmStop lm_minimize(const OeFunctor& f, VecR& x, int max_fev, bool chi2_units) {
  constexpr double kFactor = 100;
  const int nv = f.values(), np = f.inputs();
  VecR r(nv), rn(nv);
  MatR J(nv, np);
  f(x, r);
  int nfev = 1;
  double fnorm = r.norm();
  if (!std::isfinite(fnorm)) return LmStop::kBadStart;
  VecR diag(np);
  double delta = 0, xnorm = 0, par = 0, mark = INFINITY;
  LmStop stop = LmStop::kConverged;
  bool done = false;
  MatR A;
  VecR g;
  for (int iter = 1; !done && fnorm > 0; ++iter) {  // (an exact fit has nothing to refine)
    f.df(x, J);
    A.noalias() = J.transpose().lazyProduct(J);
    g.noalias() = J.transpose() * r;
    const VecR colnorm = A.diagonal().cwiseMax(0.0).cwiseSqrt();
    if (iter == 1) {
      for (int j = 0; j < np; ++j) diag(j) = colnorm(j) == 0 ? 1.0 : colnorm(j);
      xnorm = diag.cwiseProduct(x).norm();
      delta = kFactor * xnorm;
      if (delta == 0) delta = kFactor;
    } else {
      diag = diag.cwiseMax(colnorm);
    }
    while (true) {  // until a step is accepted (ratio >= 1e-4) or a stop
      const Lmpar lp = lmpar(A, g, diag, delta, par);
      par = lp.par;
      const double pnorm = diag.cwiseProduct(lp.h).norm();
      if (iter == 1) delta = std::min(delta, pnorm);
      const VecR xn = x + lp.h;
      f(xn, rn);
      ++nfev;
      const double fnorm1 = rn.norm();
      double actred = -1;
      if (std::isfinite(fnorm1) && 0.1 * fnorm1 < fnorm)
        actred = 1 - (fnorm1 / fnorm) * (fnorm1 / fnorm);
      const double jh2 = std::max(0.0, lp.h.dot(A * lp.h));  // ||J h||^2
      const double temp1 = std::sqrt(jh2) / fnorm, temp2 = std::sqrt(par) * pnorm / fnorm;
      const double prered = temp1 * temp1 + temp2 * temp2 / 0.5;
      const double dirder = -(temp1 * temp1 + temp2 * temp2);
      const double ratio = prered != 0 ? actred / prered : 0;
      update_trust_region(ratio, actred, dirder, fnorm1, fnorm, pnorm, delta, par);
      const bool accepted = ratio >= 1e-4;
      if (accepted) {
        x = xn;
        r.swap(rn);
        xnorm = diag.cwiseProduct(x).norm();
        fnorm = fnorm1;
      }
      if (lm_converged(actred, prered, ratio, delta, xnorm)) {
        done = true;
        break;
      }
      if (nfev >= max_fev) {
        stop = LmStop::kBudget;
        done = true;
        break;
      }
      if (accepted) break;
    }
    if (done || iter % kStallSteps) continue;
    const double now = fnorm * fnorm;
    if (mark - now < (chi2_units ? kStallChi2 : kStallRel * now)) {
      stop = LmStop::kStalled;
      break;
    }
    mark = now;
  }
  if (stop == LmStop::kConverged) {  // the polish: one Gauss-Newton step by QR of J
    f.df(x, J);
    const VecR xn = x + VecR(J.colPivHouseholderQr().solve(-r));
    f(xn, rn);
    if (rn.norm() < fnorm) x = xn;
  }
  return stop;
}

// A "pair" with |zeta| >= 1 is two real roots: list it so (the refinement may cross zeta = 1).
void split_overdamped(std::vector<Root>& v) {
  std::vector<Root> out;
  for (const Root& r : v) {
    if (r.pair && std::abs(r.zeta) >= 1.0) {
      // The larger root directly, the smaller as wn^2 over it: -wn (zeta - q) cancels to 0 for a
      // large zeta (a pair at zeta 1e116 split into a pole at -1.2e117 and one at -0 rad/s, which
      // made the model's value NaN).
      const double q = std::sqrt(r.zeta * r.zeta - 1.0);
      const double big = -r.wn * (r.zeta + std::copysign(q, r.zeta));
      out.push_back(Root::Real(big));
      out.push_back(Root::Real(r.wn * r.wn / big));
    } else {
      out.push_back(r);
    }
  }
  std::sort(out.begin(), out.end(), [](const Root& a, const Root& b) {
    return (a.pair ? a.wn : std::abs(a.real)) < (b.pair ? b.wn : std::abs(b.real));
  });
  v = out;
}

}  // namespace

Tf refine(const Data& d, const Tf& start, bool free_delay, int max_evaluations, bool* budget_hit) {
  if (budget_hit) *budget_hit = false;
  // A zero at exactly s = 0 cannot be packed; such starts are returned unrefined.
  for (const Root& z : start.zeros)
    if (!z.pair && z.real == 0) return start;
  // Real roots of one sign are refined in pairs (zeta >= 1 is two real roots): two real poles can
  // then become a resonance, which their separate parameters cannot.
  Tf merged = start;
  merge_real_roots(merged.zeros);
  merge_real_roots(merged.poles);
  Param p{merged, start.gain == 0 ? 1.0 : start.gain, free_delay, start.delay_s, d.max_delay};
  OeFunctor f{&d, &p};
  VecR x = p.pack(merged);
  const LmStop stop =
      lm_minimize(f, x, max_evaluations > 0 ? max_evaluations : 200 * (p.size() + 1), d.has_sigma);
  if (budget_hit) *budget_hit = stop == LmStop::kBudget;
  Tf out = p.unpack(x);
  for (const Root& q : out.poles)
    if (!std::isfinite(q.wn) || !std::isfinite(q.real)) return start;
  if (!std::isfinite(out.gain)) return start;
  split_overdamped(out.zeros);
  split_overdamped(out.poles);
  // A refinement that ran a root off to where the model cannot be evaluated on the data (a pole at
  // 0 or beyond the floating-point range) is not a fit: the start stands.
  for (const double w : d.w)
    if (!std::isfinite(std::abs(out.at(w)))) return start;
  return out;
}

Score score(const Data& d, const Tf& t) {
  Score s;
  double den = 0;
  double chi = 0;
  for (size_t i = 0; i < d.w.size(); ++i) {
    C e = d.g[i] - t.at(d.w[i]);
    s.sse += d.W[i] * std::norm(e);
    den += d.W[i] * std::norm(d.g[i]);
    if (d.has_sigma) chi += std::norm(e) / (d.sigma[i] * d.sigma[i]);
  }
  s.e_n = s.sse / den;
  if (d.has_sigma) s.chi2 = chi;
  return s;
}

// The chosen model's rms and largest |G_data - G_model| / |G_data| over the points (only the
// result reports them; score() runs at every candidate and leaves them out).
std::pair<double, double> rel_errors(const Data& d, const Tf& t) {
  double rel2 = 0, max_rel = 0;
  for (size_t i = 0; i < d.w.size(); ++i) {
    const double rel = std::abs(d.g[i] - t.at(d.w[i])) / std::max(std::abs(d.g[i]), 1e-300);
    rel2 += rel * rel;
    max_rel = std::max(max_rel, rel);
  }
  return {std::sqrt(rel2 / d.w.size()), max_rel};
}

Sigmas parameter_sigmas(const Data& d, const Tf& t, bool free_delay, double sse) {
  Sigmas out;
  Param p{t, t.gain == 0 ? 1.0 : t.gain, free_delay, t.delay_s, d.max_delay};
  for (const Root& z : t.zeros)
    if (!z.pair && z.real == 0) return out;
  OeFunctor f{&d, &p};
  VecR x = p.pack(t);
  MatR J(f.values(), f.inputs());
  f.df(x, J);
  // cov = V diag(1/s^2) V^T from the SVD of J; a direction with s ~ 0 is not identified by the
  // data: its parameters get an infinite standard deviation.
  Eigen::JacobiSVD<MatR> svd(J, Eigen::ComputeThinV);
  const VecR sv = svd.singularValues();
  MatR cov = MatR::Zero(J.cols(), J.cols());
  std::vector<bool> unidentified(J.cols(), false);
  for (int i = 0; i < sv.size(); ++i) {
    if (sv(i) <= 1e-12 * sv(0)) {
      for (int k = 0; k < J.cols(); ++k)
        if (std::abs(svd.matrixV()(k, i)) > 1e-6) unidentified[k] = true;
      continue;
    }
    cov += svd.matrixV().col(i) * svd.matrixV().col(i).transpose() / (sv(i) * sv(i));
  }
  for (int k = 0; k < J.cols(); ++k)
    if (unidentified[k]) cov(k, k) = INFINITY;
  const double var = sse / std::max(1.0, double(f.values() - f.inputs()));
  // Without sigma: scaled by the residual variance. With sigma (measured or estimated): each of
  // the 2N real rows (real and imaginary parts of e_i / sigma_i, sigma_i the complex value's
  // standard deviation) has variance 1/2, widened when the reduced chi^2 exceeds 1 (the data
  // scatter more than sigma says; var = chi^2 / (2N - p) is then above 1/2).
  cov *= d.has_sigma ? std::max(0.5, var) : var;
  auto sd = [&](int k) { return std::sqrt(std::max(0.0, cov(k, k))); };
  // A pair's location s = wn (-zeta +- j sqrt(1 - zeta^2)) moves by |ds|/wn = dzeta / sqrt(1 -
  // zeta^2): unbounded as zeta -> 1, where the two roots split on the real axis by sqrt(2 dzeta)
  // instead. The relative sigma from dzeta is the smaller of the two.
  auto from_zeta = [](double zeta, double dzeta) {
    const double z = std::min(std::abs(zeta), 1.0);
    const double lin = dzeta / std::sqrt(std::max(1.0 - z * z, 1e-300));
    return std::min(lin, std::sqrt(2.0 * dzeta));
  };
  int k = 0;
  out.gain = sd(k++);  // x0 = gain / g0 ~ 1: relative
  for (const Root& z : t.zeros) {
    if (z.pair) {
      out.zeros.push_back(std::hypot(sd(k), from_zeta(z.zeta, sd(k + 1))));
      k += 2;
    } else {
      out.zeros.push_back(sd(k) * std::abs(z.real));
      ++k;
    }
  }
  for (const Root& q : t.poles) {
    if (q.pair) {
      out.poles.push_back(std::hypot(sd(k), from_zeta(q.zeta, q.zeta * sd(k + 1))));
      k += 2;
    } else {
      out.poles.push_back(sd(k));
      ++k;
    }
  }
  if (free_delay) out.delay = sd(k);
  return out;
}

}  // namespace fralab::tfns_detail
