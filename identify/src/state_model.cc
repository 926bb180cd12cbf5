// The state model of a transfer matrix (fralab/identify/state_model.h): rank-one factors of each
// pole cluster's residues fitted to the data, ranks grown by the criterion, realised as A, B, C, D.
#include "fralab/identify/state_model.h"

#include <cmath>
#include <functional>
#include <set>

#include "fralab/core/frd.h"
#include "fralab/core/numerics.h"
#include "fralab/core/pair_id.h"

namespace fralab {
namespace {

using Cx = std::complex<double>;

Cx location(const Root& r) {
  Cx l = r.locations()[0];
  return l.imag() < 0 ? std::conj(l) : l;
}

// The check of one path's model `g` against its curve (state_model.h, 4.).
StateModelPathCheck check_path(const std::vector<FrdPoint>& pts, const FitResult& fit,
                               const std::function<Cx(double)>& g) {
  StateModelPathCheck c;
  c.fit_status = fit.status_str();
  bool sigma = true;
  for (const auto& p : pts)
    if (p.valid && p.mag > 0) sigma = sigma && p.sigma > 0;
  std::vector<Cx> model, meas;
  double chi2 = 0, fit_chi2 = 0;
  const bool has_tf = fit.has_model();
  for (const auto& p : pts) {
    if (!p.valid || !(p.mag > 0)) continue;
    ++c.points;
    const Cx gm = g(p.w), gd = p.value();
    if (sigma) {
      chi2 += std::norm(gm - gd) / (p.sigma * p.sigma);
      fit_chi2 += std::norm((has_tf ? fit.tf.at(p.w) : Cx(0)) - gd) / (p.sigma * p.sigma);
    }
    if (sigma && p.sigma > 0.3 * p.mag) continue;
    ++c.clear;
    // A model with no response at a clear point has an unbounded log error (rms_log_error alone
    // would skip the point and read 0 for a model silent everywhere).
    c.model_silent = c.model_silent || gm == Cx(0);
    model.push_back(gm);
    meas.push_back(gd);
  }
  if (sigma && c.points > 0) {
    c.chi2_per_point = chi2 / c.points;
    c.fit_chi2_per_point = fit_chi2 / c.points;
  }
  if (c.clear > 0 && !c.model_silent) c.error = detail::rms_log_error(model, meas);
  return c;
}

}  // namespace

Cx StateModel::at(int o, int i, double w) const {
  const int n = order;
  Eigen::MatrixXcd M = Cx(0, w) * Eigen::MatrixXcd::Identity(n, n) - A.cast<Cx>();
  Cx g = D(o, i);
  if (n > 0) {
    Eigen::VectorXcd x = M.partialPivLu().solve(B.col(i).cast<Cx>());
    g += (this->C.row(o).cast<Cx>() * x)(0);
  }
  return g * std::polar(1.0, -w * delay_s(o, i));
}

namespace {

// One path's data for the weighted fit of the rank-one factors: the path's delay removed, weights
// 1/sigma (1/|G| without sigma), and at every point each cluster's 1/(s - p) and 1/(s - conj p).
struct PathData {
  int o = 0, i = 0;
  bool has_d = false;  // a biproper fit: d_oi is fitted with the factors
  std::vector<Cx> g;
  std::vector<double> wt;
  std::vector<Cx> hp, hm;  // point-major, nk per point
};

// Cluster k's term at point q for the residue r = c_ok b_ik: r/(s - p) + conj(r)/(s - conj p) for a
// pair, r/(s - p) for a real pole (r real). Real-linear in r.
Cx term(const PathData& pd, size_t q, int nk, int k, bool pair, Cx r) {
  const size_t at = q * nk + k;
  return pair ? r * pd.hp[at] + std::conj(r) * pd.hm[at] : r * pd.hp[at];
}

// The factors' components: component j is a rank-one term c_j b_j^T on cluster kc[j]'s pole (a
// cluster of residue rank r has r components).
struct Components {
  std::vector<int> kc;     // the cluster of each component
  std::vector<bool> pair;  // that cluster's pole is a pair
  int nk = 0;              // clusters (the stride of PathData::hp)
  int size() const { return int(kc.size()); }
};

// sum over the paths and points of wt^2 |g - d - sum_j term_j|^2.
double weighted_sse(const std::vector<PathData>& paths, const Components& cm,
                    const Eigen::MatrixXcd& c, const Eigen::MatrixXcd& b,
                    const Eigen::MatrixXd& D) {
  double sse = 0;
  for (const PathData& pd : paths) {
    for (size_t q = 0; q < pd.g.size(); ++q) {
      Cx v = D(pd.o, pd.i);
      for (int j = 0; j < cm.size(); ++j)
        v += term(pd, q, cm.nk, cm.kc[j], cm.pair[j], c(pd.o, j) * b(pd.i, j));
      sse += pd.wt[q] * pd.wt[q] * std::norm(pd.g[q] - v);
    }
  }
  return sse;
}

// One half-step of the alternating least squares: with b fixed, each output's c (side 0), or with c
// fixed, each input's b (side 1), with the d of its biproper paths: a linear weighted least-squares
// problem per output (input), its unknowns Re (and Im, for a pair) of each factor.
void solve_side(int side, const std::vector<PathData>& paths, const Components& cm,
                Eigen::MatrixXcd& c, Eigen::MatrixXcd& b, Eigen::MatrixXd& D) {
  const int nc = cm.size();
  Eigen::MatrixXcd& own = side == 0 ? c : b;
  const Eigen::MatrixXcd& other = side == 0 ? b : c;
  for (int e = 0; e < own.rows(); ++e) {
    std::vector<const PathData*> mine;
    for (const PathData& pd : paths)
      if ((side == 0 ? pd.o : pd.i) == e) mine.push_back(&pd);
    if (mine.empty()) continue;
    std::vector<int> col(nc);
    int nu = 0;
    for (int j = 0; j < nc; ++j) col[j] = nu, nu += cm.pair[j] ? 2 : 1;
    std::vector<int> dcol(mine.size(), -1);
    size_t rows = 0;
    for (size_t j = 0; j < mine.size(); ++j) {
      if (mine[j]->has_d) dcol[j] = nu++;
      rows += 2 * mine[j]->g.size();
    }
    // Nothing to solve for (no pole in the model, no biproper path here): a decomposition of an
    // empty matrix is undefined (Eigen's pivoting reads the maximum of no column norms).
    if (nu == 0 || rows == 0) continue;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, nu);
    Eigen::VectorXd y(rows);
    size_t r0 = 0;
    for (size_t j = 0; j < mine.size(); ++j) {
      const PathData& pd = *mine[j];
      const size_t np = pd.g.size();
      const int oe = side == 0 ? pd.i : pd.o;  // the other factor's row
      for (size_t q = 0; q < np; ++q) {
        auto put = [&](int cc, Cx v) {
          A(r0 + q, cc) = pd.wt[q] * v.real();
          A(r0 + np + q, cc) = pd.wt[q] * v.imag();
        };
        for (int k = 0; k < nc; ++k) {
          put(col[k], term(pd, q, cm.nk, cm.kc[k], cm.pair[k], other(oe, k)));  // d/d Re(own)
          if (cm.pair[k])
            put(col[k] + 1, term(pd, q, cm.nk, cm.kc[k], true, Cx(0, 1) * other(oe, k)));
        }
        if (dcol[j] >= 0) put(dcol[j], 1.0);
        y(r0 + q) = pd.wt[q] * pd.g[q].real();
        y(r0 + np + q) = pd.wt[q] * pd.g[q].imag();
      }
      r0 += 2 * np;
    }
    // Columns scaled to unit norm, then the minimum-norm solution: a factor the data do not
    // determine stays 0.
    Eigen::VectorXd scale = A.colwise().norm().transpose();
    for (int j = 0; j < nu; ++j) scale(j) = scale(j) > 0 ? 1.0 / scale(j) : 0.0;
    // The threshold is set before the decomposition: its Z part is built for the rank seen then,
    // and a threshold changed afterwards makes solve() read Z coefficients never computed.
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
    cod.setThreshold(1e-10);
    cod.compute(A * scale.asDiagonal());
    const Eigen::VectorXd x = scale.asDiagonal() * cod.solve(y);
    for (int k = 0; k < nc; ++k)
      own(e, k) = cm.pair[k] ? Cx(x(col[k]), x(col[k] + 1)) : Cx(x(col[k]));
    for (size_t j = 0; j < mine.size(); ++j)
      if (dcol[j] >= 0) D(mine[j]->o, mine[j]->i) = x(dcol[j]);
  }
}

// The factors fitted to the data by alternating weighted least squares (each half-step an exact
// minimum, so the misfit never rises), each sweep extrapolated along its step while that lowers
// the misfit further (alternating least squares crawls along flat valleys). Returns the misfit;
// *sweeps: the sweeps taken.
double fit_factors(const std::vector<PathData>& paths, const Components& cm,
                   const StateModelOptions& opt, Eigen::MatrixXcd& c, Eigen::MatrixXcd& b,
                   Eigen::MatrixXd& D, int* sweeps) {
  double sse = weighted_sse(paths, cm, c, b, D);
  for (*sweeps = 0; *sweeps < opt.max_sweeps && sse > 0; ++*sweeps) {
    Eigen::MatrixXcd c1 = c, b1 = b;
    Eigen::MatrixXd D1 = D;
    solve_side(0, paths, cm, c1, b1, D1);
    solve_side(1, paths, cm, c1, b1, D1);
    double next = weighted_sse(paths, cm, c1, b1, D1);
    if (!(next <= sse)) break;
    for (double a = 2; a <= 64; a *= 2) {  // the sweep's step, doubled while it helps
      Eigen::MatrixXcd c2 = c + a * (c1 - c), b2 = b + a * (b1 - b);
      Eigen::MatrixXd D2 = D + a * (D1 - D);
      const double e = weighted_sse(paths, cm, c2, b2, D2);
      if (!(e < next)) break;
      c1 = c2, b1 = b2, D1 = D2, next = e;
    }
    const double gain = sse - next;
    c = c1, b = b1, D = D1, sse = next;
    if (gain <= opt.rel_tol * next) {
      ++*sweeps;  // this sweep was taken
      break;
    }
  }
  return sse;
}

// Weighted linear least squares of `target` (at pd's points) on d (with_d) and the residues of the
// clusters ks: min sum wt^2 |target - d - sum_k term_k(r_k)|^2, unknowns d, then Re (and Im, for a
// pair) of each r_k in ks's order. *fitted: |W A x|, the root of the chi2 the fit removes.
Eigen::VectorXd residue_fit(const PathData& pd, int nk, const std::vector<int>& ks,
                            const std::vector<bool>& pair, bool with_d,
                            const std::vector<Cx>& target, double* fitted = nullptr) {
  int nu = with_d ? 1 : 0;
  for (int k : ks) nu += pair[k] ? 2 : 1;
  const size_t np = pd.g.size();
  if (nu == 0 || np == 0) {  // nothing to fit (see solve_side)
    if (fitted) *fitted = 0;
    return Eigen::VectorXd::Zero(nu);
  }
  Eigen::MatrixXd A(2 * np, nu);
  Eigen::VectorXd y(2 * np);
  for (size_t q = 0; q < np; ++q) {
    int c = 0;
    auto put = [&](Cx v) {
      A(q, c) = pd.wt[q] * v.real();
      A(np + q, c) = pd.wt[q] * v.imag();
      ++c;
    };
    if (with_d) put(1.0);
    for (int k : ks) {
      put(term(pd, q, nk, k, pair[k], 1.0));
      if (pair[k]) put(term(pd, q, nk, k, true, Cx(0, 1)));
    }
    y(q) = pd.wt[q] * target[q].real();
    y(np + q) = pd.wt[q] * target[q].imag();
  }
  Eigen::VectorXd x = A.colPivHouseholderQr().solve(y);
  if (fitted) *fitted = (A * x).norm();
  return x;
}

// The start of one more component on cluster k: each path's residue on k refitted to what the
// model leaves of its data (weighted least squares, one residue per path), entered in a matrix
// with its phase and, as its size, the root of the chi2 it would remove (dimensionless: the
// outputs' units differ by orders of magnitude, and the paths the model misses most lead); its
// first right singular vector is b'. c' is then solved by the fit's first half-step (from 0).
Eigen::VectorXcd residual_direction(const std::vector<PathData>& paths, const Components& cm, int k,
                                    const std::vector<bool>& pair, const Eigen::MatrixXcd& c,
                                    const Eigen::MatrixXcd& b, const Eigen::MatrixXd& D, int no,
                                    int ni) {
  Eigen::MatrixXcd E = Eigen::MatrixXcd::Zero(no, ni);
  for (const PathData& pd : paths) {
    std::vector<Cx> e(pd.g.size());  // what the model leaves of the data
    for (size_t q = 0; q < pd.g.size(); ++q) {
      Cx v = D(pd.o, pd.i);
      for (int j = 0; j < cm.size(); ++j)
        v += term(pd, q, cm.nk, cm.kc[j], cm.pair[j], c(pd.o, j) * b(pd.i, j));
      e[q] = pd.g[q] - v;
    }
    double fitted = 0;
    const Eigen::VectorXd x = residue_fit(pd, cm.nk, {k}, pair, false, e, &fitted);
    const Cx r = pair[k] ? Cx(x(0), x(1)) : Cx(x(0));
    // Its phase, and as its size the root of the chi2 that residue alone would remove.
    if (std::abs(r) > 0) E(pd.o, pd.i) = r / std::abs(r) * fitted;
  }
  if (!pair[k]) {  // a real pole's factors are real
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(E.real(), Eigen::ComputeThinV);
    return svd.matrixV().col(0).cast<Cx>();
  }
  Eigen::JacobiSVD<Eigen::MatrixXcd> svd(E, Eigen::ComputeThinV);
  return svd.matrixV().col(0).conjugate();
}

// build_state_model's steps, in order: the paths' data and their own residues, the rank-one
// factors' start and fit, Gilbert's ranks, the factors balanced, the realisation, the check.
class StateModelBuilder {
 public:
  StateModelBuilder(const TransferMatrix& m,
                    const std::map<std::string, std::vector<FrdPoint>>& data,
                    const StateModelOptions& opt)
      : m_(m),
        data_(data),
        opt_(opt),
        no_(int(m.outputs.size())),
        ni_(int(m.inputs.size())),
        nk_(int(m.clusters.size())) {
    s_.inputs = m.inputs;
    s_.outputs = m.outputs;
    s_.delay_s = Eigen::MatrixXd::Zero(no_, ni_);
    s_.D = Eigen::MatrixXd::Zero(no_, ni_);
    pair_.resize(nk_);
    pole_.resize(nk_);
    for (int k = 0; k < nk_; ++k)
      pair_[k] = m.clusters[k].mean.pair, pole_[k] = location(m.clusters[k].mean);
    R_.assign(nk_, Eigen::MatrixXcd::Zero(no_, ni_));
  }

