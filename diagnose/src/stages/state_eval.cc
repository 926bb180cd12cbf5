// The state model's responses at the prepared pairs' points (state_eval.h).
#include "state_eval.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "fralab/core/pair_id.h"

namespace fralab::diag {
namespace {

// The entries `moved` sets at values moved_v, in e and v: a named parameter as the entries it sets
// (their moves add: no set holds two that overlap), each valued as it sets it; the added lags and
// delays as they are.
void expand_named(const StateSpace& sim, const std::vector<StateEntry>& moved,
                  const std::vector<double>& moved_v, std::vector<StateEntry>& e,
                  std::vector<double>& v) {
  for (size_t k = 0; k < moved.size(); ++k) {
    if (!moved[k].named()) {
      e.push_back(moved[k]), v.push_back(moved_v[k]);
      continue;
    }
    const NamedParameter& np = sim.parameters[size_t(moved[k].row)];
    for (const NamedParameter::Entry& x : np.entries) {
      e.push_back({x.matrix, x.row, x.col});
      v.push_back(entry_value(sim, e.back()) *
                  (x.inverse ? np.value / moved_v[k] : moved_v[k] / np.value));
    }
  }
}

}  // namespace

StateEval::StateEval(const DiagnosisRun& r, const StateSpace& sim, const Paths& sim_paths)
    : r_(r), sim_(sim) {
  std::map<double, size_t> index;
  at_.resize(r.pairs.size());
  for (size_t k = 0; k < r.pairs.size(); ++k) {
    const PairFit& p = r.pairs[k];
    const PairId id = PairId::parse(p.pair);
    if (id.actuator()) continue;
    const auto oi = std::find(sim.outputs.begin(), sim.outputs.end(), id.output);
    const auto ii = std::find(sim.inputs.begin(), sim.inputs.end(), id.input);
    if (oi == sim.outputs.end() || ii == sim.inputs.end()) continue;
    const size_t i = size_t(oi - sim.outputs.begin()), j = size_t(ii - sim.inputs.begin());
    if (!sim_paths[i][j]) continue;
    at_[k].path = {Eigen::Index(i), Eigen::Index(j)};
    for (double w : p.w) {
      const auto it = index.emplace(w, w_.size()).first;
      if (it->second == w_.size()) w_.push_back(w);
      at_[k].w.push_back(it->second);
    }
  }
  for (const PairFit& p : r.pairs) points_ += p.w.size();
  ok_ = responses(sim, &g_sim_) && resolvent();
}

bool StateEval::responses(const StateSpace& ss, std::vector<Eigen::MatrixXcd>* g) const {
  if (!stable(ss)) return false;
  g->resize(w_.size());
  auto added = [](const std::vector<double>& d, const std::vector<double>& d0, size_t k) {
    return (k < d.size() ? d[k] : 0.0) - (k < d0.size() ? d0[k] : 0.0);
  };
  for (size_t q = 0; q < w_.size(); ++q) {
    Eigen::MatrixXcd& gq = (*g)[q] = state_space_response(ss, C(0, w_[q]));
    for (Eigen::Index j = 0; j < gq.cols(); ++j)
      if (const double t = added(ss.input_delay_s, sim_.input_delay_s, size_t(j)); t != 0)
        gq.col(j) *= std::exp(C(0, -w_[q] * t));
    for (Eigen::Index i = 0; i < gq.rows(); ++i)
      if (const double t = added(ss.output_delay_s, sim_.output_delay_s, size_t(i)); t != 0)
        gq.row(i) *= std::exp(C(0, -w_[q] * t));
  }
  return true;
}

std::vector<Eigen::MatrixXcd> StateEval::moved_responses(const std::vector<StateEntry>& moved,
                                                         const std::vector<double>& moved_v) const {
  std::vector<StateEntry> e;
  std::vector<double> v;
  expand_named(sim_, moved, moved_v, e, v);
  std::vector<int> a;
  std::vector<double> delta(e.size());
  for (size_t k = 0; k < e.size(); ++k) {
    delta[k] = v[k] - entry_value(sim_, e[k]);
    if (e[k].matrix == 'A') a.push_back(int(k));
  }
  const Eigen::Index ka = Eigen::Index(a.size()), p = sim_.C.rows(), m = sim_.B.cols();
  std::vector<Eigen::MatrixXcd> g = G_;
  std::vector<C> post_col(e.size(), C(1, 0)), post_row(e.size(), C(1, 0));
  for (size_t q = 0; q < g.size(); ++q) {
    const Eigen::MatrixXcd &R = R_[q], &X = X_[q], &Y = Y_[q];
    // (C' R)(:, r) and (R B')(c, :).
    auto cr = [&](int r) {
      Eigen::VectorXcd col = X.col(r);
      for (size_t k = 0; k < e.size(); ++k)
        if (e[k].matrix == 'C') col(e[k].row) += delta[k] * R(e[k].col, r);
      return col;
    };
    auto rb = [&](int c) {
      Eigen::RowVectorXcd row = Y.row(c);
      for (size_t k = 0; k < e.size(); ++k)
        if (e[k].matrix == 'B') row(e[k].col) += delta[k] * R(c, e[k].row);
      return row;
    };
    for (size_t k = 0; k < e.size(); ++k) {
      if (e[k].matrix == 'B') g[q].col(e[k].col) += delta[k] * X.col(e[k].row);
      if (e[k].matrix == 'C') g[q].row(e[k].row) += delta[k] * Y.row(e[k].col);
      if (e[k].matrix == 'D') g[q](e[k].row, e[k].col) += delta[k];
    }
    for (size_t k = 0; k < e.size(); ++k)
      for (size_t l = 0; l < e.size(); ++l)
        if (e[k].matrix == 'C' && e[l].matrix == 'B')
          g[q](e[k].row, e[l].col) += delta[k] * delta[l] * R(e[k].col, e[l].row);
    for (size_t k = 0; k < e.size(); ++k) {
      if (!e[k].added() || !(v[k] > 0)) continue;
      const C f = e[k].lag() ? 1.0 / C(1.0, w_[q] * v[k]) : std::exp(C(0, -w_[q] * v[k]));
      (e[k].at_input() ? post_col : post_row)[k] = f;
    }
    if (ka == 0) {
      apply_lags(g[q], e, post_col, post_row);
      continue;
    }
    if (ka == 1) {  // one entry of A: Sherman-Morrison
      const StateEntry& ex = e[size_t(a[0])];
      const double d = delta[size_t(a[0])];
      g[q].noalias() += (d / (1.0 - d * R(ex.col, ex.row))) * cr(ex.row) * rb(ex.col);
      apply_lags(g[q], e, post_col, post_row);
      continue;
    }
    Eigen::MatrixXcd P(p, ka), Q(ka, m), S(ka, ka);
    for (Eigen::Index x = 0; x < ka; ++x) {
      const StateEntry& ex = e[size_t(a[size_t(x)])];
      P.col(x) = cr(ex.row) * delta[size_t(a[size_t(x)])];
      Q.row(x) = rb(ex.col);
      for (Eigen::Index y = 0; y < ka; ++y) {
        const StateEntry& ey = e[size_t(a[size_t(y)])];
        S(x, y) = (x == y ? 1.0 : 0.0) - R(ex.col, ey.row) * delta[size_t(a[size_t(y)])];
      }
    }
    g[q] += P * S.partialPivLu().solve(Q);
    apply_lags(g[q], e, post_col, post_row);
  }
  return g;
}

void StateEval::apply_lags(Eigen::MatrixXcd& g, const std::vector<StateEntry>& e,
                           const std::vector<C>& post_col, const std::vector<C>& post_row) {
  for (size_t k = 0; k < e.size(); ++k) {
    if (!e[k].added()) continue;
    if (e[k].at_input())
      g.col(e[k].col) *= post_col[k];
    else
      g.row(e[k].row) *= post_row[k];
  }
}

bool StateEval::stable(const StateSpace& ss) {
  if (ss.A.rows() == 0 || !ss.A.allFinite()) return false;
  const Eigen::EigenSolver<Eigen::MatrixXd> es(ss.A, false);
  return es.info() == Eigen::Success && es.eigenvalues().real().maxCoeff() < 0;
}

std::vector<std::vector<C>> StateEval::ratio(const StateSpace& ss) const {
  std::vector<Eigen::MatrixXcd> g;
  if (!responses(ss, &g)) return {};
  return ratio_of(g);
}

std::vector<std::vector<C>> StateEval::ratio_of(const std::vector<Eigen::MatrixXcd>& g) const {
  std::vector<std::vector<C>> F(r_.pairs.size());
  for (size_t k = 0; k < r_.pairs.size(); ++k) {
    F[k].assign(r_.pairs[k].w.size(), C(1, 0));
    const auto [i, j] = at_[k].path;
    if (i < 0) continue;
    for (size_t q = 0; q < F[k].size(); ++q) {
      const C s = g_sim_[at_[k].w[q]](i, j);
      if (s != C(0, 0)) F[k][q] = g[at_[k].w[q]](i, j) / s;
    }
  }
  return F;
}

bool StateEval::residuals(const StateSpace& ss, Eigen::VectorXd* res) const {
  const auto F = ratio(ss);
  if (F.empty()) return false;
  residuals_of(F, res);
  return true;
}

void StateEval::residuals_moved(const std::vector<StateEntry>& e, const std::vector<double>& v,
                                Eigen::VectorXd* res) const {
  residuals_of(ratio_of(moved_responses(e, v)), res);
}

void StateEval::residuals_of(const std::vector<std::vector<C>>& F, Eigen::VectorXd* res) const {
  res->resize(Eigen::Index(2 * points()));
  Eigen::Index m = 0;
  for (size_t k = 0; k < r_.pairs.size(); ++k) {
    const PairFit& p = r_.pairs[k];
    for (size_t q = 0; q < p.w.size(); ++q) {
      const C model = p.sim[q] * p.factor[q] * F[k][q];
      const C e = model != C(0, 0) && p.meas[q] != C(0, 0)
                      ? std::log(p.meas[q] / model) * (std::abs(p.meas[q]) / p.sig[q])
                      : (p.meas[q] - model) / p.sig[q];
      (*res)(m++) = e.real(), (*res)(m++) = e.imag();
    }
  }
}

double StateEval::chi2(const StateSpace& ss) const {
  Eigen::VectorXd res;
  return residuals(ss, &res) ? res.squaredNorm() : INFINITY;
}

std::pair<double, double> StateEval::band() const {
  return {*std::min_element(w_.begin(), w_.end()), *std::max_element(w_.begin(), w_.end())};
}

bool StateEval::resolvent() {
  const Eigen::Index n = sim_.A.rows();
  for (auto* v : {&R_, &X_, &Y_, &G_}) v->resize(w_.size());
  for (size_t q = 0; q < w_.size(); ++q) {
    const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(C(0, w_[q]) * Eigen::MatrixXcd::Identity(n, n) -
                                                   sim_.A.cast<C>());
    R_[q] = lu.inverse();
    X_[q] = sim_.C.cast<C>() * R_[q];
    Y_[q] = R_[q] * sim_.B.cast<C>();
    G_[q] = X_[q] * sim_.B.cast<C>() + sim_.D.cast<C>();
    if (!R_[q].allFinite()) return false;
  }
  return true;
}

}  // namespace fralab::diag
