// Stage 5b, the findings sized together (docs/method/diagnosis.md, "The stages"): findings that
// touch the same pairs (linked through shared pairs into groups) have their primary parameters
// refined jointly (with any other parameter the data resolve, as a moved pair's damping), every
// finding in place: chi2 = sum over the group's pairs and points of
// |G_meas - G_model|^2 / sigma_eff^2 (the fitting measurement), minimised by Levenberg-Marquardt
// on forward-difference derivatives (a parameter whose cause's domain is positive in its
// logarithm), each frequency and delay kept within the range its cause is searched in (bounds_of).
// Fitted one after the other, each cause is sized on what the others left: a pole moved by 10 % and
// a gain 0.5 dB higher on one path came back as 16 % and 0.25 dB (diagnose_test,
// TwoOverlappingEffectsOnOnePathAreSizedJointly). A finding alone on its pairs is left as fitted
// (the joint problem is then its own). A refinement that does not lower chi2 leaves the group as it
// was. The state model's entries, fitted as one set over every pair (stage 3a), take their
// intervals here, each the marginal 1-sigma of the group's linearised covariance with every other
// parameter free: moved alone (stage 6), entries the data leave nearly interchangeable (one input,
// one state's row) would get intervals far narrower than the data allow.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "stages.h"

namespace fralab::diag {
namespace {

bool share(const Finding& a, const Finding& b) {
  for (const auto& p : a.pairs)
    if (std::find(b.pairs.begin(), b.pairs.end(), p) != b.pairs.end()) return true;
  return false;
}

// Findings linked through shared pairs, as groups of indices.
std::vector<std::vector<size_t>> groups_of(const std::vector<Finding>& fs) {
  std::vector<size_t> parent(fs.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<size_t(size_t)> root = [&](size_t i) {
    return parent[i] == i ? i : parent[i] = root(parent[i]);
  };
  for (size_t i = 0; i < fs.size(); ++i)
    for (size_t j = i + 1; j < fs.size(); ++j)
      if (share(fs[i], fs[j])) parent[root(i)] = root(j);
  std::map<size_t, std::vector<size_t>> g;
  for (size_t i = 0; i < fs.size(); ++i) g[root(i)].push_back(i);
  std::vector<std::vector<size_t>> out;
  for (auto& [k, v] : g) out.push_back(v);
  return out;
}

// A free parameter of the joint fit: finding fs[finding]'s parameter `key`, fitted in its
// logarithm when `log`, kept within [lo, hi] (in the fitted variable, so logarithms when `log`).
struct FreeParameter {
  size_t finding;
  Param key;
  bool log;
  double lo = -INFINITY, hi = INFINITY;
};

// Where f's parameter `key` may go, in its own units: a frequency (a corner, a resonance, a
// moved pole) within the band of f's pairs widened by opt.corner_decades_beyond on each side, as
// the corner causes search (a root far beyond every measured point acts as a gain there, and
// Levenberg-Marquardt would follow it out without end); a moved pole also within
// opt.pole_shift_range of its simulated place; a delay within [delay_min_s, delay_max_s]; a
// damping within [kDampingSearchMin, kDampingSearchMax], down to a tenth of the simulated one (the
// modes stage's) where that is lower (one refined to 0 is an undamped pair, a model no run can
// hold). The value f holds is always inside: a bound never moves a finding.
std::array<double, 2> bounds_of(const DiagnosisRun& r, const Finding& f, Param key, double v) {
  std::array<double, 2> b{-INFINITY, INFINITY};
  if (key == Param::kCornerRadS || key == Param::kWnRadS || key == Param::kToRadS) {
    double wlo = INFINITY, whi = 0;
    for (const PairFit* p : fitted_pairs(r, f.pairs))
      for (double w : p->w) wlo = std::min(wlo, w), whi = std::max(whi, w);
    if (!(whi > 0)) return b;
    const double widen = std::pow(10.0, r.opt.corner_decades_beyond);
    b = {wlo / widen, whi * widen};
    if (key == Param::kToRadS && f.parameters.count(Param::kFromRadS)) {
      const double from = std::abs(f.parameters.at(Param::kFromRadS));
      b = {std::max(b[0], from / r.opt.pole_shift_range),
           std::min(b[1], from * r.opt.pole_shift_range)};
    }
  } else if (key == Param::kDelayS) {
    b = {r.opt.delay_min_s, r.opt.delay_max_s};
  } else if (key == Param::kToZeta || key == Param::kZeta) {
    const auto from = f.parameters.find(Param::kFromZeta);
    const double lo = from == f.parameters.end() ? kDampingSearchMin
                                                 : std::min(kDampingSearchMin, from->second / 10);
    b = {lo, kDampingSearchMax};
  }
  return {std::min(b[0], v), std::max(b[1], v)};
}

// The free parameters of fs[group]: each finding's primary one and those of its others the data
// resolve (a moved pair's damping), scales all; each with its bounds (bounds_of).
std::vector<FreeParameter> free_parameters(const DiagnosisRun& r, const std::vector<Finding>& fs,
                                           const std::vector<size_t>& group) {
  std::vector<FreeParameter> params;
  auto add = [&](size_t i, Param key, bool log) {
    const double v = fs[i].parameters.at(key);
    const auto [lo, hi] = bounds_of(r, fs[i], key, v);
    FreeParameter p{i, key, log};
    p.lo = log ? (lo > 0 ? std::log(lo) : -INFINITY) : lo;
    p.hi = log ? std::log(hi) : hi;
    params.push_back(p);
  };
  for (size_t i : group) {
    const CauseUnit& unit = *cause_unit(fs[i].cause);
    const std::optional<Param> key = unit.primary_parameter(fs[i]).key;
    if (!key || !fs[i].parameters.count(*key)) continue;
    add(i, *key, unit.interval_domain().positive && fs[i].parameters.at(*key) > 0);
    for (const SecondaryParameter& sp : unit.secondary_parameters(fs[i]))
      if (sp.fitted && fs[i].parameters.count(sp.key) && fs[i].parameters.at(sp.key) > 0)
        add(i, sp.key, true);
  }
  return params;
}

// The weighted residuals (G_meas - G_model) / sigma over `pairs`, real and imaginary parts, of
// the simulation extended by fs with the free parameters at x; their Jacobian by forward
// differences.
class JointResiduals {
 public:
  JointResiduals(const DiagnosisRun& r, const std::vector<Finding>& fs,
                 const std::vector<FreeParameter>& params, const std::vector<const PairFit*>& pairs)
      : r_(r), fs_(fs), params_(params), pairs_(pairs) {}

  int size() const { return int(params_.size()); }

  // x with each parameter moved back inside its bounds.
  Eigen::VectorXd clamped(Eigen::VectorXd x) const {
    for (int k = 0; k < size(); ++k)
      x(k) = std::clamp(x(k), params_[size_t(k)].lo, params_[size_t(k)].hi);
    return x;
  }

  // x as fs holds it.
  Eigen::VectorXd x_of(const std::vector<Finding>& fs) const {
    Eigen::VectorXd x(size());
    for (int k = 0; k < size(); ++k) {
      const FreeParameter& p = params_[size_t(k)];
      const double v = fs[p.finding].parameters.at(p.key);
      x(k) = p.log ? std::log(v) : v;
    }
    return x;
  }

  void set(std::vector<Finding>& f, const Eigen::VectorXd& x) const {
    for (int k = 0; k < size(); ++k) {
      const FreeParameter& p = params_[size_t(k)];
      f[p.finding].parameters[p.key] = p.log ? std::exp(x(k)) : x(k);
    }
  }

  // False where a residual is not finite.
  bool residuals(const Eigen::VectorXd& x, Eigen::VectorXd* res) const {
    std::vector<Finding> moved = fs_;
    set(moved, x);
    const Model m = extended_by(r_, moved, moved.size());
    std::vector<double> v;
    for (const PairFit* p : pairs_) {
      for (size_t q = 0; q < p->w.size(); ++q) {
        const C g =
            model_pair_response(m, p->pair, p->w[q], p->amp[q], r_.opt.chain, p->ms).value_or(0.0);
        const C e = (p->meas[q] - g) / p->sig[q];
        v.push_back(e.real()), v.push_back(e.imag());
      }
    }
    *res = Eigen::Map<Eigen::VectorXd>(v.data(), Eigen::Index(v.size()));
    return res->allFinite();
  }

  // At x, where the residuals are res; a column whose step fails is zero.
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& x, const Eigen::VectorXd& res) const {
    Eigen::MatrixXd J(res.size(), size());
    for (int k = 0; k < size(); ++k) {
      Eigen::VectorXd xh = x, rh;
      const double h = 1e-6 * std::max(1.0, std::abs(x(k)));
      xh(k) += h;
      if (!residuals(xh, &rh) || rh.size() != res.size()) {
        J.col(k).setZero();
        continue;
      }
      J.col(k) = (rh - res) / h;
    }
    return J;
  }

 private:
  const DiagnosisRun& r_;
  const std::vector<Finding>& fs_;
  const std::vector<FreeParameter>& params_;
  const std::vector<const PairFit*>& pairs_;
};

// Levenberg-Marquardt from x (its residuals res, chi2 their squared norm): at most 50 steps, each
// tried with up to 10 dampings; x and res at the end, and chi2 there.
double levenberg_marquardt(const JointResiduals& p, Eigen::VectorXd& x, Eigen::VectorXd& res) {
  double chi2 = res.squaredNorm(), lambda = 1e-3;
  for (int it = 0; it < 50; ++it) {
    const Eigen::MatrixXd J = p.jacobian(x, res);
    const Eigen::MatrixXd A = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * res;
    bool accepted = false;
    for (int tries = 0; tries < 10 && !accepted; ++tries) {
      Eigen::MatrixXd Ad = A;
      Ad.diagonal() += lambda * A.diagonal().cwiseMax(1e-12);
      const Eigen::VectorXd dx = Ad.ldlt().solve(-g);
      Eigen::VectorXd rn;
      const Eigen::VectorXd xn = dx.allFinite() ? p.clamped(x + dx) : x;
      if (dx.allFinite() && p.residuals(xn, &rn) && rn.squaredNorm() < chi2) {
        x = xn, res = rn;
        const double before = chi2;
        chi2 = rn.squaredNorm();
        lambda = std::max(lambda / 10, 1e-12);
        accepted = true;
        if (before - chi2 < 1e-9 * before) it = 50;  // converged
      } else {
        lambda *= 10;
      }
    }
    if (!accepted) break;
  }
  return chi2;
}

}  // namespace

void refine(DiagnosisRun& r, std::vector<Finding>& fs, const std::vector<size_t>& group,
            const std::vector<const PairFit*>& pairs, size_t min_params, ParameterSigmas* sigmas) {
  const std::vector<FreeParameter> params = free_parameters(r, fs, group);
  if (params.empty() || params.size() < min_params) return;
  const JointResiduals p(r, fs, params, pairs);
  Eigen::VectorXd x = p.x_of(fs);
  Eigen::VectorXd res;
  if (!p.residuals(x, &res)) return;
  const double start = res.squaredNorm();
  const double chi2 = levenberg_marquardt(p, x, res);
  if (chi2 < start) p.set(fs, x);
  if (!sigmas) return;
  if (!(chi2 < start)) {  // the start stands: the Jacobian there
    x = p.x_of(fs);
    if (!p.residuals(x, &res)) return;
  }
  const Eigen::MatrixXd J = p.jacobian(x, res);
  const Eigen::MatrixXd A = J.transpose() * J;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(A);
  if (!lu.isInvertible()) return;
  const Eigen::MatrixXd cov = lu.inverse();
  // chi2 rises by `scale` at 1 sigma, as in the intervals of stage 6: chi2 per point, at least 1
  // (a point is two residuals, its real and imaginary parts).
  const double scale = std::max(1.0, res.squaredNorm() / (0.5 * double(res.size())));
  for (int k = 0; k < p.size(); ++k)
    if (cov(k, k) > 0)
      (*sigmas)[{params[size_t(k)].finding, params[size_t(k)].key}] = std::sqrt(cov(k, k) * scale);
}

bool of_the_state_model(const Finding& f) {
  return f.cause == CauseKind::kStateParameter ||
         (f.cause == CauseKind::kMissingLag && f.text_parameters.count("state")) ||
         (f.cause == CauseKind::kTimeDelay && f.text_parameters.count("delay"));
}

void joint(DiagnosisRun& r) {
  std::vector<Finding>& fs = r.findings;
  for (Finding& f : fs)
    if (of_the_state_model(f)) f.intervals.clear();  // given again below, at the values refined
  for (const std::vector<size_t>& group : groups_of(fs)) {
    if (group.size() < 2) continue;
    std::vector<const PairFit*> pairs;
    for (const std::vector<PairFit>* set : {&r.original, &r.absent})
      for (const auto& p : *set)
        for (size_t i : group)
          if (std::find(fs[i].pairs.begin(), fs[i].pairs.end(), p.pair) != fs[i].pairs.end() &&
              std::find(pairs.begin(), pairs.end(), &p) == pairs.end())
            pairs.push_back(&p);
    const bool states = std::any_of(group.begin(), group.end(),
                                    [&](size_t i) { return of_the_state_model(fs[i]); });
    ParameterSigmas sigmas;
    refine(r, fs, group, pairs, 2, states ? &sigmas : nullptr);
    for (const auto& [at, sigma] : sigmas) {
      Finding& f = fs[at.first];
      if (!of_the_state_model(f)) continue;
      const CauseUnit& unit = *cause_unit(f.cause);
      const double v = f.parameters.at(at.second);
      // As refine fitted it: a positive primary parameter, or a secondary one, in its logarithm.
      const bool log =
          at.second != unit.primary_parameter(f).key || (unit.interval_domain().positive && v > 0);
      f.intervals[at.second] =
          log ? std::array<double, 2>{v * std::exp(-sigma), v * std::exp(sigma)}
              : std::array<double, 2>{v - sigma, v + sigma};
    }
  }
}

}  // namespace fralab::diag
