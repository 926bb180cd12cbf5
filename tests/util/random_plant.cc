#include "random_plant.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

namespace fralab::testing {

namespace {

Tf lag(double a, double gain = 1.0) {
  Tf t;
  t.gain = gain;
  t.poles = {Root::Real(-a)};
  return t;
}

std::string name_of(std::mt19937_64& g, const char* prefix, int i) {
  static const char* syl[] = {"ka", "ro", "mi", "tu", "ze", "lo", "fa", "ni", "su", "ve"};
  return std::string(prefix) + syl[g() % 10] + syl[g() % 10] + std::to_string(i);
}

// An effect's `at` parameters (the simulated root it moves) match a finding's within this,
// relative.
constexpr double kAtRel = 1e-3;

}  // namespace

std::string HiddenEffect::describe() const {
  std::ostringstream s;
  s << to_string(cause) << " [" << to_string(scope) << (input.empty() ? "" : " " + input)
    << (output.empty() ? "" : " " + output) << "] " << (param ? to_string(*param) : "") << "="
    << value;
  for (const auto& [k, v] : text) s << " " << k << "=" << v;
  for (const auto& [k, v] : exact) s << " " << to_string(k) << "=" << v;
  for (const auto& [k, v] : at) s << " " << to_string(k) << "=" << v;
  return s.str();
}

bool HiddenEffect::matches(const Finding& f) const {
  if (f.cause != cause || f.scope != scope || f.input != input || f.output != output) return false;
  if (!param) return true;
  const auto it = f.parameters.find(*param);
  if (it == f.parameters.end()) return false;
  const double tol = std::max(tol_abs, tol_rel * std::abs(value));
  for (const auto& [k, v] : text) {
    const auto t = f.text_parameters.find(k);
    if (t == f.text_parameters.end() || t->second != v) return false;
  }
  for (const auto& [k, v] : exact) {
    const auto x = f.parameters.find(k);
    if (x == f.parameters.end() || x->second != v) return false;
  }
  for (const auto& [k, v] : at) {
    const auto x = f.parameters.find(k);
    if (x == f.parameters.end() || !(std::abs(x->second / v - 1) <= kAtRel)) return false;
  }
  return std::abs(it->second - value) <= tol;
}

RandomCase random_case(uint64_t seed, int index, int n_hidden) {
  std::mt19937_64 g(seed * 1000003u + uint64_t(index));
  std::mt19937_64 g_path(seed * 7919u + uint64_t(index) * 104729u + 17u);
  std::uniform_real_distribution<double> u(0, 1);
  auto logu = [&](double lo, double hi) { return lo * std::pow(hi / lo, u(g)); };
  RandomCase c;
  c.name = "case" + std::to_string(index);
  Model& m = c.simulation;
  m.name = "random plant " + std::to_string(index);
  const int ni = 1 + int(g() % 3), no = 2 + int(g() % 3);
  for (int i = 0; i < ni; ++i) {
    ModelInput in;
    in.name = name_of(g, "U", i);
    in.units = "1";
    in.full_scale = 10.0;
    in.noise_rms = u(g) < 0.5 ? 0.0 : 0.001;  // clean or noisy position channel
    in.actuator = lag(logu(15, 60));
    m.inputs.push_back(in);
    m.steady_state[in.name] = 5.0;
  }
  for (int o = 0; o < no; ++o) {
    ModelOutput out;
    out.name = name_of(g, "Y", o);
    out.units = "1";
    out.noise_rms = logu(0.0005, 0.003);
    if (u(g) < 0.3) out.sensor = lag(logu(40, 120));
    m.outputs.push_back(out);
    m.steady_state[out.name] = 50.0;
  }
  for (const auto& in : m.inputs)
    for (const auto& out : m.outputs) {
      Tf t = lag(logu(0.5, 8), (u(g) < 0.3 ? -1 : 1) * logu(0.5, 3));
      if (u(g) < 0.4) t.poles.push_back(Root::Real(-logu(10, 40)));
      if (u(g) < 0.2) t.poles.push_back(Root::Pair(logu(8, 30), logu(0.15, 0.5)));
      m.paths.push_back({out.name, in.name, t, Json::object()});
    }
  c.engine = m;
  const int nh = n_hidden >= 0 ? n_hidden : int(g() % 3);
  std::vector<std::string> used;  // one effect per path or input, so each is identifiable
  for (int h = 0; h < nh; ++h) {
    const std::string in = m.inputs[g() % ni].name, out = m.outputs[g() % no].name;
    ModelPath* ep = c.engine.path(out, in);
    // A path the simulation lacks (kind 11) is drawn from its own generator, 1 effect in 12, so
    // the other kinds' cases are the same sequence with or without it.
    int kind = int(g() % 11);
    if (g_path() % 12 == 0) kind = 11;
    const bool at_input = kind == 4 || kind == 5;
    const bool at_output = kind == 10;
    const std::string key = at_input ? "in:" + in : at_output ? "out:" + out : in + ":" + out;
    bool clash = false;
    for (const auto& k : used) {
      const bool k_input = k.rfind("in:", 0) == 0, k_output = k.rfind("out:", 0) == 0;
      clash |= k == key || k == "in:" + in || (at_input && k.rfind(in + ":", 0) == 0);
      // an output's sensor touches every path into it
      clash |= k_output || (at_output && !k_input && k.size() > out.size() &&
                            k.compare(k.size() - out.size() - 1, out.size() + 1, ":" + out) == 0);
      clash |= at_output && k_input;
    }
    if (clash) continue;
    used.push_back(key);
    HiddenEffect e{};
    e.input = in;
    e.output = out;
    e.scope = Scope::kPath;
    switch (kind) {
      case 0:  // a delay in one path
        e.cause = CauseKind::kTimeDelay, e.param = Param::kDelayS, e.value = logu(0.005, 0.03);
        e.tol_abs = 0.5e-3, e.tol_rel = 0.1;
        ep->tf.delay_s = e.value;
        break;
      case 1:  // a lag the simulation lacks
        e.cause = CauseKind::kMissingLag, e.param = Param::kCornerRadS, e.value = logu(2, 30);
        e.tol_rel = 0.1;
        ep->tf.poles.push_back(Root::Real(-e.value));
        break;
      case 2: {  // a gain error
        const double db = (u(g) < 0.5 ? -1 : 1) * logu(1.5, 4);
        e.cause = CauseKind::kGainMismatch, e.param = Param::kGainDb, e.value = db, e.tol_abs = 0.3;
        ep->tf.gain *= std::pow(10.0, db / 20);
        break;
      }
      case 3: {  // a path pole in the wrong place
        const double from = -ep->tf.poles[0].real, to = from * logu(1.6, 3);
        e.cause = CauseKind::kPoleShift, e.param = Param::kToRadS, e.value = to, e.tol_rel = 0.1;
        ep->tf.poles[0].real = -to;
        break;
      }
      case 4: {  // the actuator's pole
        ModelInput& ein = c.engine.inputs[c.engine.input_index(in)];
        const double from = -ein.actuator->poles[0].real, to = from * logu(1.8, 3);
        e.cause = CauseKind::kPoleShift, e.scope = Scope::kInput, e.output = "";
        e.param = Param::kToRadS, e.value = to, e.tol_rel = 0.1;
        ein.actuator->poles[0].real = -to;
        break;
      }
      case 5: {  // the actuator's backlash (2 % amplitude = 0.2: width 0.03-0.08)
        ModelInput& ein = c.engine.inputs[c.engine.input_index(in)];
        e.cause = CauseKind::kHysteresis, e.scope = Scope::kInput, e.output = "";
        e.param = Param::kWidth, e.value = logu(0.03, 0.08), e.tol_rel = 0.25;
        ein.nonlinearity.push_back({NonlinearityKind::kHysteresis, e.value});
        break;
      }
      case 6: {  // a lead (a real zero) the simulation lacks
        e.cause = CauseKind::kMissingLead, e.param = Param::kCornerRadS, e.value = logu(2, 20);
        e.tol_rel = 0.1;
        ep->tf.zeros.push_back(Root::Real(-e.value));
        break;
      }
      case 7: {  // a resonance the simulation lacks
        e.cause = CauseKind::kMissingResonance, e.param = Param::kWnRadS, e.value = logu(3, 40);
        e.tol_rel = 0.1;
        ep->tf.poles.push_back(Root::Pair(e.value, logu(0.1, 0.3)));
        break;
      }
      case 8: {  // the path's sign
        e.cause = CauseKind::kSignError, e.param = Param::kSign, e.value = -1, e.tol_abs = 1e-9;
        ep->tf.gain = -ep->tf.gain;
        break;
      }
      case 9: {  // the damping of a pair (one is added to both models when the path has none)
        Root* pr = nullptr;
        for (auto& r : ep->tf.poles)
          if (r.pair) pr = &r;
        if (!pr) {
          const Root pair = Root::Pair(logu(5, 25), 0.4);
          ep->tf.poles.push_back(pair);
          c.simulation.path(out, in)->tf.poles.push_back(pair);
          pr = &ep->tf.poles.back();
        }
        e.cause = CauseKind::kDampingError, e.param = Param::kToZeta,
        e.value = pr->zeta * logu(0.15, 0.4);
        e.tol_rel = 0.15;
        pr->zeta = e.value;
        break;
      }
      case 11: {  // a path the simulation lacks: the engine responds there, the simulation not
        e.cause = CauseKind::kMissingPath, e.param = Param::kGain, e.value = ep->tf.gain;
        e.tol_rel = 0.1;
        auto& sp = c.simulation.paths;
        sp.erase(
            std::remove_if(sp.begin(), sp.end(),
                           [&](const ModelPath& p) { return p.input == in && p.output == out; }),
            sp.end());
        break;
      }
      case 10: {  // a sensor lag: every path into the output, reported once (scope output)
        ModelOutput& eo = c.engine.outputs[c.engine.output_index(out)];
        e.cause = CauseKind::kMissingLag, e.param = Param::kCornerRadS, e.value = logu(3, 30);
        e.tol_rel = 0.1;
        if (ni > 1) e.scope = Scope::kOutput, e.input = "";  // one path alone: that path's
        if (!eo.sensor) eo.sensor = Tf{};
        eo.sensor->poles.push_back(Root::Real(-e.value));
        break;
      }
    }
    c.hidden.push_back(e);
  }
  return c;
}

bool set_hidden_parameter(Model& engine, const HiddenEffect& e, double value) {
  const double old = e.value;
  auto same = [&](double v) { return std::abs(v - old) <= 1e-12 * std::abs(old); };
  // The real root at -old among `roots`, moved to -value.
  auto move_real = [&](std::vector<Root>& roots) {
    for (Root& r : roots)
      if (!r.pair && same(-r.real)) {
        r.real = -value;
        return true;
      }
    return false;
  };
  ModelPath* p = engine.path(e.output, e.input);
  const int in = engine.input_index(e.input), out = engine.output_index(e.output);
  switch (e.cause) {
    case CauseKind::kTimeDelay:
      if (!p) return false;
      p->tf.delay_s = value;
      return true;
    case CauseKind::kGainMismatch:
      if (!p) return false;
      p->tf.gain *= std::pow(10.0, (value - old) / 20);
      return true;
    case CauseKind::kMissingLag:  // in the path, else in the output's sensor
      if (p && move_real(p->tf.poles)) return true;
      return out >= 0 && engine.outputs[size_t(out)].sensor &&
             move_real(engine.outputs[size_t(out)].sensor->poles);
    case CauseKind::kMissingLead:
      return p && move_real(p->tf.zeros);
    case CauseKind::kPoleShift:
      if (e.scope == Scope::kInput)
        return in >= 0 && engine.inputs[size_t(in)].actuator &&
               move_real(engine.inputs[size_t(in)].actuator->poles);
      return p && move_real(p->tf.poles);
    case CauseKind::kHysteresis:
      if (in < 0) return false;
      for (NonlinearitySpec& n : engine.inputs[size_t(in)].nonlinearity)
        if (n.kind == NonlinearityKind::kHysteresis) {
          n.width = value;
          return true;
        }
      return false;
    case CauseKind::kMissingResonance:
    case CauseKind::kDampingError:
      if (!p) return false;
      for (Root& r : p->tf.poles)
        if (r.pair && same(e.cause == CauseKind::kDampingError ? r.zeta : r.wn)) {
          (e.cause == CauseKind::kDampingError ? r.zeta : r.wn) = value;
          return true;
        }
      return false;
    default:
      return false;
  }
}

std::optional<std::array<double, 2>> two_sigma_interval(const Finding& f,
                                                        std::optional<Param> param) {
  if (!param) return std::nullopt;
  const auto v = f.parameters.find(*param);
  const auto iv = f.intervals.find(*param);
  if (v == f.parameters.end() || iv == f.intervals.end() || !std::isfinite(iv->second[0]) ||
      !std::isfinite(iv->second[1]))
    return std::nullopt;
  return std::array<double, 2>{v->second - 2 * (v->second - iv->second[0]),
                               v->second + 2 * (iv->second[1] - v->second)};
}

Score score(const RandomCase& c, const std::vector<Finding>& findings) {
  Score s;
  s.findings = int(findings.size());
  s.hidden = int(c.hidden.size());
  for (const auto& f : findings) {
    bool ok = false;
    for (const auto& h : c.hidden) ok |= h.matches(f);
    if (ok) {
      ++s.true_findings;
    } else {
      std::ostringstream d;
      d << to_string(f.cause) << " [" << to_string(f.scope) << " " << f.input << " " << f.output
        << "]";
      for (const auto& [k, v] : f.parameters) d << " " << to_string(k) << "=" << v;
      s.false_findings.push_back(d.str());
    }
  }
  for (const auto& h : c.hidden) {
    const Finding* match = nullptr;
    for (const auto& f : findings)
      if (!match && h.matches(f)) match = &f;
    if (!match) {
      s.missed.push_back(h.describe());
      continue;
    }
    ++s.found;
    const auto two = two_sigma_interval(*match, h.param);
    if (!two) continue;
    ++s.with_interval;
    const auto [lo, hi] = *two;
    if (h.value >= lo && h.value <= hi) {
      ++s.in_two_sigma;
    } else {
      std::ostringstream d;
      d << h.describe() << ": found " << match->parameters.at(*h.param) << ", 2-sigma " << lo
        << " .. " << hi;
      s.outside_two_sigma.push_back(d.str());
    }
  }
  return s;
}

}  // namespace fralab::testing
