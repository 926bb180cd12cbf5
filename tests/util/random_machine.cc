#include "random_machine.h"

#include <algorithm>
#include <cmath>
#include <random>

namespace fralab::testing {

RandomCase random_machine_case(uint64_t seed, int index, int n_hidden, int inputs, int outputs) {
  std::mt19937_64 g(seed * 2654435761u + uint64_t(index) * 40503u + 7u);
  std::uniform_real_distribution<double> u(0, 1);
  auto logu = [&](double lo, double hi) { return lo * std::pow(hi / lo, u(g)); };
  RandomCase c;
  c.name = "machine" + std::to_string(index);
  Model& m = c.simulation;
  m.name = "random machine " + std::to_string(index);
  m.speed_pct = 90;
  const int ni_drawn = 1 + int(g() % 3), no_drawn = 2 + int(g() % 4);
  const int ni = inputs > 0 ? inputs : ni_drawn, no = outputs > 0 ? outputs : no_drawn;
  static const char* in_units[] = {"mm", "deg", "lb/hr"};
  static const double in_scale[] = {10.0, 100.0, 3000.0};
  for (int i = 0; i < ni; ++i) {
    ModelInput in;
    in.name = "U" + std::to_string(i);
    const int k = int(g() % 3);
    in.units = in_units[k];
    in.full_scale = in_scale[k];
    in.test_amplitude_pct = 2;
    Tf a;
    a.poles = {Root::Real(-logu(15, 60))};
    in.actuator = a;
    m.inputs.push_back(in);
    m.steady_state[in.name] = 0.5 * in.full_scale;
  }
  static const char* out_units[] = {"psia", "rpm", "degR", "1"};
  static const double out_scale[] = {0.5, 500.0, 50.0, 0.01};  // a strong path's gain per unit
  const double rotor = logu(0.3, 3.0);                         // the slow mode, s
  for (int o = 0; o < no; ++o) {
    ModelOutput out;
    out.name = "Y" + std::to_string(o);
    const int k = int(g() % 4);
    out.units = out_units[k];
    const double fast = logu(10, 60);  // the fast dynamics of every path into this output
    double strongest = 0;
    for (int i = 0; i < ni; ++i) {
      const ModelInput& in = m.inputs[size_t(i)];
      const bool weak = u(g) < 0.25;
      const double gain = out_scale[k] / in.full_scale * 10 * logu(0.5, 2) *
                          (weak ? logu(0.03, 0.1) : 1.0) * (u(g) < 0.3 ? -1 : 1);
      Tf t;
      t.gain = gain;
      t.poles = {Root::Real(-1 / rotor), Root::Real(-fast)};
      if (u(g) < 0.3) t.zeros = {Root::Real(-logu(0.5, 5) / rotor)};
      m.paths.push_back({out.name, in.name, t, Json::object()});
      strongest = std::max(strongest, std::abs(gain) * in.full_scale * 0.02);
    }
    out.noise_rms = strongest * logu(0.003, 0.01);
    m.outputs.push_back(out);
    m.steady_state[out.name] = 100 * out_scale[k];
  }
  c.engine = m;
  const int nh = n_hidden >= 0 ? n_hidden : int(g() % 4);
  // Places taken, so that each hidden effect stays identifiable: one effect of a kind per place.
  std::vector<std::string> used;
  std::vector<int> kinds;  // per hidden effect, the kind drawn
  auto take = [&](const std::string& key) {
    if (std::find(used.begin(), used.end(), key) != used.end()) return false;
    used.push_back(key);
    return true;
  };
  for (int h = 0; h < nh; ++h) {
    const std::string in = m.inputs[g() % size_t(ni)].name;
    const std::string out = m.outputs[g() % size_t(no)].name;
    const int kind = int(g() % 10);
    HiddenEffect e{};
    e.input = in, e.output = out, e.scope = Scope::kPath;
    switch (kind) {
      case 0: {  // a sensor lag: every path into the output
        if (!take("sensor-lag:" + out) || !take("sensor:" + out)) continue;
        ModelOutput& eo = c.engine.outputs[size_t(c.engine.output_index(out))];
        e.cause = CauseKind::kMissingLag, e.param = Param::kCornerRadS, e.value = logu(3, 30);
        e.tol_rel = 0.1;
        if (ni > 1) e.scope = Scope::kOutput, e.input = "";
        if (!eo.sensor) eo.sensor = Tf{};
        eo.sensor->poles.push_back(Root::Real(-e.value));
        break;
      }
      case 1: {  // a sensor's delay
        if (!take("sensor-delay:" + out)) continue;
        ModelOutput& eo = c.engine.outputs[size_t(c.engine.output_index(out))];
        e.cause = CauseKind::kTimeDelay, e.param = Param::kDelayS, e.value = logu(0.005, 0.03);
        e.tol_abs = 0.5e-3, e.tol_rel = 0.1;
        if (ni > 1) e.scope = Scope::kOutput, e.input = "";
        if (!eo.sensor) eo.sensor = Tf{};
        eo.sensor->delay_s += e.value;
        break;
      }
      case 2: {  // an input's calibration: every path from it
        if (!take("gain-in:" + in)) continue;
        const double db = (u(g) < 0.5 ? -1 : 1) * logu(1.5, 4);
        e.cause = CauseKind::kGainMismatch, e.param = Param::kGainDb, e.value = db, e.tol_abs = 0.3;
        // Every path from the input; with one input that is every path: the plant's, once the
        // scope stage sees three pairs or more.
        e.scope = ni == 1 && no >= 3 ? Scope::kPlant : Scope::kInput, e.output = "";
        if (e.scope == Scope::kPlant) e.input = "";
        for (auto& p : c.engine.paths)
          if (p.input == in) p.tf.gain *= std::pow(10.0, db / 20);
        break;
      }
      case 3: {  // an output's calibration: every path into it
        if (!take("gain-out:" + out)) continue;
        const double db = (u(g) < 0.5 ? -1 : 1) * logu(1.5, 4);
        e.cause = CauseKind::kGainMismatch, e.param = Param::kGainDb, e.value = db, e.tol_abs = 0.3;
        if (ni > 1) e.scope = Scope::kOutput, e.input = "";
        for (auto& p : c.engine.paths)
          if (p.output == out) p.tf.gain *= std::pow(10.0, db / 20);
        break;
      }
      case 4: {  // the actuator's pole
        if (!take("actuator-pole:" + in)) continue;
        ModelInput& ein = c.engine.inputs[size_t(c.engine.input_index(in))];
        const double from = -ein.actuator->poles[0].real, to = from * logu(1.8, 3);
        e.cause = CauseKind::kPoleShift, e.scope = Scope::kInput, e.output = "";
        e.param = Param::kToRadS, e.value = to, e.tol_rel = 0.1;
        ein.actuator->poles[0].real = -to;
        break;
      }
      case 5: {  // the actuator's backlash, 0.3-0.8 % of full scale (2 % amplitude)
        if (!take("backlash:" + in)) continue;
        ModelInput& ein = c.engine.inputs[size_t(c.engine.input_index(in))];
        e.cause = CauseKind::kHysteresis, e.scope = Scope::kInput, e.output = "";
        e.param = Param::kWidth, e.value = ein.full_scale * logu(0.003, 0.008), e.tol_rel = 0.25;
        ein.nonlinearity.push_back({NonlinearityKind::kHysteresis, e.value});
        break;
      }
      case 6: {  // the rotor's mode, moved in every path
        if (!take("rotor")) continue;
        const double to = (1 / rotor) * logu(1.5, 2.5);
        e.cause = CauseKind::kPoleShift, e.param = Param::kToRadS, e.value = to, e.tol_rel = 0.1;
        // Every path: the plant's from three pairs on; a 1 x 2 plant's two paths are its input's.
        e.scope = ni * no >= 3 ? Scope::kPlant : Scope::kInput;
        e.output = "";
        if (e.scope == Scope::kPlant) e.input = "";
        for (auto& p : c.engine.paths) p.tf.poles[0].real = -to;
        break;
      }
      case 7: {  // a path's delay
        if (!take("path-delay:" + in + ":" + out)) continue;
        e.cause = CauseKind::kTimeDelay, e.param = Param::kDelayS, e.value = logu(0.005, 0.03);
        e.tol_abs = 0.5e-3, e.tol_rel = 0.1;
        c.engine.path(out, in)->tf.delay_s += e.value;
        break;
      }
      case 8: {  // a path's missing lag
        if (!take("path-lag:" + in + ":" + out)) continue;
        e.cause = CauseKind::kMissingLag, e.param = Param::kCornerRadS, e.value = logu(2, 30);
        e.tol_rel = 0.1;
        c.engine.path(out, in)->tf.poles.push_back(Root::Real(-e.value));
        break;
      }
      case 9: {  // a path the simulation lacks
        if (!take("path-missing:" + in + ":" + out)) continue;
        e.cause = CauseKind::kMissingPath, e.param = Param::kGain;
        e.value = c.engine.path(out, in)->tf.gain;
        e.tol_rel = 0.1;
        auto& sp = c.simulation.paths;
        sp.erase(
            std::remove_if(sp.begin(), sp.end(),
                           [&](const ModelPath& p) { return p.input == in && p.output == out; }),
            sp.end());
        break;
      }
    }
    c.hidden.push_back(e);
    kinds.push_back(kind);
  }
  // A missing path's gain is the engine's path as the other effects left it (a calibration over
  // it scales it too).
  for (HiddenEffect& e : c.hidden)
    if (e.cause == CauseKind::kMissingPath) e.value = c.engine.path(e.output, e.input)->tf.gain;
  // The scope a finding can have is set by the paths the simulation has (a path it lacks is fitted
  // as a path of its own, effects included): every path from three on is the plant's; two or
  // more into one output, that output's; from one input, that input's; one path alone, its own.
  for (size_t h = 0; h < c.hidden.size(); ++h) {
    HiddenEffect& e = c.hidden[h];
    if (kinds[h] != 0 && kinds[h] != 1 && kinds[h] != 2 && kinds[h] != 3 && kinds[h] != 6)
      continue;  // an actuator's own pair, or one path
    std::vector<const ModelPath*> covered;
    for (const ModelPath& p : c.simulation.paths)
      if (e.scope == Scope::kPlant || (e.scope == Scope::kInput && p.input == e.input) ||
          (e.scope == Scope::kOutput && p.output == e.output) ||
          (e.scope == Scope::kPath && p.output == e.output))  // a sensor's on a 1-input plant
        covered.push_back(&p);
    bool one_input = !covered.empty(), one_output = !covered.empty();
    for (const ModelPath* p : covered) {
      one_input &= p->input == covered[0]->input;
      one_output &= p->output == covered[0]->output;
    }
    if (covered.size() == c.simulation.paths.size() && covered.size() >= 3)
      e.scope = Scope::kPlant, e.input = "", e.output = "";
    else if (covered.size() >= 2 && one_output)
      e.scope = Scope::kOutput, e.input = "", e.output = covered[0]->output;
    else if (covered.size() >= 2 && one_input)
      e.scope = Scope::kInput, e.input = covered[0]->input, e.output = "";
    else if (covered.size() == 1)
      e.scope = Scope::kPath, e.input = covered[0]->input, e.output = covered[0]->output;
  }
  // Two gains or two delays at one place (an output's delay and its one path's on a one-input
  // plant) are one effect there, their sum: no measurement tells them apart.
  for (size_t h = 0; h < c.hidden.size(); ++h)
    for (size_t k = h + 1; k < c.hidden.size(); ++k) {
      HiddenEffect &a = c.hidden[h], &b = c.hidden[k];
      if ((a.cause != CauseKind::kGainMismatch && a.cause != CauseKind::kTimeDelay) ||
          a.cause != b.cause || a.scope != b.scope || a.input != b.input || a.output != b.output)
        continue;
      a.value += b.value;
      a.tol_abs = std::max(a.tol_abs, b.tol_abs), a.tol_rel = std::max(a.tol_rel, b.tol_rel);
      c.hidden.erase(c.hidden.begin() + long(k));
      --k;
    }
  // An effect on one path the simulation lacks is inside that missing path's fit: not a finding
  // of its own.
  std::vector<HiddenEffect> kept;
  for (const HiddenEffect& e : c.hidden)
    if (e.cause == CauseKind::kMissingPath || e.scope != Scope::kPath ||
        c.simulation.path(e.output, e.input))
      kept.push_back(e);
  c.hidden = kept;
  return c;
}

RandomCase random_machine_case_with_fault(uint64_t seed, int index, const std::string& output,
                                          const ChannelFault& f) {
  RandomCase c = random_machine_case(seed, index, 0);
  c.engine.outputs[size_t(c.engine.output_index(output))].faults = {f};
  return c;
}

}  // namespace fralab::testing