  StateModel build() {
    for (int o = 0; o < no_; ++o)
      for (int i = 0; i < ni_; ++i) add_path(o, i);
    start_factors();
    // ... then fitted to the data themselves (fit_factors).
    cm_.nk = nk_;
    for (int k = 0; k < nk_; ++k) cm_.kc.push_back(k), cm_.pair.push_back(pair_[k]);
    s_.start_chi2 = weighted_sse(paths_, cm_, c_, b_, s_.D);
    s_.fit_chi2 = fit_factors(paths_, cm_, opt_, c_, b_, s_.D, &s_.sweeps);
    grow_ranks();
    balance_factors();
    realise();
    check_against_data();
    return s_;
  }

 private:
  // Path o, i's data for the factors, its delay, and the residues of its own clusters, alone (the
  // start of the factors' fit); nothing where it is not measured or its fit failed.
  void add_path(int o, int i) {
    auto it = m_.fits.find({m_.outputs[o], m_.inputs[i]});
    const std::string key = m_.inputs[i] + ":" + m_.outputs[o];
    auto dit = data_.find(key);
    if (it == m_.fits.end() || dit == data_.end()) return;
    const FitResult& fit = it->second;
    std::vector<FrdPoint> pts;
    bool sigma = true;
    for (const auto& p : dit->second) {
      if (!p.valid || !(p.mag > 0)) continue;
      pts.push_back(p);
      sigma = sigma && p.sigma > 0;
    }
    const bool converged = fit.status == FitResult::Status::kConverged;
    // The factors are fitted to every measured path but failed fits: the rank-one products put
    // response into every path, so a path left out is predicted by factors nothing holds there
    // (on the J85 lab's run, 1e22 chi2 per point on the P5 paths that reached the maximum
    // order). A path with no response is fitted too (its data, noise, by its sigma).
    const bool mor = fit.has_model() && !converged;
    const bool zero = fit.status == FitResult::Status::kNoResponse && sigma;
    if (pts.empty() || !(converged || mor || zero)) return;
    all_sigma_ = all_sigma_ && sigma;
    const Tf& tf = fit.tf;
    if (converged || mor) s_.delay_s(o, i) = tf.delay_s;
    PathData pd;
    pd.o = o;
    pd.i = i;
    pd.has_d = converged && tf.num_order() >= tf.den_order();
    for (const FrdPoint& p : pts) {
      const Cx sj(0, p.w);
      pd.g.push_back(p.value() * std::polar(1.0, p.w * s_.delay_s(o, i)));  // delay removed
      pd.wt.push_back(p.sigma > 0 ? 1.0 / p.sigma : 1.0 / p.mag);
      for (int k = 0; k < nk_; ++k) {
        pd.hp.push_back(1.0 / (sj - pole_[k]));
        pd.hm.push_back(1.0 / (sj - std::conj(pole_[k])));
      }
    }
    paths_.push_back(pd);
    if (!converged) return;
    const std::vector<int> ks = own_clusters(key, tf);
    if (ks.empty() && !pd.has_d) return;
    const Eigen::VectorXd x = residue_fit(pd, nk_, ks, pair_, pd.has_d, pd.g);
    int c = 0;
    if (pd.has_d) s_.D(o, i) = x(c++);
    for (int k : ks) {
      R_[k](o, i) = pair_[k] ? Cx(x(c), x(c + 1)) : Cx(x(c));
      c += pair_[k] ? 2 : 1;
    }
  }

