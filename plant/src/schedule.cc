#include "fralab/plant/schedule.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <regex>

#include "fralab/core/error.h"
#include "fralab/core/text.h"
#include "fralab/plant/embedded_models.h"

namespace fralab {

namespace fs = std::filesystem;

namespace {

std::string num(double v) { return significant(v, 6); }

double linear(double a, double b, double t) { return a + (b - a) * t; }

// log |v| linear in t when a and b have one sign (gains, time constants, natural frequencies).
double geometric(double a, double b, double t) {
  if (a == b) return a;
  if (a * b > 0)
    return std::copysign(std::exp(linear(std::log(std::abs(a)), std::log(std::abs(b)), t)), a);
  return linear(a, b, t);
}

// A group of roots as one quadratic factor a2 s^2 + a1 s + 1 (a pair, two real roots, or one real
// root with a2 = 0: its second root at infinity), for a pair at one point whose partner at the
// other is one or two real roots. Blended coefficient by coefficient: a1, a2 > 0 (stable roots)
// stay so, and the group's order is the larger of its two sides'.
struct Quadratic {
  double a1 = 0, a2 = 0;
};

Quadratic quadratic_of_pair(const Root& p) { return {2 * p.zeta / p.wn, 1 / (p.wn * p.wn)}; }

// One or two real roots: (1 - s/r1)(1 - s/r2) = 1 - (1/r1 + 1/r2) s + s^2 / (r1 r2).
Quadratic quadratic_of_reals(const std::vector<Root>& rs) {
  const Root &r1 = rs.front(), &r2 = rs.back();
  if (rs.size() == 1) return {-1 / r1.real, 0};
  return {-(1 / r1.real + 1 / r2.real), 1 / (r1.real * r2.real)};
}

void push_roots_of(const Quadratic& q, std::vector<Root>& out) {
  if (q.a2 == 0) {
    if (q.a1 != 0) out.push_back(Root::Real(-1 / q.a1));
    return;
  }
  const double d = q.a1 * q.a1 - 4 * q.a2;
  if (d < 0) {  // a2 > 0 here
    const double wn = 1 / std::sqrt(q.a2);
    out.push_back(Root::Pair(wn, q.a1 * wn / 2));
    return;
  }
  const double e = std::sqrt(d);
  out.push_back(Root::Real((-q.a1 - e) / (2 * q.a2)));
  out.push_back(Root::Real((-q.a1 + e) / (2 * q.a2)));
}

double scale_of(const Root& r) { return r.pair ? r.wn : std::abs(r.real); }
double log_distance(const Root& a, const Root& b) {
  return std::abs(std::log(scale_of(a) / scale_of(b)));
}

// One tf's roots (zeros, or poles) between two points: matched along their tracks (real with
// real, pair with pair, nearest first; then a pair left at one point with the one or two real
// roots left nearest it at the other), the rest faded.
std::vector<Root> blend_roots(const std::vector<Root>& a, const std::vector<Root>& b, double t) {
  struct Candidate {
    double d;
    size_t i, j;
  };
  std::vector<Candidate> c;
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j)
      if (a[i].pair == b[j].pair) c.push_back({log_distance(a[i], b[j]), i, j});
  std::stable_sort(c.begin(), c.end(),
                   [](const Candidate& p, const Candidate& q) { return p.d < q.d; });
  std::vector<bool> used_a(a.size(), false), used_b(b.size(), false);
  std::vector<Root> out;
  for (const Candidate& k : c) {
    if (used_a[k.i] || used_b[k.j]) continue;
    used_a[k.i] = used_b[k.j] = true;
    const Root &r = a[k.i], &q = b[k.j];
    if (r.pair) {
      out.push_back(Root::Pair(geometric(r.wn, q.wn, t), linear(r.zeta, q.zeta, t)));
    } else {
      const double tau = geometric(-1 / r.real, -1 / q.real, t);
      if (tau != 0) out.push_back(Root::Real(-1 / tau));  // tau = 0: at infinity, factor 1
    }
  }
  // A pair left on one side with the real roots left on the other.
  auto mixed = [&](const std::vector<Root>& ps, std::vector<bool>& used_p,
                   const std::vector<Root>& rs, std::vector<bool>& used_r, bool pairs_at_lo) {
    for (size_t i = 0; i < ps.size(); ++i) {
      if (used_p[i] || !ps[i].pair) continue;
      std::vector<Root> group;
      for (int k = 0; k < 2; ++k) {
        int best = -1;
        for (size_t j = 0; j < rs.size(); ++j)
          if (!used_r[j] && !rs[j].pair &&
              (best < 0 || log_distance(ps[i], rs[j]) < log_distance(ps[i], rs[size_t(best)])))
            best = int(j);
        if (best < 0) break;
        used_r[size_t(best)] = true;
        group.push_back(rs[size_t(best)]);
      }
      if (group.empty()) return;
      used_p[i] = true;
      const Quadratic qp = quadratic_of_pair(ps[i]), qr = quadratic_of_reals(group);
      const Quadratic &lo = pairs_at_lo ? qp : qr, &hi = pairs_at_lo ? qr : qp;
      push_roots_of({linear(lo.a1, hi.a1, t), linear(lo.a2, hi.a2, t)}, out);
    }
  };
  mixed(a, used_a, b, used_b, true);
  mixed(b, used_b, a, used_a, false);
  for (size_t i = 0; i < a.size(); ++i) {  // fades towards hi, where its factor is 1
    if (used_a[i]) continue;
    const Root& r = a[i];
    out.push_back(r.pair ? Root::Pair(r.wn / (1 - t), r.zeta) : Root::Real(r.real / (1 - t)));
  }
  for (size_t j = 0; j < b.size(); ++j) {  // fades towards lo
    if (used_b[j]) continue;
    const Root& q = b[j];
    out.push_back(q.pair ? Root::Pair(q.wn / t, q.zeta) : Root::Real(q.real / t));
  }
  return out;
}

Tf blend_tf(const Tf& a, const Tf& b, double t) {
  Tf r = a;
  r.gain = geometric(a.gain, b.gain, t);
  r.delay_s = linear(a.delay_s, b.delay_s, t);
  r.zeros = blend_roots(a.zeros, b.zeros, t);
  r.poles = blend_roots(a.poles, b.poles, t);
  return r;
}

std::optional<Tf> blend_optional(const std::optional<Tf>& a, const std::optional<Tf>& b, double t) {
  if (!a && !b) return std::nullopt;
  return blend_tf(a.value_or(Tf{}), b.value_or(Tf{}), t);
}

// Numbers of two JSON objects present in both, linearly; the rest as lo has it.
Json blend_numbers(const Json& a, const Json& b, double t) {
  Json r = a;
  if (!a.is_object() || !b.is_object()) return r;
  for (auto it = a.begin(); it != a.end(); ++it)
    if (it->is_number() && b.contains(it.key()) && b[it.key()].is_number())
      r[it.key()] = linear(it->get<double>(), b[it.key()].get<double>(), t);
  return r;
}

class Interpolation {
 public:
  Interpolation(const SetModel& lo, const SetModel& hi, double x, const InterpolationOptions& o)
      : lo_(lo), hi_(hi), x_(x), o_(o), t_((x - lo.x) / (hi.x - lo.x)) {}

