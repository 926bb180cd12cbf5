#include "fralab/plant/realisation.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "fralab/core/error.h"

namespace fralab {
namespace {

using Eigen::MatrixXd;
using Cd = std::complex<double>;

constexpr double kSameRoot = 1e-9;  // a root of the model's path is the state model's (relative)
constexpr double kAgree = 1e-9;     // the realisation's response agrees with the model's (relative)

// A linear block: x' = A x + B u, y = C x + D u, its states named.
struct Lti {
  MatrixXd A, B, C, D;
  std::vector<std::string> names;
};

// a then b (b's inputs are a's outputs).
Lti series(const Lti& a, const Lti& b) {
  const Eigen::Index n1 = a.A.rows(), n2 = b.A.rows();
  Lti s;
  s.A = MatrixXd::Zero(n1 + n2, n1 + n2);
  s.A.topLeftCorner(n1, n1) = a.A;
  s.A.bottomLeftCorner(n2, n1) = b.B * a.C;
  s.A.bottomRightCorner(n2, n2) = b.A;
  s.B.resize(n1 + n2, a.B.cols());
  s.B << a.B, b.B * a.D;
  s.C.resize(b.C.rows(), n1 + n2);
  s.C << b.D * a.C, b.C;
  s.D = b.D * a.D;
  s.names = a.names;
  s.names.insert(s.names.end(), b.names.begin(), b.names.end());
  return s;
}

Lti gain_block(double g) {
  return {MatrixXd(0, 0), MatrixXd(0, 1), MatrixXd(1, 0), MatrixXd::Constant(1, 1, g), {}};
}

// One pole factor (a real root, a pair, or two real roots together) and the zero factors it
// carries (of total order at most its own).
struct Section {
  std::vector<Root> poles, zeros;
  int free() const {
    int o = 0;
    for (const Root& p : poles) o += p.order();
    for (const Root& z : zeros) o -= z.order();
    return o;
  }
};

std::vector<Section> sections_of(const Tf& t, const std::string& where) {
  if (!t.proper())
    throw InputError(where + ": more zeros than poles (improper); it has no state model");
  std::vector<Section> s;
  for (const Root& p : t.poles) s.push_back({{p}, {}});
  for (const Root& z : t.zeros) {
    if (!z.pair) continue;
    auto home = std::find_if(s.begin(), s.end(), [](const Section& x) { return x.free() >= 2; });
    if (home == s.end()) {
      // Two real poles without zeros share a second-order section (the zeros' pairs come first,
      // so every real pole's section is still free; the count works since the tf is proper).
      auto lone = [](const Section& x) { return x.poles.size() == 1 && !x.poles[0].pair; };
      auto a = std::find_if(s.begin(), s.end(), lone);
      auto b = a == s.end() ? s.end() : std::find_if(a + 1, s.end(), lone);
      if (b == s.end()) throw std::logic_error(where + ": no section holds a pair of zeros");
      a->poles.push_back(b->poles[0]);
      s.erase(b);
      home = a;
    }
    home->zeros.push_back(z);
  }
  for (const Root& z : t.zeros) {
    if (z.pair) continue;
    auto home = std::find_if(s.begin(), s.end(), [](const Section& x) { return x.free() >= 1; });
    if (home == s.end()) throw std::logic_error(where + ": no section holds a zero");
    home->zeros.push_back(z);
  }
  return s;
}

// The zero factors as a polynomial in sigma = s / wn, ascending powers (z0 = 1).
std::vector<double> zero_polynomial(const std::vector<Root>& zeros, double wn) {
  std::vector<double> p = {1.0};
  for (const Root& z : zeros) {
    const std::vector<double> f =
        z.pair ? std::vector<double>{1.0, 2 * z.zeta * wn / z.wn, (wn / z.wn) * (wn / z.wn)}
               : std::vector<double>{1.0, -wn / z.real};
    std::vector<double> q(p.size() + f.size() - 1, 0.0);
    for (size_t a = 0; a < p.size(); ++a)
      for (size_t b = 0; b < f.size(); ++b) q[a + b] += p[a] * f[b];
    p = q;
  }
  p.resize(3, 0.0);
  return p;
}

Lti realise_section(const Section& x, const StatePlace& place, const StateNamer& namer) {
  Lti l;
  if (x.poles.size() == 1 && !x.poles[0].pair) {
    const double wn = -x.poles[0].real;
    const std::vector<double> z = zero_polynomial(x.zeros, wn);
    l.A = MatrixXd::Constant(1, 1, -wn);
    l.B = MatrixXd::Constant(1, 1, wn);
    l.C = MatrixXd::Constant(1, 1, 1.0 - z[1]);
    l.D = MatrixXd::Constant(1, 1, z[1]);
    l.names = {namer(place, x.poles[0])};
    return l;
  }
  double wn = 0, zeta = 0;
  if (x.poles.size() == 1) {
    wn = x.poles[0].wn, zeta = x.poles[0].zeta;
    const std::string name = namer(place, x.poles[0]);
    l.names = {name + " (1)", name + " (2)"};
  } else {
    const double r1 = x.poles[0].real, r2 = x.poles[1].real;
    wn = std::sqrt(r1 * r2);
    zeta = -0.5 * wn * (1 / r1 + 1 / r2);
    l.names = {namer(place, x.poles[0]), namer(place, x.poles[1])};
  }
  const std::vector<double> z = zero_polynomial(x.zeros, wn);
  l.A.resize(2, 2);
  l.A << 0, wn, -wn, -2 * zeta * wn;
  l.B.resize(2, 1);
  l.B << 0, wn;
  l.C.resize(1, 2);
  l.C << z[0] - z[2], z[1] - 2 * zeta * z[2];
  l.D = MatrixXd::Constant(1, 1, z[2]);
  return l;
}

// The rational part of t (its delay left out) as a cascade of sections, its gain on the last.
Lti realise_tf(const Tf& t, const StatePlace& place, const StateNamer& namer) {
  Lti l = gain_block(1.0);
  for (const Section& x : sections_of(t, place.str()))
    l = series(l, realise_section(x, place, namer));
  l.C *= t.gain;
  l.D *= t.gain;
  return l;
}

// SISO blocks side by side: block k from input in[k] to output out[k], outputs summed.
Lti wire(const std::vector<Lti>& blocks, const std::vector<int>& in, const std::vector<int>& out,
         Eigen::Index n_in, Eigen::Index n_out) {
  Eigen::Index n = 0;
  for (const Lti& b : blocks) n += b.A.rows();
  Lti w{MatrixXd::Zero(n, n),
        MatrixXd::Zero(n, n_in),
        MatrixXd::Zero(n_out, n),
        MatrixXd::Zero(n_out, n_in),
        {}};
  Eigen::Index at = 0;
  for (size_t k = 0; k < blocks.size(); ++k) {
    const Lti& b = blocks[k];
    const Eigen::Index q = b.A.rows();
    w.A.block(at, at, q, q) = b.A;
    w.B.block(at, in[k], q, 1) = b.B;
    w.C.block(out[k], at, 1, q) = b.C;
    w.D(out[k], in[k]) += b.D(0, 0);
    w.names.insert(w.names.end(), b.names.begin(), b.names.end());
    at += q;
  }
  return w;
}

// `from` taken out of `roots`; false when one of them is not there.
bool take_out(std::vector<Root>& roots, const std::vector<Root>& from) {
  for (const Root& r : from) {
    auto it = std::find_if(roots.begin(), roots.end(),
                           [&](const Root& x) { return x.same_as(r, kSameRoot); });
    if (it == roots.end()) return false;
    roots.erase(it);
  }
  return true;
}

// a / b as a factor (a's rational part holding every root of b's), or nothing.
std::optional<Tf> ratio(const Tf& a, const Tf& b) {
  Tf r;
  r.gain = a.gain / b.gain;
  r.poles = a.poles, r.zeros = a.zeros;
  if (!take_out(r.poles, b.poles) || !take_out(r.zeros, b.zeros)) return std::nullopt;
  return r;
}

bool same_factor(const Tf& a, const Tf& b) {
  if (std::abs(a.gain - b.gain) > kSameRoot * std::abs(b.gain)) return false;
  std::vector<Root> p = a.poles, z = a.zeros;
  return p.size() == b.poles.size() && z.size() == b.zeros.size() && take_out(p, b.poles) &&
         take_out(z, b.zeros);
}

Tf rational(Tf t) {
  t.delay_s = 0;
  return t;
}

// The model's rational parts: position to output channel per path (nullopt: no path).
std::vector<std::vector<std::optional<Tf>>> model_paths(const Model& m) {
  std::vector<std::vector<std::optional<Tf>>> g(m.outputs.size(),
                                                std::vector<std::optional<Tf>>(m.inputs.size()));
  for (size_t i = 0; i < m.outputs.size(); ++i)
    for (size_t j = 0; j < m.inputs.size(); ++j)
      if (const ModelPath* p = m.path(m.outputs[i].name, m.inputs[j].name))
        g[i][j] = rational(p->tf);
  return g;
}

// The state model the model carries, with a factor before each input and after each output, when
// that explains every path; nothing otherwise.
std::optional<Lti> around_core(const Model& m, const StateNamer& namer) {
  const StateSpace& core = *m.state_space;
  if (core.inputs.size() != m.inputs.size() || core.outputs.size() != m.outputs.size())
    return std::nullopt;
  const Eigen::Index ni = Eigen::Index(m.inputs.size()), no = Eigen::Index(m.outputs.size());
  for (Eigen::Index j = 0; j < ni; ++j)
    if (core.inputs[size_t(j)] != m.inputs[size_t(j)].name) return std::nullopt;
  for (Eigen::Index i = 0; i < no; ++i)
    if (core.outputs[size_t(i)] != m.outputs[size_t(i)].name) return std::nullopt;
  const auto g = model_paths(m);
  const auto core_paths = state_space_paths(core, m.name);
  // What the model adds to each path of the core.
  const size_t nos = static_cast<size_t>(no), nis = static_cast<size_t>(ni);
  std::vector<std::vector<std::optional<Tf>>> r(nos, std::vector<std::optional<Tf>>(nis));
  for (Eigen::Index i = 0; i < no; ++i)
    for (Eigen::Index j = 0; j < ni; ++j) {
      const auto& c = core_paths[size_t(i)][size_t(j)];
      if (bool(c) != bool(g[size_t(i)][size_t(j)])) return std::nullopt;
      if (!c) continue;
      r[size_t(i)][size_t(j)] = ratio(*g[size_t(i)][size_t(j)], rational(*c));
      if (!r[size_t(i)][size_t(j)]) return std::nullopt;  // a root of the core moved on a path
    }
  // A factor common to an input's paths goes before the input; what remains, after the outputs.
  std::vector<Tf> in(nis), out(nos);
  for (Eigen::Index j = 0; j < ni; ++j) {
    std::optional<Tf> common;
    bool all = true;
    for (Eigen::Index i = 0; i < no && all; ++i)
      if (const auto& x = r[size_t(i)][size_t(j)]) {
        if (!common) common = *x;
        all = same_factor(*x, *common);
      }
    if (all && common) in[size_t(j)] = *common;
  }
  for (Eigen::Index i = 0; i < no; ++i) {
    bool set = false;
    for (Eigen::Index j = 0; j < ni; ++j) {
      const auto& x = r[size_t(i)][size_t(j)];
      if (!x) continue;
      const auto rest = ratio(*x, in[size_t(j)]);
      if (!rest) return std::nullopt;
      if (!set)
        out[size_t(i)] = *rest, set = true;
      else if (!same_factor(*rest, out[size_t(i)]))
        return std::nullopt;
    }
  }
  // A factor that is 1 to rounding (the ratio of two factorings of one path) is 1.
  for (auto* list : {&in, &out})
    for (Tf& t : *list)
      if (t.poles.empty() && t.zeros.empty() && std::abs(t.gain - 1) <= kSameRoot) t.gain = 1;
  std::vector<Lti> ib, ob;
  std::vector<int> ii, oi;
  for (Eigen::Index j = 0; j < ni; ++j) {
    if (!in[size_t(j)].proper()) return std::nullopt;
    ib.push_back(
        realise_tf(in[size_t(j)], {StatePlace::Kind::kInput, "", m.inputs[size_t(j)].name}, namer));
    ii.push_back(int(j));
  }
  for (Eigen::Index i = 0; i < no; ++i) {
    const auto& s = m.outputs[size_t(i)].sensor;
    const Tf o = s ? out[size_t(i)] * rational(*s) : out[size_t(i)];
    if (!o.proper()) return std::nullopt;
    ob.push_back(realise_tf(o, {StatePlace::Kind::kOutput, m.outputs[size_t(i)].name, ""}, namer));
    oi.push_back(int(i));
  }
  const Lti mid{core.A, core.B, core.C, core.D.size() ? core.D : MatrixXd::Zero(no, ni),
                core.states};
  return series(series(wire(ib, ii, ii, ni, ni), mid), wire(ob, oi, oi, no, no));
}

// One block per path, then each output's sensor.
Lti per_path(const Model& m, const StateNamer& namer) {
  const auto g = model_paths(m);
  const Eigen::Index ni = Eigen::Index(m.inputs.size()), no = Eigen::Index(m.outputs.size());
  std::vector<Lti> pb, sb;
  std::vector<int> pin, pout, sio;
  for (Eigen::Index i = 0; i < no; ++i)
    for (Eigen::Index j = 0; j < ni; ++j)
      if (const auto& t = g[size_t(i)][size_t(j)]) {
        pb.push_back(realise_tf(
            *t, {StatePlace::Kind::kPath, m.outputs[size_t(i)].name, m.inputs[size_t(j)].name},
            namer));
        pin.push_back(int(j)), pout.push_back(int(i));
      }
  for (Eigen::Index i = 0; i < no; ++i) {
    const auto& s = m.outputs[size_t(i)].sensor;
    sb.push_back(s ? realise_tf(rational(*s),
                                {StatePlace::Kind::kOutput, m.outputs[size_t(i)].name, ""}, namer)
                   : gain_block(1.0));
    sio.push_back(int(i));
  }
  return series(wire(pb, pin, pout, ni, no), wire(sb, sio, sio, no, no));
}

// The largest relative disagreement of ss's rational response with the model's (delays out) at
// each pole's frequency of the model, a decade beyond the slowest and the fastest, and 0.
double disagreement(const Model& m, const StateSpace& ss) {
  std::vector<double> ws = {0.0};
  double lo = INFINITY, hi = 0;
  auto add = [&](const Tf& t) {
    for (const Root& p : t.poles) {
      const double w = p.pair ? p.wn : std::abs(p.real);
      ws.push_back(w), lo = std::min(lo, w), hi = std::max(hi, w);
    }
  };
  for (const ModelPath& p : m.paths) add(p.tf);
  for (const ModelOutput& o : m.outputs)
    if (o.sensor) add(*o.sensor);
  if (hi > 0) ws.push_back(lo / 10), ws.push_back(hi * 10);
  double worst = 0;
  for (double w : ws) {
    const Eigen::MatrixXcd h = state_space_response(ss, Cd(0, w));
    for (int i = 0; i < int(m.outputs.size()); ++i)
      for (int j = 0; j < int(m.inputs.size()); ++j) {
        const ModelPath* p = m.path(m.outputs[size_t(i)].name, m.inputs[size_t(j)].name);
        const Cd want = p ? rational(p->tf).rational(Cd(0, w)) *
                                (m.outputs[size_t(i)].sensor
                                     ? rational(*m.outputs[size_t(i)].sensor).rational(Cd(0, w))
                                     : Cd(1, 0))
                          : Cd(0, 0);
        worst = std::max(worst, std::abs(h(i, j) - want) / std::max(std::abs(want), 1e-300));
        if (!p && std::abs(h(i, j)) > 0) worst = INFINITY;
      }
  }
  return worst;
}

StateSpace as_state_space(const Model& m, Lti l) {
  StateSpace ss;
  ss.A = std::move(l.A), ss.B = std::move(l.B), ss.C = std::move(l.C), ss.D = std::move(l.D);
  // Names given twice (two equal poles in one place) numbered.
  std::set<std::string> used;
  for (const ModelInput& in : m.inputs) used.insert(in.name);
  for (const ModelOutput& out : m.outputs) used.insert(out.name);
  for (const std::string& s : l.names) {
    std::string name = s;
    for (int k = 2; used.count(name); ++k) name = s + " #" + std::to_string(k);
    used.insert(name);
    ss.states.push_back(name);
  }
  for (const ModelInput& in : m.inputs) ss.inputs.push_back(in.name);
  for (const ModelOutput& out : m.outputs) ss.outputs.push_back(out.name);
  // Each path's delay: common to its input, then to its output, then its own.
  const Eigen::Index ni = Eigen::Index(m.inputs.size()), no = Eigen::Index(m.outputs.size());
  MatrixXd tau = MatrixXd::Constant(no, ni, NAN);
  for (Eigen::Index i = 0; i < no; ++i)
    for (Eigen::Index j = 0; j < ni; ++j)
      if (const ModelPath* p = m.path(m.outputs[size_t(i)].name, m.inputs[size_t(j)].name))
        tau(i, j) = p->tf.delay_s +
                    (m.outputs[size_t(i)].sensor ? m.outputs[size_t(i)].sensor->delay_s : 0.0);
  ss.input_delay_s.assign(size_t(ni), 0.0);
  ss.output_delay_s.assign(size_t(no), 0.0);
  for (Eigen::Index j = 0; j < ni; ++j) {
    double least = INFINITY;
    for (Eigen::Index i = 0; i < no; ++i)
      if (!std::isnan(tau(i, j))) least = std::min(least, tau(i, j));
    ss.input_delay_s[size_t(j)] = std::isfinite(least) ? least : 0.0;
  }
  for (Eigen::Index i = 0; i < no; ++i) {
    double least = INFINITY;
    for (Eigen::Index j = 0; j < ni; ++j)
      if (!std::isnan(tau(i, j))) least = std::min(least, tau(i, j) - ss.input_delay_s[size_t(j)]);
    ss.output_delay_s[size_t(i)] = std::isfinite(least) ? std::max(least, 0.0) : 0.0;
  }
  ss.path_delay_s = MatrixXd::Zero(no, ni);
  for (Eigen::Index i = 0; i < no; ++i)
    for (Eigen::Index j = 0; j < ni; ++j)
      if (!std::isnan(tau(i, j)))
        ss.path_delay_s(i, j) =
            std::max(0.0, tau(i, j) - ss.input_delay_s[size_t(j)] - ss.output_delay_s[size_t(i)]);
  return ss;
}

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

std::string StatePlace::str() const {
  switch (kind) {
    case Kind::kPath:
      return input + ":" + output;
    case Kind::kInput:
      return input + " input";
    case Kind::kOutput:
      return output + " output";
  }
  return "";
}

std::string default_state_name(const StatePlace& place, const Root& pole) {
  return place.str() + (pole.pair ? " mode " + num(pole.wn) + " rad/s zeta " + num(pole.zeta)
                                  : " pole " + num(pole.real) + " rad/s");
}

StateSpace model_state_space(const Model& m, const StateNamer& namer_in) {
  const StateNamer namer = namer_in ? namer_in : StateNamer(default_state_name);
  const std::string source = m.source.empty() ? m.name : m.source;
  if (m.state_space) {
    if (auto l = around_core(m, namer)) {
      StateSpace ss = as_state_space(m, std::move(*l));
      if (disagreement(m, ss) <= kAgree) return ss;
    }
  }
  StateSpace ss = as_state_space(m, per_path(m, namer));
  if (ss.A.rows() == 0)
    throw InputError(source + ": no path has dynamics (a state model needs at least one state)");
  const double d = disagreement(m, ss);
  if (!(d <= kAgree))
    throw InputError(source + ": its state model disagrees with its paths by " + num(d) +
                     " (relative) somewhere; the paths' roots may be too close to realise");
  return ss;
}

Json model_state_space_document(const Model& m, const StateSpace& ss) {
  Json doc = model_to_json(m);
  const Json mats = state_space_document(ss, m.name);
  doc["format"] = kStateSpaceFormat;
  doc.erase("paths");
  for (size_t k = 0; k < m.inputs.size(); ++k) {
    doc["inputs"][k].erase("delay_s");
    if (ss.input_delay_s[k] > 0) doc["inputs"][k]["delay_s"] = ss.input_delay_s[k];
  }
  for (size_t k = 0; k < m.outputs.size(); ++k) {
    doc["outputs"][k].erase("sensor");
    doc["outputs"][k].erase("delay_s");
    if (ss.output_delay_s[k] > 0) doc["outputs"][k]["delay_s"] = ss.output_delay_s[k];
  }
  for (const char* key : {"states", "A", "B", "C", "D"}) doc[key] = mats[key];
  if (ss.path_delay_s.size() && ss.path_delay_s.cwiseAbs().maxCoeff() > 0)
    doc["delay_s"] = mats["delay_s"];
  return doc;
}

}  // namespace fralab