  // A path's own clusters: those nearest its fit's poles, or with one pole set those it is a
  // member of.
  std::vector<int> own_clusters(const std::string& key, const Tf& tf) const {
    std::vector<int> ks;
    if (m_.from_pole_set) {
      for (int k = 0; k < nk_; ++k) {
        const auto& mem = m_.clusters[size_t(k)].pairs;
        if (std::find(mem.begin(), mem.end(), key) != mem.end()) ks.push_back(k);
      }
    }
    for (const Root& p : m_.from_pole_set ? std::vector<Root>{} : tf.poles) {
      int best = -1;
      double bd = INFINITY;
      for (int k = 0; k < nk_; ++k) {
        if (pair_[k] != p.pair) continue;
        double d = std::abs(pole_[k] - location(p));
        if (d < bd) bd = d, best = k;
      }
      if (best >= 0 && std::find(ks.begin(), ks.end(), best) == ks.end()) ks.push_back(best);
    }
    return ks;
  }

  // The rank-one factors R_k ~ c_k b_k^T: the SVD's (real ones for a real pole) as the start.
  void start_factors() {
    c_ = Eigen::MatrixXcd::Zero(no_, nk_);
    b_ = Eigen::MatrixXcd::Zero(ni_, nk_);
    for (int k = 0; k < nk_; ++k) {
      Eigen::JacobiSVD<Eigen::MatrixXcd> svd(R_[k], Eigen::ComputeThinU | Eigen::ComputeThinV);
      const auto sv = svd.singularValues();
      const double total = sv.squaredNorm();
      s_.rank1_loss.push_back(total > 0 ? 1.0 - sv(0) * sv(0) / total : 0.0);
      if (pair_[k]) {
        c_.col(k) = svd.matrixU().col(0) * std::sqrt(sv(0));
        b_.col(k) = svd.matrixV().col(0).conjugate() * std::sqrt(sv(0));
      } else {
        Eigen::JacobiSVD<Eigen::MatrixXd> rs(R_[k].real(),
                                             Eigen::ComputeThinU | Eigen::ComputeThinV);
        const double s1 = rs.singularValues()(0);
        c_.col(k) = (rs.matrixU().col(0) * std::sqrt(s1)).cast<Cx>();
        b_.col(k) = (rs.matrixV().col(0) * std::sqrt(s1)).cast<Cx>();
      }
    }
  }