  Model run() {
    Model m = lo_.model;
    m.name = lo_.model.name + " .. " + hi_.model.name + ", interpolated at " + o_.schedule_by +
             " " + num(x_);
    m.source = lo_.spec + " .. " + hi_.spec + " at " + o_.schedule_by + " " + num(x_);
    m.warnings.clear();
    m.speed_pct =
        o_.schedule_by == "speed_pct" ? x_ : linear(lo_.model.speed_pct, hi_.model.speed_pct, t_);
    m.operating_point_extra =
        blend_numbers(lo_.model.operating_point_extra, hi_.model.operating_point_extra, t_);
    if (o_.schedule_by != "speed_pct") m.operating_point_extra[o_.schedule_by] = x_;
    for (auto& [ch, v] : m.steady_state) {
      const auto it = hi_.model.steady_state.find(ch);
      if (it != hi_.model.steady_state.end()) v = linear(v, it->second, t_);
    }
    inputs(m);
    outputs(m);
    paths(m);
    const std::vector<std::string> said = m.warnings;
    Model checked = parse_model(model_to_json(m), m.source);  // a model the plant can run
    checked.source = m.source;
    checked.warnings = said;
    return checked;
  }

 private:
  std::string where(const std::string& what, bool at_hi) const {
    const SetModel& s = at_hi ? hi_ : lo_;
    return what + " of " + s.spec + " (" + o_.schedule_by + " " + num(s.x) + ") but not of " +
           (at_hi ? lo_ : hi_).spec;
  }

  // A channel present at one point only: refused, or left out and said.
  bool keep_unmatched(const std::string& what, bool at_hi, Model& m) const {
    const std::string text = where(what, at_hi);
    if (!o_.common_channels_only)
      throw InputError(text + ": the models between " + num(lo_.x) + " and " + num(hi_.x) +
                       " cannot be interpolated");
    m.warnings.push_back(text + ": left out");
    return false;
  }

