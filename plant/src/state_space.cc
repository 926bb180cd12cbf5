#include "fralab/plant/state_space.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <memory>
#include <set>
#include <tuple>

#include "fralab/core/error.h"

namespace fralab {
namespace {

using Cd = std::complex<double>;

constexpr double kCancel = 1e-7;  // a zero within this of a pole (relative, at least 1) cancels
constexpr double kImag = 1e-9;    // a root with |imag| below this (relative) is real
constexpr double kAgree = 1e-6;   // the path's factored response agrees with C(sI-A)^-1 B + D

std::string size_str(const Eigen::MatrixXd& m) {
  return std::to_string(m.rows()) + " x " + std::to_string(m.cols());
}

// Roots (each complex pair given once, by its member with positive imaginary part, or both) as
// fralab's factors: real roots and (wn, zeta) pairs.
std::vector<Root> as_roots(const std::vector<Cd>& r) {
  std::vector<Root> out;
  for (const Cd& z : r) {
    const double scale = std::max(1.0, std::abs(z));
    if (std::abs(z.imag()) <= kImag * scale)
      out.push_back(Root::Real(z.real()));
    else if (z.imag() > 0)
      out.push_back(Root::Pair(std::abs(z), -z.real() / std::abs(z)));
  }
  return out;
}

Eigen::MatrixXd matrix(const Json& doc, const JsonWhere& root, const std::string& key,
                       bool optional_empty) {
  if (!doc.contains(key)) {
    if (optional_empty) return Eigen::MatrixXd(0, 0);
    json_fail(root / key, "missing: the state model's " + key + " matrix (an array of rows)");
  }
  const JsonWhere w = root / key;
  const Json& rows = doc[key];
  if (!rows.is_array()) json_fail(w, "must be an array of rows");
  if (rows.empty()) return Eigen::MatrixXd(0, 0);
  const size_t cols = rows[0].is_array() ? rows[0].size() : 0;
  Eigen::MatrixXd m(Eigen::Index(rows.size()), Eigen::Index(cols));
  for (size_t r = 0; r < rows.size(); ++r) {
    if (!rows[r].is_array() || rows[r].size() != cols)
      json_fail(w / r, "every row must be an array of " + std::to_string(cols) + " numbers");
    for (size_t c = 0; c < cols; ++c)
      m(Eigen::Index(r), Eigen::Index(c)) = json_number(rows[r][c], w / r / c);
  }
  return m;
}

}  // namespace

namespace {

using Fail = std::function<void(const std::string&)>;

// The matrices' sizes against the names (A square, B states x inputs, C outputs x states, D
// outputs x inputs or empty), and every entry finite.
void check_matrix_sizes(const StateSpace& s, const Fail& fail) {
  const Eigen::Index n = s.A.rows(), m = Eigen::Index(s.inputs.size()),
                     p = Eigen::Index(s.outputs.size());
  if (n == 0) fail("A: no states");
  if (s.A.cols() != n) fail("A is " + size_str(s.A) + ": it must be square");
  if (Eigen::Index(s.states.size()) != n)
    fail(std::to_string(s.states.size()) + " state names for " + std::to_string(n) + " states (A)");
  if (m == 0) fail("no inputs");
  if (p == 0) fail("no outputs");
  if (s.B.rows() != n || s.B.cols() != m)
    fail("B is " + size_str(s.B) + ", expected " + std::to_string(n) + " x " + std::to_string(m) +
         " (states x inputs)");
  if (s.C.rows() != p || s.C.cols() != n)
    fail("C is " + size_str(s.C) + ", expected " + std::to_string(p) + " x " + std::to_string(n) +
         " (outputs x states)");
  if (s.D.size() != 0 && (s.D.rows() != p || s.D.cols() != m))
    fail("D is " + size_str(s.D) + ", expected " + std::to_string(p) + " x " + std::to_string(m) +
         " (outputs x inputs)");
  for (const auto& [name, mat] : {std::pair<const char*, const Eigen::MatrixXd*>{"A", &s.A},
                                  {"B", &s.B},
                                  {"C", &s.C},
                                  {"D", &s.D}})
    for (Eigen::Index r = 0; r < mat->rows(); ++r)
      for (Eigen::Index c = 0; c < mat->cols(); ++c)
        if (!std::isfinite((*mat)(r, c)))
          fail(std::string(name) + "(" + std::to_string(r + 1) + ", " + std::to_string(c + 1) +
               ") is not a finite number");
}

// Names given once and not empty; the delays' counts against the channels, each >= 0 and finite.
void check_names_and_delays(const StateSpace& s, const Fail& fail) {
  const Eigen::Index m = Eigen::Index(s.inputs.size()), p = Eigen::Index(s.outputs.size());
  std::set<std::string> seen;
  for (const auto* names : {&s.states, &s.inputs, &s.outputs})
    for (const std::string& x : *names) {
      if (x.empty()) fail("a state, input or output name is empty");
      if (!seen.insert(x).second) fail("the name \"" + x + "\" is given twice");
    }
  if (!s.input_delay_s.empty() && s.input_delay_s.size() != s.inputs.size())
    fail(std::to_string(s.input_delay_s.size()) + " input delays for " +
         std::to_string(s.inputs.size()) + " inputs");
  if (!s.output_delay_s.empty() && s.output_delay_s.size() != s.outputs.size())
    fail(std::to_string(s.output_delay_s.size()) + " output delays for " +
         std::to_string(s.outputs.size()) + " outputs");
  if (s.path_delay_s.size() != 0 && (s.path_delay_s.rows() != p || s.path_delay_s.cols() != m))
    fail("delay_s is " + size_str(s.path_delay_s) + ", expected " + std::to_string(p) + " x " +
         std::to_string(m) + " (outputs x inputs)");
  std::vector<double> all(s.input_delay_s);
  all.insert(all.end(), s.output_delay_s.begin(), s.output_delay_s.end());
  all.insert(all.end(), s.path_delay_s.data(), s.path_delay_s.data() + s.path_delay_s.size());
  for (double d : all)
    if (!(d >= 0) || !std::isfinite(d)) fail("a delay is negative or not finite");
}

// Each named parameter: a unique name, a finite nonzero value, entries inside their matrices,
// nonzero (a zero entry no value moves) and each given once.
void check_named_parameters(const StateSpace& s, const Fail& fail) {
  std::set<std::string> named;
  for (const NamedParameter& np : s.parameters) {
    const std::string what = "parameter \"" + np.name + "\"";
    if (np.name.empty()) fail("a parameter's name is empty");
    if (!named.insert(np.name).second) fail(what + " is given twice");
    if (!std::isfinite(np.value) || np.value == 0) fail(what + ": its value is zero or not finite");
    if (np.entries.empty()) fail(what + " sets no entry");
    std::set<std::tuple<char, int, int>> set;
    for (const NamedParameter::Entry& e : np.entries) {
      const Eigen::MatrixXd* mat = e.matrix == 'A'   ? &s.A
                                   : e.matrix == 'B' ? &s.B
                                   : e.matrix == 'C' ? &s.C
                                   : e.matrix == 'D' ? &s.D
                                                     : nullptr;
      const std::string entry = std::string(1, e.matrix) + "(" + std::to_string(e.row + 1) + ", " +
                                std::to_string(e.col + 1) + ")";
      if (!mat) fail(what + ": an entry's matrix is not A, B, C or D");
      if (e.row < 0 || e.col < 0 || e.row >= mat->rows() || e.col >= mat->cols())
        fail(what + ": its entry " + entry + " is outside " + std::string(1, e.matrix) + " (" +
             size_str(*mat) + ")");
      if ((*mat)(e.row, e.col) == 0)
        fail(what + ": its entry " + entry + " is 0, which no value of the parameter moves");
      if (!set.emplace(e.matrix, e.row, e.col).second)
        fail(what + ": its entry " + entry + " is given twice");
    }
  }
}

// Every mode of A in the open left half plane.
void check_stable_modes(const StateSpace& s, const Fail& fail) {
  const Eigen::EigenSolver<Eigen::MatrixXd> es(s.A, false);
  if (es.info() != Eigen::Success) fail("A: its eigenvalues could not be computed");
  for (Eigen::Index k = 0; k < s.A.rows(); ++k) {
    const Cd l = es.eigenvalues()(k);
    if (!(l.real() < 0))
      fail("A has a mode at " + std::to_string(l.real()) + (l.imag() >= 0 ? " + " : " - ") +
           std::to_string(std::abs(l.imag())) +
           "j rad/s, not in the open left half plane (an unstable or marginal mode: fralab's "
           "simulations are stable)");
  }
}

}  // namespace

void StateSpace::validate(const std::string& source) const {
  const Fail fail = [&](const std::string& what) { throw InputError(source + ": " + what); };
  check_matrix_sizes(*this, fail);
  check_names_and_delays(*this, fail);
  check_named_parameters(*this, fail);
  check_stable_modes(*this, fail);
}

StateSpace with_parameter(const StateSpace& ss, size_t k, double p) {
  StateSpace out = ss;
  NamedParameter& np = out.parameters[k];
  for (const NamedParameter::Entry& e : np.entries) {
    Eigen::MatrixXd& m = e.matrix == 'A'   ? out.A
                         : e.matrix == 'B' ? out.B
                         : e.matrix == 'C' ? out.C
                                           : out.D;
    m(e.row, e.col) *= e.inverse ? np.value / p : p / np.value;
  }
  np.value = p;
  return out;
}

Eigen::MatrixXcd state_space_response(const StateSpace& ss, Cd s) {
  Eigen::MatrixXcd M = -ss.A.cast<Cd>();
  M.diagonal().array() += s;
  Eigen::MatrixXcd g = ss.C.cast<Cd>() * M.partialPivLu().solve(ss.B.cast<Cd>());
  if (ss.D.size()) g += ss.D.cast<Cd>();
  return g;
}

namespace {

// What every path of a state model shares: A's eigenvalues, and the responses at the frequencies
// each path's factored form is checked at (each mode's, a decade beyond the slowest and the
// fastest, and 0).
struct PathsCommon {
  std::vector<Cd> poles;
  std::vector<double> ws;
  std::vector<Eigen::MatrixXcd> want;
  explicit PathsCommon(const StateSpace& ss) {
    const Eigen::Index n = ss.A.rows();
    const Eigen::EigenSolver<Eigen::MatrixXd> es(ss.A, false);
    poles.assign(es.eigenvalues().data(), es.eigenvalues().data() + n);
    ws = {0.0};
    double lo = INFINITY, hi = 0;
    for (const Cd& p : poles) lo = std::min(lo, std::abs(p)), hi = std::max(hi, std::abs(p));
    for (const Cd& p : poles) ws.push_back(std::abs(p));
    ws.push_back(lo / 10), ws.push_back(hi * 10);
    for (double w : ws) want.push_back(state_space_response(ss, Cd(0, w)));
  }
};

std::optional<Tf> factor_path(const StateSpace& ss, int i, int j, const std::string& source,
                              const PathsCommon& common) {
  const Eigen::Index n = ss.A.rows();
  const Eigen::VectorXd b = ss.B.col(j);
  const Eigen::RowVectorXd c = ss.C.row(i);
  const double d = ss.D.size() ? ss.D(i, j) : 0.0;
  const std::string path = ss.inputs[size_t(j)] + " -> " + ss.outputs[size_t(i)];
  // Zero at every frequency: D = 0 and every Markov parameter C A^k B (k < n) negligible.
  {
    Eigen::VectorXd v = b;
    bool zero = d == 0;
    const double an = std::max(ss.A.norm(), 1e-300);
    double scale = c.norm() * b.norm();
    for (Eigen::Index k = 0; k < n && zero; ++k) {
      if (std::abs(c.dot(v)) > 1e-12 * scale) zero = false;
      v = ss.A * v;
      scale *= an;
    }
    if (zero) return std::nullopt;
  }
  // Poles: A's eigenvalues.
  const std::vector<Cd>& poles = common.poles;
  // Zeros: the finite generalised eigenvalues of ([A b; c d], [I 0; 0 0]).
  Eigen::MatrixXd M(n + 1, n + 1), N = Eigen::MatrixXd::Zero(n + 1, n + 1);
  M << ss.A, b, c, d;
  N.topLeftCorner(n, n).setIdentity();
  Eigen::GeneralizedEigenSolver<Eigen::MatrixXd> ges(M, N, false);
  std::vector<Cd> zeros;
  const double big = 1e8 * std::max(1.0, ss.A.cwiseAbs().maxCoeff());
  for (Eigen::Index k = 0; k < n + 1; ++k) {
    const Cd alpha = ges.alphas()(k);
    const double beta = ges.betas()(k);
    if (std::abs(beta) == 0 || std::abs(alpha / beta) > big) continue;
    zeros.push_back(alpha / beta);
  }
  // A zero on a pole: the mode does not reach this path.
  std::vector<bool> gone(poles.size(), false);
  std::vector<Cd> kept_zeros;
  for (const Cd& z : zeros) {
    size_t best = poles.size();
    double dist = INFINITY;
    for (size_t k = 0; k < poles.size(); ++k)
      if (!gone[k] && std::abs(z - poles[k]) < dist) {
        dist = std::abs(z - poles[k]);
        best = k;
      }
    if (best < poles.size() && dist <= kCancel * std::max(1.0, std::abs(poles[best])))
      gone[best] = true;
    else
      kept_zeros.push_back(z);
  }
  std::vector<Cd> kept_poles;
  for (size_t k = 0; k < poles.size(); ++k)
    if (!gone[k]) kept_poles.push_back(poles[k]);
  for (const Cd& z : kept_zeros)
    if (std::abs(z) <= 1e-9 * std::max(1.0, ss.A.cwiseAbs().maxCoeff()))
      throw InputError(source + ": the path " + path +
                       " has a zero at s = 0 (a derivative): fralab's transfer functions are in "
                       "DC-gain form and have no root at s = 0");
  Tf tf;
  tf.gain = d - c.dot(ss.A.partialPivLu().solve(b));
  tf.zeros = as_roots(kept_zeros);
  tf.poles = as_roots(kept_poles);
  tf.delay_s = (ss.input_delay_s.empty() ? 0.0 : ss.input_delay_s[size_t(j)]) +
               (ss.output_delay_s.empty() ? 0.0 : ss.output_delay_s[size_t(i)]) +
               (ss.path_delay_s.size() ? ss.path_delay_s(i, j) : 0.0);
  // The factored form must be the state model's response (a check, not an approximation): at
  // each of the modes' frequencies and a decade beyond the slowest and the fastest, within kAgree
  // of the path's largest magnitude there.
  const std::vector<double>& ws = common.ws;
  double peak = 0;
  for (size_t k = 0; k < ws.size(); ++k) peak = std::max(peak, std::abs(common.want[k](i, j)));
  for (size_t k = 0; k < ws.size(); ++k)
    if (std::abs(tf.rational(Cd(0, ws[k])) - common.want[k](i, j)) > kAgree * peak)
      throw InputError(source + ": the path " + path + " could not be factored to agree with " +
                       "C (sI - A)^-1 B + D at " + std::to_string(ws[k]) +
                       " rad/s (nearly cancelling modes; give the model in a balanced form)");
  return tf;
}

}  // namespace

std::optional<Tf> state_space_path(const StateSpace& ss, int i, int j, const std::string& source) {
  return factor_path(ss, i, j, source, PathsCommon(ss));
}

std::vector<std::vector<std::optional<Tf>>> state_space_paths(const StateSpace& ss,
                                                              const std::string& source) {
  const PathsCommon common(ss);
  std::vector<std::vector<std::optional<Tf>>> out(ss.outputs.size());
  for (size_t i = 0; i < ss.outputs.size(); ++i)
    for (size_t j = 0; j < ss.inputs.size(); ++j)
      out[i].push_back(factor_path(ss, int(i), int(j), source, common));
  return out;
}

std::optional<ModeParticipation> mode_participation(const StateSpace& ss, Cd s, double rel) {
  const Eigen::EigenSolver<Eigen::MatrixXd> es(ss.A, true);
  if (es.info() != Eigen::Success) return std::nullopt;
  const Eigen::VectorXcd& l = es.eigenvalues();
  Eigen::Index k = 0;
  for (Eigen::Index q = 1; q < l.size(); ++q)
    if (std::abs(l(q) - s) < std::abs(l(k) - s)) k = q;
  if (std::abs(l(k) - s) > rel * std::abs(s)) return std::nullopt;
  const Eigen::MatrixXcd V = es.eigenvectors();
  const Eigen::FullPivLU<Eigen::MatrixXcd> lu(V);
  if (!lu.isInvertible()) return std::nullopt;  // a defective A: no participation factors
  const Eigen::MatrixXcd W = lu.inverse();
  ModeParticipation out;
  out.eigenvalue = l(k);
  double sum = 0;
  std::vector<double> p(size_t(l.size()));
  for (Eigen::Index j = 0; j < l.size(); ++j) sum += p[size_t(j)] = std::abs(V(j, k) * W(k, j));
  for (Eigen::Index j = 0; j < l.size(); ++j)
    out.states.emplace_back(ss.states[size_t(j)], sum > 0 ? p[size_t(j)] / sum : 0.0);
  std::stable_sort(out.states.begin(), out.states.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  return out;
}

StateSpace state_space_from_json(const Json& doc, const std::string& source) {
  const JsonWhere root{source, ""};
  json_require_object(doc, root);
  StateSpace ss;
  ss.A = matrix(doc, root, "A", false);
  ss.B = matrix(doc, root, "B", false);
  ss.C = matrix(doc, root, "C", false);
  ss.D = matrix(doc, root, "D", true);
  ss.path_delay_s = matrix(doc, root, "delay_s", true);
  auto names = [&](const std::string& key, std::vector<std::string>& out,
                   std::vector<double>* delays) {
    const Json& a = json_array_member(doc, root, key);
    for (size_t k = 0; k < a.size(); ++k) {
      json_require_object(a[k], root / key / k);
      out.push_back(json_string_member(a[k], root / key / k, "name"));
      if (delays) delays->push_back(json_number_member(a[k], root / key / k, "delay_s", 0.0));
    }
  };
  names("states", ss.states, nullptr);
  names("inputs", ss.inputs, &ss.input_delay_s);
  names("outputs", ss.outputs, &ss.output_delay_s);
  if (ss.D.size() == 0)
    ss.D = Eigen::MatrixXd::Zero(Eigen::Index(ss.outputs.size()), Eigen::Index(ss.inputs.size()));
  const Json& params = json_array_member(doc, root, "parameters", true);
  for (size_t k = 0; k < params.size(); ++k) {
    const JsonWhere at = root / "parameters" / k;
    json_require_object(params[k], at);
    NamedParameter np;
    np.name = json_string_member(params[k], at, "name");
    np.units = params[k].contains("units") ? json_string_member(params[k], at, "units") : "";
    np.value = json_number_member(params[k], at, "value");
    const Json& entries = json_array_member(params[k], at, "entries");
    for (size_t q = 0; q < entries.size(); ++q) {
      const JsonWhere eq = at / "entries" / q;
      json_require_object(entries[q], eq);
      const std::string m = json_string_member(entries[q], eq, "matrix");
      if (m.size() != 1 || std::string("ABCD").find(m[0]) == std::string::npos)
        json_fail(eq / "matrix", "\"" + m + "\" is not A, B, C or D");
      const std::string form = entries[q].contains("form")
                                   ? json_string_member(entries[q], eq, "form")
                                   : std::string("proportional");
      if (form != "proportional" && form != "inverse")
        json_fail(eq / "form", "\"" + form + "\" is not proportional or inverse");
      const double row = json_number_member(entries[q], eq, "row"),
                   col = json_number_member(entries[q], eq, "col");
      if (row != std::floor(row) || col != std::floor(col) || row < 1 || col < 1 || row > 1e6 ||
          col > 1e6)
        json_fail(eq, "row and col are whole numbers from 1");
      np.entries.push_back({m[0], int(row) - 1, int(col) - 1, form == "inverse"});
    }
    ss.parameters.push_back(std::move(np));
  }
  return ss;
}

Model parse_state_space_model(const Json& doc, const std::string& source) {
  const JsonWhere root{source, ""};
  json_require_object(doc, root);
  const std::string format = json_string_member(doc, root, "format");
  if (format != kStateSpaceFormat)
    json_fail(root / "format",
              "expected \"" + std::string(kStateSpaceFormat) + "\", found \"" + format + "\"");
  const StateSpace ss = state_space_from_json(doc, source);
  ss.validate(source);
  // The document as a fralab-model/1 one: the channels as given (their delays moved into the
  // paths), the paths the state model implies.
  Json m = doc;
  m["format"] = kModelFormat;
  for (const char* key : {"states", "A", "B", "C", "D", "delay_s"}) m.erase(key);
  for (const char* key : {"inputs", "outputs"})
    for (Json& ch : m[key]) ch.erase("delay_s");
  m["paths"] = Json::array();
  const auto paths = state_space_paths(ss, source);
  for (size_t i = 0; i < ss.outputs.size(); ++i)
    for (size_t j = 0; j < ss.inputs.size(); ++j)
      if (const auto& tf = paths[i][j])
        m["paths"].push_back({{"output", ss.outputs[size_t(i)]},
                              {"input", ss.inputs[size_t(j)]},
                              {"tf", tf_to_json(*tf)}});
  Model model = parse_model(m, source);
  model.state_space = std::make_shared<const StateSpace>(ss);
  return model;
}

Json state_space_document(const StateSpace& ss, const std::string& name) {
  auto rows = [](const Eigen::MatrixXd& x) {
    Json r = Json::array();
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
      Json row = Json::array();
      for (Eigen::Index k = 0; k < x.cols(); ++k) row.push_back(x(i, k));
      r.push_back(row);
    }
    return r;
  };
  Json doc = {{"format", kStateSpaceFormat}, {"name", name}};
  doc["states"] = Json::array();
  for (const auto& s : ss.states) doc["states"].push_back({{"name", s}});
  doc["inputs"] = Json::array();
  for (size_t k = 0; k < ss.inputs.size(); ++k) {
    Json in = {{"name", ss.inputs[k]}, {"units", "1"}, {"full_scale", 1.0}};
    if (!ss.input_delay_s.empty() && ss.input_delay_s[k] > 0) in["delay_s"] = ss.input_delay_s[k];
    doc["inputs"].push_back(in);
  }
  doc["outputs"] = Json::array();
  for (size_t k = 0; k < ss.outputs.size(); ++k) {
    Json out = {{"name", ss.outputs[k]}, {"units", "1"}};
    if (!ss.output_delay_s.empty() && ss.output_delay_s[k] > 0)
      out["delay_s"] = ss.output_delay_s[k];
    doc["outputs"].push_back(out);
  }
  doc["A"] = rows(ss.A);
  doc["B"] = rows(ss.B);
  doc["C"] = rows(ss.C);
  doc["D"] = rows(ss.D);
  if (ss.path_delay_s.size()) doc["delay_s"] = rows(ss.path_delay_s);
  for (const NamedParameter& np : ss.parameters) {
    Json entries = Json::array();
    for (const NamedParameter::Entry& e : np.entries)
      entries.push_back({{"matrix", std::string(1, e.matrix)},
                         {"row", e.row + 1},
                         {"col", e.col + 1},
                         {"form", e.inverse ? "inverse" : "proportional"}});
    doc["parameters"].push_back(
        {{"name", np.name}, {"units", np.units}, {"value", np.value}, {"entries", entries}});
  }
  return doc;
}

}  // namespace fralab