  // Gilbert's realisation: a cluster whose residues the data show are not rank one gets one more
  // component (its pole's states once more) while that lowers the criterion, the misfit plus
  // ln(2N) per real parameter the component adds (as the order search's; with sigma on every
  // path the misfit is chi2, else the unknown-variance form 2N ln(sse / 2N), the sse floored at
  // 1e-18 of the data's weighted energy so that noise-free data do not buy rounding).
  void grow_ranks() {
    s_.rank.assign(nk_, 1);
    for (int k = 0; k < nk_; ++k) s_.poles.push_back(m_.clusters[k].mean);
    std::set<int> outs_used, ins_used;
    size_t n_points = 0;
    double energy = 0;
    for (const PathData& pd : paths_) {
      outs_used.insert(pd.o), ins_used.insert(pd.i), n_points += pd.g.size();
      for (size_t q = 0; q < pd.g.size(); ++q) energy += pd.wt[q] * pd.wt[q] * std::norm(pd.g[q]);
    }
    const double nr = 2.0 * double(n_points), per_param = std::log(std::max(nr, 2.0));
    auto criterion = [&](double sse) {
      return all_sigma_ ? sse : nr * std::log(std::max(sse, 1e-18 * energy) / nr);
    };
    const std::vector<int> cap = rank_caps();
    // Each candidate is tried with a few sweeps from the current factors, against the current
    // factors given the same sweeps: alternating least squares creeps on along flat valleys for
    // hundreds of sweeps, and a candidate given more sweeps than the model it is compared with
    // would be credited with the creep (the J85 test: 100-300 in chi2 for components the data do
    // not need).
    StateModelOptions trial = opt_;
    trial.max_sweeps = std::min(opt_.max_sweeps, opt_.rank_trial_sweeps);
    while (opt_.max_sweeps > 0) {
      Eigen::MatrixXcd c0 = c_, b0 = b_;
      Eigen::MatrixXd D0 = s_.D;
      int sweeps0 = 0;
      const double crit0 = criterion(fit_factors(paths_, cm_, trial, c0, b0, D0, &sweeps0));
      int best = -1;
      double best_crit = crit0;
      Eigen::MatrixXcd best_c, best_b;
      Eigen::MatrixXd best_D;
      for (int k = 0; k < nk_; ++k) {
        if (s_.rank[k] >= cap[k]) continue;
        Components cm2 = cm_;
        cm2.kc.push_back(k), cm2.pair.push_back(pair_[k]);
        Eigen::MatrixXcd c2(no_, cm2.size()), b2(ni_, cm2.size());
        c2 << c_, Eigen::VectorXcd::Zero(no_);
        b2 << b_, residual_direction(paths_, cm_, k, pair_, c_, b_, s_.D, no_, ni_);
        Eigen::MatrixXd D2 = s_.D;
        int sweeps = 0;
        const double sse = fit_factors(paths_, cm2, trial, c2, b2, D2, &sweeps);
        const double added =
            (int(outs_used.size()) + int(ins_used.size()) - 1) * (pair_[k] ? 2 : 1);
        const double cr = criterion(sse) + per_param * added;
        if (cr < best_crit) best = k, best_crit = cr, best_c = c2, best_b = b2, best_D = D2;
      }
      if (best < 0) break;
      cm_.kc.push_back(best), cm_.pair.push_back(pair_[best]);
      c_ = best_c, b_ = best_b, s_.D = best_D;
      int sweeps = 0;
      s_.fit_chi2 = fit_factors(paths_, cm_, opt_, c_, b_, s_.D, &sweeps);
      s_.sweeps += sweeps;
      ++s_.rank[best];
    }
  }