  void inputs(Model& m) {
    m.inputs.clear();
    for (const ModelInput& a : lo_.model.inputs) {
      const int j = hi_.model.input_index(a.name);
      if (j < 0) {
        keep_unmatched("input " + a.name, false, m);
        continue;
      }
      const ModelInput& b = hi_.model.inputs[size_t(j)];
      if (a.units != b.units)
        throw InputError("input " + a.name + ": units " + a.units + " in " + lo_.spec + ", " +
                         b.units + " in " + hi_.spec);
      ModelInput r = a;
      r.full_scale = linear(a.full_scale, b.full_scale, t_);
      r.noise_rms = linear(a.noise_rms, b.noise_rms, t_);
      if (a.test_amplitude_pct > 0 && b.test_amplitude_pct > 0)
        r.test_amplitude_pct = linear(a.test_amplitude_pct, b.test_amplitude_pct, t_);
      else
        r.test_amplitude_pct = std::max(a.test_amplitude_pct, b.test_amplitude_pct);
      r.actuator = blend_optional(a.actuator, b.actuator, t_);
      r.nonlinearity = nonlinearities(a, b);
      r.measurement_coupling.clear();
      for (const MeasurementCoupling& c : a.measurement_coupling) {
        double g = 0;
        for (const MeasurementCoupling& d : b.measurement_coupling)
          if (d.output == c.output) g = d.gain;
        r.measurement_coupling.push_back({c.output, linear(c.gain, g, t_)});
      }
      for (const MeasurementCoupling& d : b.measurement_coupling) {
        bool known = false;
        for (const MeasurementCoupling& c : a.measurement_coupling) known |= c.output == d.output;
        if (!known) r.measurement_coupling.push_back({d.output, d.gain * t_});
      }
      m.inputs.push_back(r);
    }
    for (const ModelInput& b : hi_.model.inputs)
      if (lo_.model.input_index(b.name) < 0) keep_unmatched("input " + b.name, true, m);
  }

  std::vector<NonlinearitySpec> nonlinearities(const ModelInput& a, const ModelInput& b) const {
    auto kinds = [](const ModelInput& in) {
      std::string s;
      for (const auto& n : in.nonlinearity)
        s += (s.empty() ? "" : ", ") + std::string(to_string(n.kind));
      return s.empty() ? std::string("none") : s;
    };
    if (kinds(a) != kinds(b))
      throw InputError("input " + a.name + ": nonlinearities " + kinds(a) + " in " + lo_.spec +
                       ", " + kinds(b) + " in " + hi_.spec + ": they cannot be interpolated");
    std::vector<NonlinearitySpec> r = a.nonlinearity;
    for (size_t k = 0; k < r.size(); ++k) {
      const NonlinearitySpec& q = b.nonlinearity[k];
      r[k].width = linear(r[k].width, q.width, t_);
      r[k].rate = linear(r[k].rate, q.rate, t_);
      r[k].min = linear(r[k].min, q.min, t_);
      r[k].max = linear(r[k].max, q.max, t_);
    }
    return r;
  }

  void outputs(Model& m) {
    m.outputs.clear();
    for (const ModelOutput& a : lo_.model.outputs) {
      const int j = hi_.model.output_index(a.name);
      if (j < 0) {
        keep_unmatched("output " + a.name, false, m);
        continue;
      }
      const ModelOutput& b = hi_.model.outputs[size_t(j)];
      if (a.units != b.units)
        throw InputError("output " + a.name + ": units " + a.units + " in " + lo_.spec + ", " +
                         b.units + " in " + hi_.spec);
      ModelOutput r = a;
      r.noise_rms = linear(a.noise_rms, b.noise_rms, t_);
      r.sensor = blend_optional(a.sensor, b.sensor, t_);
      m.outputs.push_back(r);
    }
    for (const ModelOutput& b : hi_.model.outputs)
      if (lo_.model.output_index(b.name) < 0) keep_unmatched("output " + b.name, true, m);
  }

  void paths(Model& m) {
    m.paths.clear();
    auto kept = [&](const ModelPath& p) {
      return m.input_index(p.input) >= 0 && m.output_index(p.output) >= 0;
    };
    for (const ModelPath& a : lo_.model.paths) {
      if (!kept(a)) continue;
      ModelPath r = a;
      if (const ModelPath* b = hi_.model.path(a.output, a.input)) {
        r.tf = blend_tf(a.tf, b->tf, t_);
      } else {
        r.tf.gain = a.tf.gain * (1 - t_);
      }
      m.paths.push_back(r);
    }
    for (const ModelPath& b : hi_.model.paths) {
      if (!kept(b) || lo_.model.path(b.output, b.input)) continue;
      ModelPath r = b;
      r.tf.gain = b.tf.gain * t_;
      m.paths.push_back(r);
    }
  }

