#include "random_state.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "exact_measurement.h"
#include "fralab/core/error.h"
#include "fralab/plant/state_space.h"

namespace fralab::testing {
namespace {

using C = std::complex<double>;

Json document(const StateSpace& ss, const std::string& name) {
  Json d = state_space_document(ss, name);
  for (Json& in : d["inputs"]) in["full_scale"] = 10.0;
  return d;
}

bool stable(const Eigen::MatrixXd& A) {
  const Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
  for (Eigen::Index k = 0; k < A.rows(); ++k)
    if (!(es.eigenvalues()(k).real() < -1e-3)) return false;
  return true;
}

// A hidden effect at input (at_input) or output `name`, its parameter to be found within 2 %.
HiddenEffect channel_effect(CauseKind cause, bool at_input, const std::string& name, Param param,
                            double value) {
  HiddenEffect e;
  e.cause = cause;
  e.scope = at_input ? Scope::kInput : Scope::kOutput;
  (at_input ? e.input : e.output) = name;
  e.param = param;
  e.value = value;
  e.tol_rel = 0.02;
  return e;
}

// ss with a first-order lag of corner p (rad/s) before input k (before) or after output k: a new
// last state x' = p (u_k - x) driving what u_k drove, or x' = p (y_k - x) read as y_k.
StateSpace with_lag(const StateSpace& ss, bool before, int k, double p) {
  const Eigen::Index n = ss.A.rows(), m = ss.B.cols(), q = ss.C.rows();
  StateSpace out = ss;
  out.A = Eigen::MatrixXd::Zero(n + 1, n + 1);
  out.A.topLeftCorner(n, n) = ss.A;
  out.A(n, n) = -p;
  out.B = Eigen::MatrixXd::Zero(n + 1, m);
  out.B.topRows(n) = ss.B;
  out.C = Eigen::MatrixXd::Zero(q, n + 1);
  out.C.leftCols(n) = ss.C;
  if (before) {
    out.A.block(0, n, n, 1) = ss.B.col(k);
    out.B.block(0, k, n, 1).setZero();
    out.B(n, k) = p;
    out.C.col(n) = ss.D.col(k);
    out.D.col(k).setZero();
  } else {
    out.A.block(n, 0, 1, n) = p * ss.C.row(k);
    out.B.row(n) = p * ss.D.row(k);
    out.C.row(k).setZero();
    out.C(k, n) = 1;
    out.D.row(k).setZero();
  }
  out.states.push_back("L" + std::to_string(k + 1));
  return out;
}

// state_measurement's grid, rad/s: a decade beyond the simulation's modes each side, 10 a decade.
std::vector<double> state_grid(const StateSpace& sim) {
  const Eigen::EigenSolver<Eigen::MatrixXd> es(sim.A, false);
  double lo = INFINITY, hi = 0;
  for (Eigen::Index k = 0; k < sim.A.rows(); ++k) {
    lo = std::min(lo, std::abs(es.eigenvalues()(k)));
    hi = std::max(hi, std::abs(es.eigenvalues()(k)));
  }
  lo /= 10, hi *= 10;
  const int n = int(std::ceil(10 * std::log10(hi / lo))) + 1;
  std::vector<double> w;
  for (int j = 0; j < n; ++j) w.push_back(lo * std::pow(hi / lo, double(j) / (n - 1)));
  return w;
}

}  // namespace

RandomCase random_state_case(uint64_t seed, int index, int n_hidden) {
  std::mt19937_64 g(seed * 2000003u + uint64_t(index) * 7u + 3u);
  std::uniform_real_distribution<double> u(0, 1);
  auto logu = [&](double lo, double hi) { return lo * std::pow(hi / lo, u(g)); };
  const int n = 2 + int(g() % 11), ni = 1 + int(g() % 3), no = 2 + int(g() % 4);
  StateSpace ss;
  for (int k = 0; k < n; ++k) ss.states.push_back("S" + std::to_string(k + 1));
  for (int k = 0; k < ni; ++k) ss.inputs.push_back("U" + std::to_string(k + 1));
  for (int k = 0; k < no; ++k) ss.outputs.push_back("Y" + std::to_string(k + 1));
  // A: each state's own rate over two decades, couplings between 40 % of the pairs of states
  // (a chain through every state, so modes are shared), drawn again until stable.
  do {
    ss.A = Eigen::MatrixXd::Zero(n, n);
    for (int k = 0; k < n; ++k) ss.A(k, k) = -logu(0.5, 50);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        if (i == j) continue;
        if (j == i + 1 || u(g) < 0.4)
          ss.A(i, j) =
              (u(g) < 0.5 ? -1 : 1) * logu(0.1, 0.6) * std::sqrt(std::abs(ss.A(i, i) * ss.A(j, j)));
      }
  } while (!stable(ss.A));
  // B: each input drives one or two states; C: each output sees one to three.
  ss.B = Eigen::MatrixXd::Zero(n, ni);
  for (int j = 0; j < ni; ++j)
    for (int q = 0, m = 1 + int(g() % 2); q < m; ++q)
      ss.B(int(g() % uint64_t(n)), j) = (u(g) < 0.8 ? 1 : -1) * logu(0.3, 3) * std::abs(ss.A(0, 0));
  ss.C = Eigen::MatrixXd::Zero(no, n);
  for (int i = 0; i < no; ++i)
    for (int q = 0, m = 1 + int(g() % 3); q < m; ++q)
      ss.C(i, int(g() % uint64_t(n))) = (u(g) < 0.8 ? 1 : -1) * logu(0.3, 3);
  ss.D = Eigen::MatrixXd::Zero(no, ni);
  // Named parameters, in about half the cases (a stream of their own, so that the rest of a case
  // is drawn as without them): a state's inertia J_Sk, 0.5-5, setting the inverse of its row of
  // A and of B, for each state with probability 0.3.
  std::mt19937_64 gp(seed * 3000017u + uint64_t(index) * 11u + 5u);
  if (u(gp) < 0.5)
    for (int k = 0; k < n; ++k) {
      if (u(gp) >= 0.3) continue;
      NamedParameter np{"J_S" + std::to_string(k + 1), "kg m2", 0.5 * std::pow(10.0, u(gp)), {}};
      for (int j = 0; j < n; ++j)
        if (ss.A(k, j) != 0) np.entries.push_back({'A', k, j, true});
      for (int j = 0; j < ni; ++j)
        if (ss.B(k, j) != 0) np.entries.push_back({'B', k, j, true});
      ss.parameters.push_back(std::move(np));
    }
  RandomCase c;
  c.name = "case" + std::to_string(index);
  try {
    c.simulation = parse_model(document(ss, "random state model " + std::to_string(index)),
                               c.name + "/simulation");
  } catch (const InputError&) {  // a path that does not factor: the next draw of this case
    return random_state_case(seed + 1000003u, index, n_hidden);
  }
  // The hidden entries: distinct nonzero entries of A (its diagonal: a time constant), B or C,
  // each moved by a factor 1.3-2 either way (a coupling or a gain: also of either size).
  StateSpace truth = ss;
  const int hide = n_hidden >= 0 ? n_hidden : int(g() % 4);
  std::vector<std::tuple<char, int, int>> taken;
  for (int h = 0, tries = 0; h < hide && tries < 100; ++tries) {
    const double r = u(g);
    const char matrix = r < 0.5 ? 'A' : r < 0.75 ? 'B' : 'C';
    Eigen::MatrixXd& M = matrix == 'A' ? truth.A : matrix == 'B' ? truth.B : truth.C;
    int i = int(g() % uint64_t(M.rows())), j = int(g() % uint64_t(M.cols()));
    if (matrix == 'A' && u(g) < 0.6) j = i;  // mostly a time constant
    if (M(i, j) == 0 ||
        std::find(taken.begin(), taken.end(), std::tuple{matrix, i, j}) != taken.end())
      continue;
    const double factor = logu(1.3, 2.0);
    const double was = M(i, j);
    M(i, j) = was * (u(g) < 0.5 ? factor : 1 / factor);
    if (matrix == 'A' && !stable(truth.A)) {
      M(i, j) = was;
      continue;
    }
    taken.emplace_back(matrix, i, j);
    HiddenEffect e;
    e.cause = CauseKind::kStateParameter;
    e.scope = Scope::kPlant;
    e.param = Param::kTo;
    e.value = M(i, j);
    e.tol_rel = 0.02;
    e.text["matrix"] = std::string(1, matrix);
    e.text["state"] = ss.states[size_t(matrix == 'C' ? j : i)];
    e.exact[Param::kRow] = i + 1;
    e.exact[Param::kCol] = j + 1;
    c.hidden.push_back(e);
    ++h;
  }
  // One named parameter moved by a factor 1.3-2 either way, in half the cases that name some,
  // where no hidden entry lies in what it sets.
  if (!ss.parameters.empty() && u(gp) < 0.5) {
    const size_t k = size_t(gp() % ss.parameters.size());
    bool free = true;
    for (const NamedParameter::Entry& x : ss.parameters[k].entries)
      free &=
          std::find(taken.begin(), taken.end(), std::tuple{x.matrix, x.row, x.col}) == taken.end();
    const double was = ss.parameters[k].value, factor = 1.3 * std::pow(2.0 / 1.3, u(gp)),
                 to = u(gp) < 0.5 ? was * factor : was / factor;
    if (free && stable(with_parameter(truth, k, to).A)) {
      truth = with_parameter(truth, k, to);
      HiddenEffect e;
      e.cause = CauseKind::kStateParameter;
      e.scope = Scope::kPlant;
      e.param = Param::kTo;
      e.value = to;
      e.tol_rel = 0.02;
      e.text["parameter"] = ss.parameters[k].name;
      c.hidden.push_back(e);
    }
  }
  // A state the simulation lacks, in about one case in four: a first-order lag before an input
  // or after an output that no hidden entry of B or C reads, its corner within A's modes.
  if (u(g) < 0.25) {
    const bool before = u(g) < 0.5;
    const int k = int(g() % uint64_t(before ? ni : no));
    const Eigen::EigenSolver<Eigen::MatrixXd> es(ss.A, false);
    const double lo = es.eigenvalues().cwiseAbs().minCoeff(),
                 hi = es.eigenvalues().cwiseAbs().maxCoeff(), corner = logu(lo, hi);
    bool read = false;
    for (const auto& [m, i, j] : taken) read |= before ? m == 'B' && j == k : m == 'C' && i == k;
    if (!read) {
      truth = with_lag(truth, before, k, corner);
      c.hidden.push_back(channel_effect(CauseKind::kMissingLag, before,
                                        before ? ss.inputs[size_t(k)] : ss.outputs[size_t(k)],
                                        Param::kCornerRadS, corner));
    }
  }
  // A delay the simulation lacks, in about one case in five: at an input or an output, its phase
  // at the top of the measured band 0.2-2 rad.
  if (u(g) < 0.2) {
    const bool at_input = u(g) < 0.5;
    const int k = int(g() % uint64_t(at_input ? ni : no));
    const std::vector<double> w = state_grid(ss);
    const double delay = logu(0.2, 2.0) / w.back();
    std::vector<double>& d = at_input ? truth.input_delay_s : truth.output_delay_s;
    d.assign(size_t(at_input ? ni : no), 0.0);
    d[size_t(k)] = delay;
    c.hidden.push_back(channel_effect(CauseKind::kTimeDelay, at_input,
                                      at_input ? ss.inputs[size_t(k)] : ss.outputs[size_t(k)],
                                      Param::kDelayS, delay));
  }
  try {
    c.engine = parse_model(document(truth, "engine " + std::to_string(index)), c.name + "/engine");
  } catch (const InputError&) {
    return random_state_case(seed + 1000003u, index, n_hidden);
  }
  return c;
}