  // A cluster's rank at most: its members' outputs and inputs, and the options' maximum.
  std::vector<int> rank_caps() const {
    std::vector<int> cap(nk_, 1);
    for (int k = 0; k < nk_; ++k) {
      std::set<std::string> mo, mi;
      for (const std::string& key : m_.clusters[k].pairs) {
        const PairId id = PairId::parse(key);
        mi.insert(id.input), mo.insert(id.output);
      }
      cap[k] = std::min({int(mo.size()), int(mi.size()), opt_.max_rank});
    }
    return cap;
  }

  // Each factor pair scaled to equal norms (the product is what the data fix). Where nb / nc
  // under- or overflows (factors of 1e-160 and 1e160, as data in units of 1e-20 weighted by their
  // sigma make them), the factor is the quotient of the roots.
  void balance_factors() {
    for (int j = 0; j < cm_.size(); ++j) {
      const double nc = c_.col(j).norm(), nb = b_.col(j).norm();
      double a = std::sqrt(nb / nc);
      if (!(std::isfinite(a) && a > 0)) a = std::sqrt(nb) / std::sqrt(nc);
      if (std::isfinite(a) && a > 0) {
        c_.col(j) *= a;
        b_.col(j) /= a;
      }
    }
  }

  // States: one per real component, two per pair's.
  void realise() {
    for (int j = 0; j < cm_.size(); ++j) s_.order += pair_[cm_.kc[j]] ? 2 : 1;
    s_.A = Eigen::MatrixXd::Zero(s_.order, s_.order);
    s_.B = Eigen::MatrixXd::Zero(s_.order, ni_);
    s_.C = Eigen::MatrixXd::Zero(no_, s_.order);
    int x0 = 0;
    for (int j = 0; j < cm_.size(); ++j) {
      const Cx p = pole_[cm_.kc[j]];
      if (!cm_.pair[j]) {
        s_.A(x0, x0) = p.real();
        s_.B.row(x0) = b_.col(j).real().transpose();
        s_.C.col(x0) = c_.col(j).real();
        x0 += 1;
      } else {
        // z' = p z + b^T u, y = 2 Re(c z): with z = x1 + j x2, x' = [[s, -w], [w, s]] x + [Re b;
        // Im b] u, y = 2 (Re c) x1 - 2 (Im c) x2.
        s_.A(x0, x0) = p.real();
        s_.A(x0, x0 + 1) = -p.imag();
        s_.A(x0 + 1, x0) = p.imag();
        s_.A(x0 + 1, x0 + 1) = p.real();
        s_.B.row(x0) = b_.col(j).real().transpose();
        s_.B.row(x0 + 1) = b_.col(j).imag().transpose();
        s_.C.col(x0) = 2 * c_.col(j).real();
        s_.C.col(x0 + 1) = -2 * c_.col(j).imag();
        x0 += 2;
      }
    }
  }