  const SetModel& lo_;
  const SetModel& hi_;
  double x_;
  const InterpolationOptions& o_;
  double t_;
};

}  // namespace

double operating_point_of(const Model& m, const std::string& schedule_by) {
  if (schedule_by == "speed_pct") {
    if (!(m.speed_pct > 0))
      throw InputError(m.source + ": no operating_point.speed_pct to schedule by");
    return m.speed_pct;
  }
  const Json& op = m.operating_point_extra;
  if (!op.is_object() || !op.contains(schedule_by) || !op[schedule_by].is_number())
    throw InputError(m.source + ": no number operating_point." + schedule_by + " to schedule by");
  return op[schedule_by].get<double>();
}

std::vector<SetModel> load_model_set(const std::string& set, const std::string& schedule_by) {
  std::vector<std::string> specs;
  if (set.find(',') != std::string::npos) {
    specs = split_list(set);
  } else if (fs::is_directory(set)) {
    for (const auto& e : fs::directory_iterator(set))
      if (e.path().extension() == ".json") specs.push_back(e.path().string());
    std::sort(specs.begin(), specs.end());
    if (specs.empty()) throw InputError(set + ": a folder without model files (*.json)");
  } else {
    // An embedded family: "j85" -> j85_<digits>, "j85_sim" -> j85_<digits>_sim.
    const bool sim = set.size() > 4 && set.compare(set.size() - 4, 4, "_sim") == 0;
    const std::string base = sim ? set.substr(0, set.size() - 4) : set;
    const std::regex family(
        "^" + std::regex_replace(base, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") + "_[0-9]+" +
        (sim ? "_sim" : "") + "\\.json$");
    for (const auto& e : embedded_models())
      if (std::regex_match(e.name, family))
        specs.push_back(std::string(e.name).substr(0, std::string(e.name).size() - 5));
    if (specs.empty()) specs.push_back(set);  // one model: a file or an embedded name
  }
  std::vector<SetModel> out;
  for (const std::string& s : specs) {
    Model m = load_model_or_embedded(s);
    if (m.source.empty()) m.source = s;
    const double x = operating_point_of(m, schedule_by);
    out.push_back({s, x, std::move(m)});
  }
  std::sort(out.begin(), out.end(), [](const SetModel& a, const SetModel& b) { return a.x < b.x; });
  for (size_t i = 1; i < out.size(); ++i) {
    if (out[i].x == out[i - 1].x)
      throw InputError(out[i - 1].spec + " and " + out[i].spec + ": the same " + schedule_by +
                       " (" + num(out[i].x) + ")");
  }
  return out;
}

std::optional<ModelAt> parse_model_at(const std::string& spec) {
  const size_t at = spec.rfind('@');
  if (at == std::string::npos) return std::nullopt;
  ModelAt r;
  r.set = spec.substr(0, at);
  std::string value = spec.substr(at + 1);
  if (const size_t eq = value.find('='); eq != std::string::npos) {
    r.schedule_by = value.substr(0, eq);
    value = value.substr(eq + 1);
  }
  const char* end = value.data() + value.size();
  const auto [p, ec] = std::from_chars(value.data(), end, r.x);
  if (r.set.empty() || r.schedule_by.empty() || ec != std::errc() || p != end ||
      !std::isfinite(r.x))
    throw InputError(spec + ": a model at an operating point is SET@X or SET@KEY=X (X a number)");
  return r;
}

Model interpolate_models(const SetModel& lo, const SetModel& hi, double x,
                         const InterpolationOptions& o) {
  if (!(lo.x < x && x < hi.x))
    throw InputError(o.schedule_by + " " + num(x) + ": not between " + lo.spec + " (" + num(lo.x) +
                     ") and " + hi.spec + " (" + num(hi.x) + ")");
  return Interpolation(lo, hi, x, o).run();
}

Model model_at(const std::vector<SetModel>& set, double x, const InterpolationOptions& o) {
  if (set.empty()) throw InputError("no models to interpolate");
  for (const SetModel& s : set)
    if (s.x == x) return s.model;
  if (!(x > set.front().x && x < set.back().x)) {
    std::string names;
    for (const SetModel& s : set) names += (names.empty() ? "" : ", ") + num(s.x);
    throw InputError(o.schedule_by + " " + num(x) + ": outside the models' range (" + names +
                     "); a model is interpolated between two points, never extrapolated");
  }
  size_t k = 1;
  while (set[k].x < x) ++k;
  return interpolate_models(set[k - 1], set[k], x, o);
}

}  // namespace fralab
