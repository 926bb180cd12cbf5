// The envelope's points joined: states tracked across points, the findings' laws, the slow
// states (envelope.h).
#include "fralab/envelope/envelope.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "envelope_text.h"
#include "fralab/core/error.h"
#include "fralab/core/text.h"

namespace fralab {

namespace {

using envelope_text::num;

// A root of transfer_matrix.json: {"real": p} or {"wn": w, "zeta": z}.
struct R {
  bool pair = false;
  double value = 0;  // tau (real) or wn (pair)
  double zeta = 0;
};
bool root_of(const Json& j, R* r) {
  if (j.contains("wn") && j["wn"].is_number()) {
    r->pair = true;
    r->value = j["wn"].get<double>();
    r->zeta = j.value("zeta", 0.0);
    return r->value > 0;
  }
  if (j.contains("real") && j["real"].is_number() && j["real"].get<double>() != 0) {
    r->pair = false;
    r->value = 1 / std::abs(j["real"].get<double>());
    return true;
  }
  return false;
}

// A path's own fit in transfer_matrix.json's `paths`, by "input:output".
const Json* path_fit(const Json& tm, const std::string& key) {
  if (!tm.contains("paths")) return nullptr;
  for (const Json& p : tm["paths"])
    if (p.value("input", "") + ":" + p.value("output", "") == key) return &p;
  return nullptr;
}

// The states of one point.
std::vector<TrackValue> point_states(const EnvelopePoint& pt) {
  std::vector<TrackValue> out;
  const Json& tm = pt.transfer_matrix;
  if (!tm.is_object()) return out;
  const Json* poles = nullptr;
  if (tm.contains("common_poles"))
    poles = &tm["common_poles"];
  else if (tm.contains("common_pole_set") && tm["common_pole_set"].contains("common_poles"))
    poles = &tm["common_pole_set"]["common_poles"];
  if (!poles) return out;
  for (const Json& c : *poles) {
    R r;
    if (!c.contains("pole") || !root_of(c["pole"], &r)) continue;
    TrackValue v;
    v.point = pt.name, v.x = pt.x, v.pair = r.pair, v.value = r.value, v.zeta = r.zeta;
    v.scope = c.value("scope", "path"), v.where = c.value("where", "");
    v.spread_lo = v.spread_hi = v.value;
    std::vector<double> sig;
    for (const Json& k : c.value("pairs", Json::array())) {
      const std::string key = k.get<std::string>();
      v.paths.push_back(key);
      const Json* f = path_fit(tm, key);
      if (!f || !f->contains("roots") || !(*f)["roots"].contains("poles")) continue;
      double best = INFINITY, bv = 0, bs = -1;
      for (const Json& q : (*f)["roots"]["poles"]) {
        const bool qp = q.value("imag", 0.0) != 0;
        if (qp != r.pair) continue;
        const double qv =
            qp ? q.value("wn", 0.0) : 1 / std::max(std::abs(q.value("real", 0.0)), 1e-300);
        if (!(qv > 0)) continue;
        const double d = std::abs(std::log(qv / r.value));
        if (d < best) best = d, bv = qv, bs = q.value("rel_sigma", -1.0);
      }
      if (best > std::log(1.5)) continue;
      v.spread_lo = std::min(v.spread_lo, bv), v.spread_hi = std::max(v.spread_hi, bv);
      if (bs >= 0) sig.push_back(bs);
    }
    if (!sig.empty()) {
      std::nth_element(sig.begin(), sig.begin() + long(sig.size() / 2), sig.end());
      v.rel_sigma = sig[sig.size() / 2];
    }
    out.push_back(v);
  }
  return out;
}

std::string label_of(const TrackValue& v) {
  if (v.scope == "plant") return "plant";
  if (v.scope == "output") return "sensor " + v.where;
  if (v.scope == "input") return "actuator " + v.where;
  std::string s = "path";
  for (const auto& p : v.paths) s += " " + p;
  return s;
}

bool share_path(const TrackValue& a, const TrackValue& b) {
  for (const auto& p : a.paths)
    if (std::find(b.paths.begin(), b.paths.end(), p) != b.paths.end()) return true;
  return false;
}

// Weighted least squares y = X beta; returns chi^2 and the covariance (scaled when chi2/dof > 1).
double wls(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const Eigen::VectorXd& s,
           Eigen::VectorXd* beta, Eigen::MatrixXd* cov) {
  const Eigen::MatrixXd Xw = s.cwiseInverse().asDiagonal() * X;
  const Eigen::VectorXd yw = y.cwiseQuotient(s);
  *beta = Xw.colPivHouseholderQr().solve(yw);
  const double chi2 = (Xw * *beta - yw).squaredNorm();
  const Eigen::MatrixXd A = Xw.transpose() * Xw;
  *cov = A.completeOrthogonalDecomposition().pseudoInverse();
  const long dof = long(y.size()) - long(X.cols());
  if (dof > 0 && chi2 / double(dof) > 1) *cov *= chi2 / double(dof);
  return chi2;
}

void fit_law(FindingLaw& f) {
  const int n = int(f.values.size());
  if (n == 0) return;
  Eigen::VectorXd x(n), y(n), s(n);
  bool positive = true;
  for (int i = 0; i < n; ++i) {
    const auto& v = f.values[size_t(i)];
    x(i) = v.x, y(i) = v.value;
    s(i) = v.sigma > 0 ? v.sigma : std::max(1e-3 * std::abs(v.value), 1e-12);
    positive = positive && v.value > 0 && v.x > 0;
  }
  const double ln_n = std::log(std::max(n, 1));
  Eigen::VectorXd beta;
  Eigen::MatrixXd cov;
  // Constant.
  {
    Eigen::MatrixXd X = Eigen::MatrixXd::Ones(n, 1);
    const double chi2 = wls(X, y, s, &beta, &cov);
    f.law = "constant", f.a = beta(0), f.b = 0, f.b_sigma = -1, f.criterion = chi2 + 1 * ln_n;
  }
  if (n < 2) return;
  // Linear.
  {
    Eigen::MatrixXd X(n, 2);
    X.col(0).setOnes(), X.col(1) = x;
    const double chi2 = wls(X, y, s, &beta, &cov);
    const double crit = chi2 + 2 * ln_n;
    if (crit < f.criterion)
      f.law = "linear", f.a = beta(0), f.b = beta(1), f.b_sigma = std::sqrt(cov(1, 1)),
      f.criterion = crit;
  }
  // Power: ln y = ln a + b ln x, sigma of ln y = sigma / y; chi^2 in y's units to first order.
  if (positive) {
    Eigen::MatrixXd X(n, 2);
    X.col(0).setOnes(), X.col(1) = x.array().log().matrix();
    const Eigen::VectorXd ly = y.array().log().matrix(), ls = s.cwiseQuotient(y);
    const double chi2 = wls(X, ly, ls, &beta, &cov);
    const double crit = chi2 + 2 * ln_n;
    if (crit < f.criterion)
      f.law = "power", f.a = std::exp(beta(0)), f.b = beta(1), f.b_sigma = std::sqrt(cov(1, 1)),
      f.criterion = crit;
  }
}

std::string finding_text(const FindingLaw& f) {
  std::ostringstream t;
  std::string where = f.scope == "input"    ? "input " + f.input
                      : f.scope == "output" ? "output " + f.output
                                            : f.input + " -> " + f.output;
  t << f.cause << " at " << where << ", " << f.parameter << ":";
  bool sim_all = !f.values.empty(), same_sim = true;
  for (const auto& v : f.values) {
    sim_all = sim_all && v.has_simulated;
    same_sim = same_sim && v.has_simulated && v.simulated == f.values.front().simulated;
  }
  if (sim_all && same_sim)
    t << " simulated " << num(f.values.front().simulated) << " at every point;";
  t << " the engine's";
  for (size_t i = 0; i < f.values.size(); ++i)
    t << (i ? ", " : " ") << num(f.values[i].value) << " (" << num(f.values[i].x) << ")";
  if (f.law == "constant") {
    t << ": constant";
  } else {
    t << ": " << f.law << ", slope " << num(f.b);
    if (f.b_sigma > 0) t << " +- " << num(f.b_sigma);
    t << (f.b > 0 ? ", rising" : ", falling");
  }
  if (!f.missing_at.empty()) {
    t << "; not found at";
    for (const auto& m : f.missing_at) t << " " << m;
  }
  return t.str();
}

// A state's values across points: the flags for one absent at some points ("found at k of n
// points (...)") and for steps of opposite signs, each larger than its two values' sigmas
// together ("not monotone: a at x1 then b at x2").
struct Step {
  std::string point;
  double x, value, sigma;
};
void flag_steps(const std::vector<Step>& v, size_t n_points, bool* every, bool* monotone,
                std::string* flags) {
  std::ostringstream fl;
  *every = v.size() == n_points;
  *monotone = true;
  if (!*every) {
    fl << "found at " << v.size() << " of " << n_points << " points (";
    for (size_t i = 0; i < v.size(); ++i) fl << (i ? ", " : "") << v[i].point;
    fl << ")";
  }
  int sign = 0;
  for (size_t i = 1; i < v.size(); ++i) {
    const Step &a = v[i - 1], &b = v[i];
    const double step = b.value - a.value;
    if (std::abs(step) <= a.sigma + b.sigma) continue;
    const int sg = step > 0 ? 1 : -1;
    if (sign != 0 && sg != sign) {
      *monotone = false;
      fl << (fl.tellp() > 0 ? "; " : "") << "not monotone: " << num(a.value) << " at " << num(a.x)
         << " then " << num(b.value) << " at " << num(b.x);
    }
    sign = sg;
  }
  *flags = fl.str();
}

// Each path's slowest real pole (time constant, s) in its own fit, by output, at one point.
std::map<std::string, std::vector<std::pair<std::string, double>>> slowest_by_output(
    const EnvelopePoint& pt) {
  std::map<std::string, std::vector<std::pair<std::string, double>>> out;
  const Json& tm = pt.transfer_matrix;
  if (!tm.is_object() || !tm.contains("paths") || !tm["paths"].is_array()) return out;
  for (const Json& p : tm["paths"]) {
    if (!p.is_object() || !p.contains("roots") || !p["roots"].is_object() ||
        !p["roots"].contains("poles") || !p["roots"]["poles"].is_array())
      continue;
    if (!p.contains("input") || !p["input"].is_string() || !p.contains("output") ||
        !p["output"].is_string())
      continue;
    const std::string in = p["input"].get<std::string>(), o = p["output"].get<std::string>();
    if (in.empty() || o.empty()) continue;
    double tau = 0;
    for (const Json& q : p["roots"]["poles"]) {
      // A real pole: "real" a number, "imag" absent or 0 (anything else is not one).
      if (!q.is_object() || !q.contains("real") || !q["real"].is_number()) continue;
      if (q.contains("imag") && !(q["imag"].is_number() && q["imag"].get<double>() == 0)) continue;
      const double re = q["real"].get<double>();
      if (re < 0) tau = std::max(tau, -1 / re);
    }
    if (tau > 0 && std::isfinite(tau)) out[o].push_back({in + ":" + o, tau});
  }
  return out;
}

double mean_tau(const std::vector<std::pair<std::string, double>>& v) {
  double s = 0;
  for (const auto& [k, t] : v) s += t;
  return s / double(v.size());
}

SlowState::Value slow_value(const EnvelopePoint& pt,
                            const std::vector<std::pair<std::string, double>>& members) {
  SlowState::Value v;
  v.point = pt.name, v.x = pt.x;
  v.tau_s = mean_tau(members);
  v.lo = INFINITY, v.hi = 0;
  double ss = 0, poles = 0;
  for (const auto& [k, t] : members) {
    v.paths.push_back(k);
    v.lo = std::min(v.lo, t), v.hi = std::max(v.hi, t);
    ss += (t - v.tau_s) * (t - v.tau_s);
    poles += 1 / t;
  }
  const double n = double(members.size());
  v.sem = n > 1 ? std::sqrt(ss / (n - 1) / n) : 0;
  v.tau_of_mean_pole_s = n / poles;
  return v;
}

using SlowPaths = std::vector<std::pair<std::string, double>>;       // (pair, tau) per path
using SlowByOutput = std::vector<std::map<std::string, SlowPaths>>;  // [point][output]

// The plant's outputs among `outputs` (in their order): from each output in turn, the outputs
// agreeing with every member so far (nearest first); the group holding the most paths. Two
// outputs agree when at every point holding both their means are within slow_ratio, at one point
// at least.
std::vector<std::string> plant_slow_outputs(const SlowByOutput& by,
                                            const std::vector<std::string>& outputs,
                                            const std::map<std::string, size_t>& count,
                                            const EnvelopeOptions& o) {
  auto agree = [&](const std::string& a, const std::string& b) {
    int common = 0;
    for (const auto& m : by) {
      if (!m.count(a) || !m.count(b)) continue;
      ++common;
      if (!(std::abs(std::log(mean_tau(m.at(a)) / mean_tau(m.at(b)))) < std::log(o.slow_ratio)))
        return false;
    }
    return common > 0;
  };
  auto distance = [&](const std::string& a, const std::string& b) {
    double d = 0;
    for (const auto& m : by)
      if (m.count(a) && m.count(b)) d += std::abs(std::log(mean_tau(m.at(a)) / mean_tau(m.at(b))));
    return d;
  };
  auto group_from = [&](const std::string& seed) {
    std::vector<std::string> g = {seed}, rest;
    for (const auto& out : outputs)
      if (out != seed) rest.push_back(out);
    std::stable_sort(rest.begin(), rest.end(), [&](const std::string& a, const std::string& b) {
      return distance(seed, a) < distance(seed, b);
    });
    for (const auto& out : rest) {
      bool all = true;
      for (const auto& m : g) all = all && agree(out, m);
      if (all) g.push_back(out);
    }
    return g;
  };
  auto paths_in = [&](const std::vector<std::string>& g) {
    size_t n = 0;
    for (const auto& out : g) n += count.at(out);
    return n;
  };
  std::vector<std::string> plant;
  for (const auto& out : outputs) {
    std::vector<std::string> g = group_from(out);
    if (paths_in(g) > paths_in(plant)) plant = g;
  }
  std::stable_sort(plant.begin(), plant.end(), [&](const std::string& a, const std::string& b) {
    return std::find(outputs.begin(), outputs.end(), a) <
           std::find(outputs.begin(), outputs.end(), b);
  });
  return plant;
}

// The plant's slow state over its outputs' paths at each point; plant_tau[i] its time constant
// at point i (0 where none of those outputs has a slow path).
SlowState plant_slow_state(const std::vector<EnvelopePoint>& points, const SlowByOutput& by,
                           const std::vector<std::string>& plant, std::vector<double>* plant_tau) {
  SlowState ps;
  ps.label = "plant", ps.outputs = plant;
  plant_tau->assign(points.size(), 0);
  for (size_t i = 0; i < points.size(); ++i) {
    SlowPaths members;
    for (const auto& out : plant)
      if (by[i].count(out))
        members.insert(members.end(), by[i].at(out).begin(), by[i].at(out).end());
    if (members.empty()) continue;
    ps.values.push_back(slow_value(points[i], members));
    (*plant_tau)[i] = ps.values.back().tau_s;
  }
  return ps;
}

// Another output's slow state: a sensor's where it is slower than the plant's at every point
// (its paths not slower than the plant there left out, named), else the output's.
SlowState output_slow_state(const std::vector<EnvelopePoint>& points, const SlowByOutput& by,
                            const std::string& out, const std::vector<double>& plant_tau) {
  bool slower = true;
  for (size_t i = 0; i < points.size(); ++i)
    if (by[i].count(out) && plant_tau[i] > 0)
      slower = slower && mean_tau(by[i].at(out)) > plant_tau[i];
  SlowState s;
  s.label = (slower ? "sensor " : "output ") + out, s.outputs = {out};
  for (size_t i = 0; i < points.size(); ++i) {
    if (!by[i].count(out)) continue;
    SlowPaths members;
    std::vector<std::string> without;
    for (const auto& m : by[i].at(out)) {
      if (slower && plant_tau[i] > 0 && !(m.second > plant_tau[i]))
        without.push_back(m.first);
      else
        members.push_back(m);
    }
    if (members.empty()) continue;
    s.values.push_back(slow_value(points[i], members));
    s.values.back().without = without;
  }
  return s;
}

// The slow states (see the header): the plant's over the outputs that agree, then one per other
// output, as sensor or output; each flagged for its steps over the points and the paths left out.
std::vector<SlowState> slow_states(const std::vector<EnvelopePoint>& points,
                                   const EnvelopeOptions& o) {
  SlowByOutput by(points.size());
  std::vector<std::string> outputs;
  std::map<std::string, size_t> count;
  for (size_t i = 0; i < points.size(); ++i) {
    by[i] = slowest_by_output(points[i]);
    for (const auto& [out, v] : by[i]) {
      if (!count.count(out)) outputs.push_back(out);
      count[out] += v.size();
    }
  }
  std::vector<SlowState> res;
  if (outputs.size() < 2) return res;
  const std::vector<std::string> plant = plant_slow_outputs(by, outputs, count, o);
  if (plant.size() < 2) return res;
  std::vector<double> plant_tau;
  res.push_back(plant_slow_state(points, by, plant, &plant_tau));
  for (const auto& out : outputs) {
    if (std::find(plant.begin(), plant.end(), out) != plant.end()) continue;
    SlowState s = output_slow_state(points, by, out, plant_tau);
    if (!s.values.empty()) res.push_back(std::move(s));
  }
  for (SlowState& s : res) {
    std::vector<Step> steps;
    for (const auto& v : s.values) steps.push_back({v.point, v.x, v.tau_s, v.sem});
    flag_steps(steps, points.size(), &s.at_every_point, &s.monotone, &s.flags);
    for (const auto& v : s.values) {
      if (v.without.empty()) continue;
      s.flags += s.flags.empty() ? "not in" : "; not in";
      for (const auto& w : v.without) s.flags += " " + w;
      s.flags += " at " + num(v.x);
    }
  }
  return res;
}
}  // namespace

void EnvelopeOptions::validate() const {
  if (schedule_by.empty()) throw InputError("envelope: --schedule-by must name a key");
  if (!(track_ratio > 1)) throw InputError("envelope: track_ratio must be > 1");
  if (!(slow_ratio > 1)) throw InputError("envelope: slow_ratio must be > 1");
}

namespace {

// Point pt's states into the tracks: the closest (state, track) couples first, each within
// track_ratio and sharing a path with the track's last value (a change of label costs the whole
// tracking window); a state no track takes starts one.
void track_states(const EnvelopePoint& pt, const EnvelopeOptions& o,
                  std::vector<StateTrack>& tracks) {
  std::vector<TrackValue> states = point_states(pt);
  std::vector<bool> taken(tracks.size(), false);
  struct Couple {
    double d;
    size_t s, t;
  };
  std::vector<Couple> cs;
  for (size_t s = 0; s < states.size(); ++s) {
    for (size_t t = 0; t < tracks.size(); ++t) {
      const StateTrack& tr = tracks[t];
      const TrackValue& last = tr.values.back();
      if (tr.pair != states[s].pair || last.point == pt.name) continue;
      const double d = std::abs(std::log(states[s].value / last.value));
      if (!(d < std::log(o.track_ratio)) || !share_path(states[s], last)) continue;
      // A state keeps its label (sensor T5 stays T5's) unless another is much nearer.
      const double cost = d + (label_of(states[s]) == label_of(last) ? 0 : std::log(o.track_ratio));
      cs.push_back({cost, s, t});
    }
  }
  std::sort(cs.begin(), cs.end(), [](const Couple& a, const Couple& b) { return a.d < b.d; });
  std::vector<bool> used(states.size(), false);
  for (const Couple& c : cs) {
    if (used[c.s] || taken[c.t]) continue;
    used[c.s] = taken[c.t] = true;
    tracks[c.t].values.push_back(states[c.s]);
  }
  for (size_t s = 0; s < states.size(); ++s) {
    if (used[s]) continue;
    StateTrack t;
    t.pair = states[s].pair;
    t.values.push_back(states[s]);
    tracks.push_back(t);
  }
}

// A track's label (the one most of its values carry) and its flags over n_points.
void label_and_flag(StateTrack& t, size_t n_points) {
  std::map<std::string, int> votes;
  for (const auto& v : t.values) ++votes[label_of(v)];
  int best = -1;
  for (const auto& [l, n] : votes)
    if (n > best) best = n, t.label = l;
  std::vector<Step> steps;
  for (const auto& v : t.values)
    steps.push_back({v.point, v.x, v.value, v.rel_sigma > 0 ? v.rel_sigma * v.value : 0});
  flag_steps(steps, n_points, &t.at_every_point, &t.monotone, &t.flags);
}

// Finding f of point pt (its diagnosis' JSON) into its law (cause, scope, input, output): the
// value of its first interval's parameter, that interval's half width as sigma, and the
// simulation's value from its first from_* parameter. Findings without an interval are left out.
void add_to_law(const Json& f, const EnvelopePoint& pt, std::map<std::string, FindingLaw>& laws) {
  if (!f.contains("intervals") || !f["intervals"].is_object() || f["intervals"].empty()) return;
  const std::string param = f["intervals"].begin().key();
  if (!f.contains("parameters") || !f["parameters"].contains(param)) return;
  auto str = [&](const char* k) {
    return f.contains(k) && f[k].is_string() ? f[k].get<std::string>() : std::string();
  };
  const std::string key =
      str("cause") + "|" + str("scope") + "|" + str("input") + "|" + str("output");
  FindingLaw& l = laws[key];
  l.cause = str("cause"), l.scope = str("scope"), l.input = str("input"), l.output = str("output"),
  l.parameter = param;
  FindingLaw::Value v;
  v.point = pt.name, v.x = pt.x, v.value = f["parameters"][param].get<double>();
  const Json& iv = f["intervals"][param];
  if (iv.is_array() && iv.size() == 2) {
    const bool lo = iv[0].is_number(), hi = iv[1].is_number();
    if (lo && hi)
      v.sigma = (iv[1].get<double>() - iv[0].get<double>()) / 2;
    else if (lo)
      v.sigma = v.value - iv[0].get<double>();
    else if (hi)
      v.sigma = iv[1].get<double>() - v.value;
  }
  for (auto it = f["parameters"].begin(); it != f["parameters"].end(); ++it) {
    if (it.key().rfind("from_", 0) == 0 && it.value().is_number()) {
      v.simulated = it.value().get<double>(), v.has_simulated = true;
      break;
    }
  }
  l.values.push_back(v);
}

}  // namespace

EnvelopeReport join_points(std::vector<EnvelopePoint> points, const EnvelopeOptions& o) {
  o.validate();
  std::sort(points.begin(), points.end(),
            [](const EnvelopePoint& a, const EnvelopePoint& b) { return a.x < b.x; });
  EnvelopeReport r;
  r.schedule_by = o.schedule_by;
  r.points = points;
  for (const EnvelopePoint& pt : points) track_states(pt, o, r.tracks);
  for (StateTrack& t : r.tracks) label_and_flag(t, points.size());
  r.slow_states = slow_states(points, o);
  // Findings across points.
  std::map<std::string, FindingLaw> laws;
  for (const EnvelopePoint& pt : points) {
    if (!pt.diagnosis.is_object() || !pt.diagnosis.contains("findings")) continue;
    for (const Json& f : pt.diagnosis["findings"]) add_to_law(f, pt, laws);
  }
  for (auto& [k, l] : laws) {
    for (const EnvelopePoint& pt : points) {
      bool here = false;
      for (const auto& v : l.values) here = here || v.point == pt.name;
      if (!here) l.missing_at.push_back(pt.name);
    }
    fit_law(l);
    l.text = finding_text(l);
    r.findings.push_back(l);
  }
  return r;
}

}  // namespace fralab