  // The model checked against the data, path by path; the error over the converged fits' paths.
  void check_against_data() {
    double sum = 0;
    int n = 0;
    for (int o = 0; o < no_; ++o) {
      for (int i = 0; i < ni_; ++i) {
        const std::string key = m_.inputs[i] + ":" + m_.outputs[o];
        auto dit = data_.find(key);
        auto fit = m_.fits.find({m_.outputs[o], m_.inputs[i]});
        if (dit == data_.end() || fit == m_.fits.end()) continue;
        const StateModelPathCheck c =
            check_path(dit->second, fit->second, [&](double w) { return s_.at(o, i, w); });
        s_.path_check[key] = c;
        if (c.error < 0) continue;
        s_.path_error[key] = c.error;
        if (fit->second.status != FitResult::Status::kConverged) continue;
        sum += c.error * c.error;
        ++n;
      }
    }
    s_.error = n ? std::sqrt(sum / n) : 0.0;
  }

  const TransferMatrix& m_;
  const std::map<std::string, std::vector<FrdPoint>>& data_;
  const StateModelOptions& opt_;
  const int no_, ni_, nk_;
  StateModel s_;
  std::vector<bool> pair_;           // each cluster's pole is a pair
  std::vector<Cx> pole_;             // each cluster's pole (upper half plane)
  std::vector<Eigen::MatrixXcd> R_;  // residues per cluster
  std::vector<PathData> paths_;      // the data the factors are fitted to
  bool all_sigma_ = true;            // every one of them with its sigma
  Components cm_;
  Eigen::MatrixXcd c_, b_;  // the factors, a column per component
};

}  // namespace

StateModel build_state_model(const TransferMatrix& m,
                             const std::map<std::string, std::vector<FrdPoint>>& data,
                             const StateModelOptions& opt) {
  opt.validate();
  return StateModelBuilder(m, data, opt).build();
}

}  // namespace fralab
