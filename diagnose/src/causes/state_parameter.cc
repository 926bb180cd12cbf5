#include "state_parameter.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <tuple>

#include "fralab/core/error.h"

namespace fralab::diag {
namespace {

constexpr double kSameStateRoot =
    1e-9;  // a path's root is the state model's: within this (relative)

StateEntry entry_of(const StateSpace& ss, const Finding& f) {
  if (const auto it = f.text_parameters.find("parameter"); it != f.text_parameters.end()) {
    for (size_t k = 0; k < ss.parameters.size(); ++k)
      if (ss.parameters[k].name == it->second) return {'P', int(k), 0};
    throw InputError("state_parameter: the simulation has no parameter \"" + it->second + "\"");
  }
  return {f.text_parameters.at("matrix")[0], int(f.parameters.at(Param::kRow)) - 1,
          int(f.parameters.at(Param::kCol)) - 1};
}

// The entries of A, B and C that e sets ((matrix, row, col)).
std::vector<std::tuple<char, int, int>> set_by(const StateSpace& ss, const StateEntry& e) {
  if (!e.named()) return {{e.matrix, e.row, e.col}};
  std::vector<std::tuple<char, int, int>> out;
  for (const NamedParameter::Entry& x : ss.parameters[size_t(e.row)].entries)
    out.emplace_back(x.matrix, x.row, x.col);
  return out;
}

// t, whose rational part holds `from`'s (where no other finding moved its roots), changed to hold
// `to`'s: each root of `from` taken out of t (or, when another finding moved it, cancelled by the
// same root on the other side), `to`'s roots put in, the gain scaled by to's over from's.
void replace(Tf& t, const Tf& from, const Tf& to) {
  auto take = [&](std::vector<Root>& side, std::vector<Root>& other, const Root& r) {
    for (auto it = side.begin(); it != side.end(); ++it)
      if (it->same_as(r, kSameStateRoot)) {
        side.erase(it);
        return;
      }
    other.push_back(r);
  };
  for (const Root& r : from.poles) take(t.poles, t.zeros, r);
  for (const Root& r : from.zeros) take(t.zeros, t.poles, r);
  t.poles.insert(t.poles.end(), to.poles.begin(), to.poles.end());
  t.zeros.insert(t.zeros.end(), to.zeros.begin(), to.zeros.end());
  t.gain *= to.gain / from.gain;
}

class StateParameter final : public CauseUnit {
 public:
  CauseKind kind() const override { return CauseKind::kStateParameter; }
  const char* name() const override { return "state_parameter"; }
  PrimaryParameter primary_parameter(const Finding& f) const override {
    return {Param::kTo, f.parameters.at(Param::kFrom)};
  }
  IntervalDomain interval_domain() const override { return {false, 1e-9}; }
  void settle(Finding& f) const override {
    if (f.parameters.count(Param::kTimeConstantFromS))
      f.parameters[Param::kTimeConstantToS] = -1 / f.parameters.at(Param::kTo);
  }
  // Every path of the model: its state model's path before and after the entry's move replaced.
  void apply(Model& m, const Finding& f) const override {
    if (!m.state_space) throw InputError("state_parameter: the simulation is not a state model");
    const StateSpace& ss = *m.state_space;
    const StateEntry e = entry_of(ss, f);
    const StateSpace moved = with_entry(ss, e, f.parameters.at(Param::kTo));
    const auto before = state_paths(ss), after = state_paths(moved);
    if (!before || !after) return;  // not a stable state model at that value: left unchanged
    for (size_t i = 0; i < ss.outputs.size(); ++i)
      for (size_t j = 0; j < ss.inputs.size(); ++j) {
        const auto& from = (*before)[i][j];
        const auto& to = (*after)[i][j];
        ModelPath* p = m.path(ss.outputs[i], ss.inputs[j]);
        if (p && from && to) {
          replace(p->tf, *from, *to);
        } else if (p && from && !to) {
          p->tf.gain = 0;
        } else if (!p && to) {
          m.paths.push_back({ss.outputs[i], ss.inputs[j], *to, Json::object()});
        }
      }
    m.state_space = std::make_shared<const StateSpace>(moved);
  }
  std::string explain(const Finding& f) const override {
    const auto& tp = f.text_parameters;
    const std::string move =
        fmt(f.parameters.at(Param::kFrom)) + " -> " + fmt(f.parameters.at(Param::kTo));
    if (tp.count("parameter"))
      return "the parameter " + tp.at("parameter") + " " + move +
             (tp.count("units") ? " " + tp.at("units") : std::string()) + " (in the states " +
             tp.at("state") +
             "): one parameter of the state model, fitted over every path it reaches";
    const std::string entry = tp.at("matrix") + "(" + fmt(f.parameters.at(Param::kRow)) + ", " +
                              fmt(f.parameters.at(Param::kCol)) + ")";
    std::string what;
    if (tp.at("matrix") == "A" && f.parameters.count(Param::kTimeConstantFromS))
      what = "the state " + tp.at("state") + "'s own rate " + entry + " " + move +
             " 1/s (time constant " + fmt(f.parameters.at(Param::kTimeConstantFromS)) + " -> " +
             fmt(f.parameters.at(Param::kTimeConstantToS)) + " s)";
    else if (tp.at("matrix") == "A")
      what = "the coupling " + entry + " into the state " + tp.at("state") + " " + move;
    else if (tp.at("matrix") == "B")
      what = "how " + tp.at("input") + " drives the state " + tp.at("state") + ", " + entry + " " +
             move;
    else
      what = "how the state " + tp.at("state") + " shows at " + tp.at("output") + ", " + entry +
             " " + move;
    return what + ": one parameter of the state model, fitted over every path it reaches";
  }
};

}  // namespace

bool overlap(const StateSpace& ss, const StateEntry& a, const StateEntry& b) {
  if (a.added() || b.added()) return a.matrix == b.matrix && a.row == b.row && a.col == b.col;
  for (const auto& x : set_by(ss, a))
    for (const auto& y : set_by(ss, b))
      if (x == y) return true;
  return false;
}

double entry_value(const StateSpace& ss, const StateEntry& e) {
  if (e.named()) return ss.parameters[size_t(e.row)].value;
  if (e.added()) return 0;
  const Eigen::MatrixXd& m = e.matrix == 'A'   ? ss.A
                             : e.matrix == 'B' ? ss.B
                             : e.matrix == 'C' ? ss.C
                                               : ss.D;
  return m(e.row, e.col);
}

StateSpace with_entry(const StateSpace& ss, const StateEntry& e, double v) {
  if (e.named()) return std::isfinite(v) && v != 0 ? with_parameter(ss, size_t(e.row), v) : ss;
  if (e.delay()) {
    if (!(v > 0)) return ss;
    StateSpace out = ss;
    std::vector<double>& d = e.at_input() ? out.input_delay_s : out.output_delay_s;
    d.resize(e.at_input() ? ss.inputs.size() : ss.outputs.size(), 0.0);
    d[size_t(e.at_input() ? e.col : e.row)] += v;
    return out;
  }
  if (e.lag()) {
    if (!(v > 0)) return ss;
    const Eigen::Index n = ss.A.rows(), m = ss.B.cols(), p = ss.C.rows();
    const Eigen::MatrixXd D = ss.D.size() ? ss.D : Eigen::MatrixXd::Zero(p, m);
    StateSpace out = ss;
    out.A = Eigen::MatrixXd::Zero(n + 1, n + 1);
    out.A.topLeftCorner(n, n) = ss.A;
    out.A(n, n) = -1 / v;
    out.B = Eigen::MatrixXd::Zero(n + 1, m);
    out.C = Eigen::MatrixXd::Zero(p, n + 1);
    out.D = D;
    if (e.matrix == 'U') {
      out.A.block(0, n, n, 1) = ss.B.col(e.col);
      out.B.topRows(n) = ss.B;
      out.B.block(0, e.col, n, 1).setZero();
      out.B(n, e.col) = 1 / v;
      out.C.leftCols(n) = ss.C;
      out.C.col(n) = D.col(e.col);
      out.D.col(e.col).setZero();
      out.states.push_back("lag before " + ss.inputs[size_t(e.col)]);
    } else {
      out.A.block(n, 0, 1, n) = ss.C.row(e.row) / v;
      out.B.topRows(n) = ss.B;
      out.B.row(n) = D.row(e.row) / v;
      out.C.leftCols(n) = ss.C;
      out.C.row(e.row).setZero();
      out.C(e.row, n) = 1;
      out.D.row(e.row).setZero();
      out.states.push_back("lag after " + ss.outputs[size_t(e.row)]);
    }
    return out;
  }
  StateSpace out = ss;
  Eigen::MatrixXd& m = e.matrix == 'A' ? out.A : e.matrix == 'B' ? out.B : out.C;
  m(e.row, e.col) = v;
  return out;
}

std::optional<std::vector<std::vector<std::optional<Tf>>>> state_paths(const StateSpace& ss) {
  try {
    ss.validate("state model");
    return state_space_paths(ss, "state model");
  } catch (const InputError&) {
    return std::nullopt;
  }
}

Finding state_parameter_finding(const StateSpace& ss, const StateEntry& e, double to,
                                const std::vector<std::string>& pairs) {
  Finding f;
  f.cause = CauseKind::kStateParameter;
  f.scope = Scope::kPlant;
  f.pairs = pairs;
  if (e.named()) {
    const NamedParameter& np = ss.parameters[size_t(e.row)];
    f.parameters = {{Param::kFrom, np.value}, {Param::kTo, to}};
    f.text_parameters["parameter"] = np.name;
    if (!np.units.empty()) f.text_parameters["units"] = np.units;
    std::vector<std::string> states;
    for (const NamedParameter::Entry& x : np.entries) {
      if (x.matrix == 'D') continue;
      const std::string& st = ss.states[size_t(x.matrix == 'C' ? x.col : x.row)];
      if (std::find(states.begin(), states.end(), st) == states.end()) states.push_back(st);
    }
    std::string joined;
    for (const std::string& st : states) joined += (joined.empty() ? "" : ", ") + st;
    f.text_parameters["state"] = joined;
    return f;
  }
  f.parameters = {{Param::kFrom, entry_value(ss, e)},
                  {Param::kTo, to},
                  {Param::kRow, e.row + 1},
                  {Param::kCol, e.col + 1}};
  f.text_parameters["matrix"] = std::string(1, e.matrix);
  if (e.matrix == 'A') {
    f.text_parameters["state"] = ss.states[size_t(e.row)];
    if (e.row == e.col) {
      f.parameters[Param::kTimeConstantFromS] = -1 / entry_value(ss, e);
      f.parameters[Param::kTimeConstantToS] = -1 / to;
    }
  } else if (e.matrix == 'B') {
    f.text_parameters["state"] = ss.states[size_t(e.row)];
    f.text_parameters["input"] = ss.inputs[size_t(e.col)];
  } else {
    f.text_parameters["state"] = ss.states[size_t(e.col)];
    f.text_parameters["output"] = ss.outputs[size_t(e.row)];
  }
  return f;
}

const CauseUnit& state_parameter_cause() {
  static const StateParameter c;
  return c;
}

}  // namespace fralab::diag