std::vector<MeasuredPair> state_measurement(const RandomCase& c, uint64_t seed, double rel_sigma) {
  return exact_measurement(c.engine, state_grid(*c.simulation.state_space), seed, rel_sigma);
}

bool state_effect_resolved(const RandomCase& c, const HiddenEffect& e, double rel_sigma) {
  const StateSpace& truth = *c.engine.state_space;
  // A lag undone: its column or row times (1 + jw / p); a delay: times exp(jw tau).
  if (e.cause == CauseKind::kMissingLag || e.cause == CauseKind::kTimeDelay) {
    const bool before = e.scope == Scope::kInput;
    const auto& names = before ? truth.inputs : truth.outputs;
    const Eigen::Index k =
        std::find(names.begin(), names.end(), before ? e.input : e.output) - names.begin();
    double chi2 = 0;
    size_t n = 0;
    for (double w : state_grid(*c.simulation.state_space)) {
      const Eigen::MatrixXcd g = state_space_response(truth, C(0, w));
      for (Eigen::Index a = 0; a < g.rows(); ++a)
        for (Eigen::Index b = 0; b < g.cols(); ++b) {
          if (std::abs(g(a, b)) == 0) continue;
          const bool on = before ? b == k : a == k;
          const C undo =
              e.cause == CauseKind::kMissingLag ? C(1, w / e.value) : std::exp(C(0, w * e.value));
          const C h = on ? g(a, b) * undo : g(a, b);
          chi2 += std::norm((g(a, b) - h) / (rel_sigma * std::abs(g(a, b))));
          ++n;
        }
    }
    return chi2 > std::log(2.0 * double(std::max<size_t>(n, 1)));
  }
  const StateSpace& sim = *c.simulation.state_space;
  StateSpace undone = truth;
  if (e.text.count("parameter")) {  // a named parameter back at the simulation's value
    for (size_t k = 0; k < sim.parameters.size(); ++k)
      if (sim.parameters[k].name == e.text.at("parameter"))
        undone = with_parameter(truth, k, sim.parameters[k].value);
  } else {
    const char matrix = e.text.at("matrix")[0];
    const int i = int(e.exact.at(Param::kRow)) - 1, j = int(e.exact.at(Param::kCol)) - 1;
    Eigen::MatrixXd& m = matrix == 'A' ? undone.A : matrix == 'B' ? undone.B : undone.C;
    m(i, j) = (matrix == 'A' ? sim.A : matrix == 'B' ? sim.B : sim.C)(i, j);
  }
  double chi2 = 0;
  size_t n = 0;
  for (double w : state_grid(*c.simulation.state_space)) {
    const Eigen::MatrixXcd g = state_space_response(truth, C(0, w)),
                           h = state_space_response(undone, C(0, w));
    for (Eigen::Index a = 0; a < g.rows(); ++a)
      for (Eigen::Index b = 0; b < g.cols(); ++b) {
        if (std::abs(g(a, b)) == 0) continue;
        chi2 += std::norm((g(a, b) - h(a, b)) / (rel_sigma * std::abs(g(a, b))));
        ++n;
      }
  }
  return chi2 > std::log(2.0 * double(std::max<size_t>(n, 1)));
}

}  // namespace fralab::testing
