#include "fralab/lab/envelope.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "fralab/core/error.h"
#include "fralab/core/text.h"
#include "fralab/diagnose/report.h"
#include "fralab/exchange/state_space_mat.h"
#include "fralab/lab/diagnose_command.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/schedule.h"

namespace fs = std::filesystem;

namespace fralab {

namespace {

std::string num(double v) { return significant(v, 4); }

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

// The slow states (see the header): the plant's over the outputs that agree, then one per other
// output, as sensor or output.
std::vector<SlowState> slow_states(const std::vector<EnvelopePoint>& points,
                                   const EnvelopeOptions& o) {
  using Paths = std::vector<std::pair<std::string, double>>;
  std::vector<std::map<std::string, Paths>> by(points.size());
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
  // a and b agree: at every point holding both their means within slow_ratio, at one point at
  // least.
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
  // The plant's group: from each output in turn, the outputs agreeing with every member so far
  // (nearest first); the group holding the most paths.
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
    for (const auto& out : g) n += count[out];
    return n;
  };
  std::vector<std::string> plant;
  for (const auto& out : outputs) {
    std::vector<std::string> g = group_from(out);
    if (paths_in(g) > paths_in(plant)) plant = g;
  }
  std::vector<std::string> others;
  for (const auto& out : outputs)
    if (std::find(plant.begin(), plant.end(), out) == plant.end()) others.push_back(out);
  if (plant.size() < 2) return res;
  std::stable_sort(plant.begin(), plant.end(), [&](const std::string& a, const std::string& b) {
    return std::find(outputs.begin(), outputs.end(), a) <
           std::find(outputs.begin(), outputs.end(), b);
  });
  SlowState ps;
  ps.label = "plant", ps.outputs = plant;
  std::vector<double> plant_tau(points.size(), 0);
  for (size_t i = 0; i < points.size(); ++i) {
    Paths members;
    for (const auto& out : plant)
      if (by[i].count(out)) members.insert(members.end(), by[i][out].begin(), by[i][out].end());
    if (members.empty()) continue;
    ps.values.push_back(slow_value(points[i], members));
    plant_tau[i] = ps.values.back().tau_s;
  }
  res.push_back(ps);
  for (const auto& out : outputs) {
    if (std::find(others.begin(), others.end(), out) == others.end()) continue;
    bool slower = true;
    for (size_t i = 0; i < points.size(); ++i)
      if (by[i].count(out) && plant_tau[i] > 0)
        slower = slower && mean_tau(by[i][out]) > plant_tau[i];
    SlowState s;
    s.label = (slower ? "sensor " : "output ") + out, s.outputs = {out};
    for (size_t i = 0; i < points.size(); ++i) {
      if (!by[i].count(out)) continue;
      Paths members;
      std::vector<std::string> without;
      for (const auto& m : by[i][out]) {
        if (slower && plant_tau[i] > 0 && !(m.second > plant_tau[i]))
          without.push_back(m.first);
        else
          members.push_back(m);
      }
      if (members.empty()) continue;
      s.values.push_back(slow_value(points[i], members));
      s.values.back().without = without;
    }
    if (!s.values.empty()) res.push_back(s);
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

EnvelopeReport join_points(std::vector<EnvelopePoint> points, const EnvelopeOptions& o) {
  o.validate();
  std::sort(points.begin(), points.end(),
            [](const EnvelopePoint& a, const EnvelopePoint& b) { return a.x < b.x; });
  EnvelopeReport r;
  r.schedule_by = o.schedule_by;
  r.points = points;
  // States into tracks.
  for (const EnvelopePoint& pt : points) {
    std::vector<TrackValue> states = point_states(pt);
    std::vector<bool> taken(r.tracks.size(), false);
    // The closest (state, track) couples first.
    struct Couple {
      double d;
      size_t s, t;
    };
    std::vector<Couple> cs;
    for (size_t s = 0; s < states.size(); ++s) {
      for (size_t t = 0; t < r.tracks.size(); ++t) {
        const StateTrack& tr = r.tracks[t];
        const TrackValue& last = tr.values.back();
        if (tr.pair != states[s].pair || last.point == pt.name) continue;
        const double d = std::abs(std::log(states[s].value / last.value));
        if (!(d < std::log(o.track_ratio)) || !share_path(states[s], last)) continue;
        // A state keeps its label (sensor T5 stays T5's) unless another is much nearer: a change
        // of label costs the whole tracking window.
        const double cost =
            d + (label_of(states[s]) == label_of(last) ? 0 : std::log(o.track_ratio));
        cs.push_back({cost, s, t});
      }
    }
    std::sort(cs.begin(), cs.end(), [](const Couple& a, const Couple& b) { return a.d < b.d; });
    std::vector<bool> used(states.size(), false);
    for (const Couple& c : cs) {
      if (used[c.s] || taken[c.t]) continue;
      used[c.s] = taken[c.t] = true;
      r.tracks[c.t].values.push_back(states[c.s]);
    }
    for (size_t s = 0; s < states.size(); ++s) {
      if (used[s]) continue;
      StateTrack t;
      t.pair = states[s].pair;
      t.values.push_back(states[s]);
      r.tracks.push_back(t);
    }
  }
  for (StateTrack& t : r.tracks) {
    std::map<std::string, int> votes;
    for (const auto& v : t.values) ++votes[label_of(v)];
    int best = -1;
    for (const auto& [l, n] : votes)
      if (n > best) best = n, t.label = l;
    std::vector<Step> steps;
    for (const auto& v : t.values)
      steps.push_back({v.point, v.x, v.value, v.rel_sigma > 0 ? v.rel_sigma * v.value : 0});
    flag_steps(steps, points.size(), &t.at_every_point, &t.monotone, &t.flags);
  }
  r.slow_states = slow_states(points, o);
  // Findings across points.
  std::map<std::string, FindingLaw> laws;
  for (const EnvelopePoint& pt : points) {
    if (!pt.diagnosis.is_object() || !pt.diagnosis.contains("findings")) continue;
    for (const Json& f : pt.diagnosis["findings"]) {
      if (!f.contains("intervals") || !f["intervals"].is_object() || f["intervals"].empty())
        continue;
      const std::string param = f["intervals"].begin().key();
      if (!f.contains("parameters") || !f["parameters"].contains(param)) continue;
      auto str = [&](const char* k) {
        return f.contains(k) && f[k].is_string() ? f[k].get<std::string>() : std::string();
      };
      const std::string key =
          str("cause") + "|" + str("scope") + "|" + str("input") + "|" + str("output");
      FindingLaw& l = laws[key];
      l.cause = str("cause"), l.scope = str("scope"), l.input = str("input"),
      l.output = str("output"), l.parameter = param;
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

Json envelope_json(const EnvelopeReport& r) {
  Json j;
  j["format"] = "fralab-envelope/1";
  j["schedule_by"] = r.schedule_by;
  j["points"] = Json::array();
  for (const auto& p : r.points) j["points"].push_back({{"name", p.name}, {"x", p.x}});
  j["states"] = Json::array();
  for (const auto& t : r.tracks) {
    Json tj{{"label", t.label},
            {"kind", t.pair ? "pair" : "real"},
            {"at_every_point", t.at_every_point},
            {"monotone", t.monotone},
            {"flags", t.flags},
            {"values", Json::array()}};
    for (const auto& v : t.values) {
      Json vj{{"point", v.point}, {"x", v.x}, {"scope", v.scope}, {"paths", v.paths}};
      if (v.where.size()) vj["where"] = v.where;
      if (v.pair) {
        vj["wn_rad_s"] = v.value, vj["zeta"] = v.zeta;
      } else {
        vj["tau_s"] = v.value;
      }
      vj["spread"] = {v.spread_lo, v.spread_hi};
      if (v.rel_sigma >= 0) vj["rel_sigma"] = v.rel_sigma;
      tj["values"].push_back(vj);
    }
    j["states"].push_back(tj);
  }
  j["slow_states"] = Json::array();
  for (const auto& t : r.slow_states) {
    Json tj{{"label", t.label},       {"outputs", t.outputs}, {"at_every_point", t.at_every_point},
            {"monotone", t.monotone}, {"flags", t.flags},     {"values", Json::array()}};
    for (const auto& v : t.values)
      tj["values"].push_back({{"point", v.point},
                              {"x", v.x},
                              {"tau_s", v.tau_s},
                              {"range", {v.lo, v.hi}},
                              {"sem", v.sem},
                              {"tau_of_mean_pole_s", v.tau_of_mean_pole_s},
                              {"paths", v.paths},
                              {"without", v.without}});
    j["slow_states"].push_back(tj);
  }
  j["findings"] = Json::array();
  for (const auto& f : r.findings) {
    Json fj{{"cause", f.cause},
            {"scope", f.scope},
            {"input", f.input},
            {"output", f.output},
            {"parameter", f.parameter},
            {"text", f.text},
            {"law", {{"form", f.law}, {"a", f.a}, {"b", f.b}, {"criterion", f.criterion}}},
            {"missing_at", f.missing_at},
            {"values", Json::array()}};
    if (f.b_sigma >= 0) fj["law"]["b_sigma"] = f.b_sigma;
    for (const auto& v : f.values) {
      Json vj{{"point", v.point}, {"x", v.x}, {"value", v.value}};
      if (v.sigma >= 0) vj["sigma"] = v.sigma;
      if (v.has_simulated) vj["simulated"] = v.simulated;
      fj["values"].push_back(vj);
    }
    j["findings"].push_back(fj);
  }
  if (!r.scheduled_model.empty()) j["scheduled_model"] = r.scheduled_model;
  j["leave_one_out"] = Json::array();
  for (const auto& l : r.leave_one_out) {
    Json lj{{"point", l.point}, {"x", l.x}, {"from", {l.from_lo, l.from_hi}}};
    if (l.refused.empty()) {
      lj["error_simulation"] = l.error_simulation;
      lj["error_scheduled"] = l.error_scheduled;
      lj["error_extended"] = l.error_extended;
      lj["left_out"] = l.left_out;
    } else {
      lj["refused"] = l.refused;
    }
    j["leave_one_out"].push_back(lj);
  }
  return j;
}

namespace {
// A state table's header after its two first columns: a column per point, then the flags.
void point_columns(std::ostringstream& md, const std::vector<EnvelopePoint>& points) {
  for (const auto& p : points) md << " " << num(p.x) << " |";
  md << " flags |\n|---|---|";
  for (size_t i = 0; i < points.size(); ++i) md << "---|";
  md << "---|\n";
}
}  // namespace

std::string envelope_markdown(const EnvelopeReport& r) {
  std::ostringstream md;
  md << "# Envelope\n\nOperating points by " << r.schedule_by << ":";
  for (const auto& p : r.points) md << " " << num(p.x) << " (`" << p.name << "/`)";
  md << ".\n\n## States across paths and points\n\nEach state's root per point: a real pole as "
        "its time constant (s), a pair as wn (rad/s) and zeta; in brackets the spread over its "
        "paths' own fits; sigma the paths' median relative sigma.\n\n| state | kind |";
  point_columns(md, r.points);
  for (const auto& t : r.tracks) {
    md << "| " << t.label << " | " << (t.pair ? "pair" : "real") << " |";
    for (const auto& p : r.points) {
      const TrackValue* v = nullptr;
      for (const auto& x : t.values)
        if (x.point == p.name) v = &x;
      if (!v) {
        md << " - |";
        continue;
      }
      md << " " << num(v->value);
      if (v->pair) md << ", " << num(v->zeta);
      if (v->spread_hi > v->spread_lo)
        md << " [" << num(v->spread_lo) << "-" << num(v->spread_hi) << "]";
      if (v->rel_sigma >= 0) md << " +-" << num(100 * v->rel_sigma) << "%";
      md << " |";
    }
    md << " " << t.flags << " |\n";
  }
  if (!r.slow_states.empty()) {
    md << "\n### Slow states, as the report's Section III averages them\n\nEach path's slowest "
          "real pole; the plant's over the outputs whose values agree, a sensor's where an "
          "output's is slower at every point. Per point the time constant (s) averaged over the "
          "paths, in brackets their range and count, and the inverse of their poles' mean (the "
          "report's tables use either).\n\n| state | outputs |";
    point_columns(md, r.points);
    for (const auto& t : r.slow_states) {
      md << "| " << t.label << " |";
      for (size_t k = 0; k < t.outputs.size(); ++k) md << (k ? ", " : " ") << t.outputs[k];
      md << " |";
      for (const auto& p : r.points) {
        const SlowState::Value* v = nullptr;
        for (const auto& x : t.values)
          if (x.point == p.name) v = &x;
        if (!v)
          md << " - |";
        else
          md << " " << num(v->tau_s) << " [" << num(v->lo) << "-" << num(v->hi) << ", "
             << v->paths.size() << (v->paths.size() == 1 ? " path" : " paths") << "; 1/mean pole "
             << num(v->tau_of_mean_pole_s) << "] |";
      }
      md << " " << t.flags << " |\n";
    }
  }
  md << "\n## Findings across points\n\n";
  if (r.findings.empty()) md << "None.\n";
  for (const auto& f : r.findings) md << "- " << f.text << "\n";
  if (!r.scheduled_model.empty())
    md << "\n## The scheduled extended model\n\n`" << r.scheduled_model
       << "`: the simulation at any " << r.schedule_by
       << " within the points (between its own points, interpolated along its roots' tracks) "
          "extended by the findings above, their parameters by their laws. A model at X: "
          "`--engine "
       << r.scheduled_model << "@X` (docs/formats.md §28).\n";
  if (!r.leave_one_out.empty()) {
    md << "\n## Leave-one-out\n\nAt each inner point, the scheduled extended model built "
          "without it (its simulation extended by the other points' findings, their laws fitted "
          "without it) against its measurement; the diagnosis' error metric.\n\n| point | from | "
          "simulation | "
          "scheduled | own extended model | notes |\n|---|---|---|---|---|---|\n";
    for (const auto& l : r.leave_one_out) {
      md << "| " << num(l.x) << " | " << l.from_lo << ", " << l.from_hi << " |";
      if (!l.refused.empty()) {
        md << " - | - | - | refused: " << l.refused << " |\n";
        continue;
      }
      md << " " << num(l.error_simulation) << " | " << num(l.error_scheduled) << " | "
         << num(l.error_extended) << " |";
      for (size_t k = 0; k < l.left_out.size(); ++k) md << (k ? "; " : " ") << l.left_out[k];
      md << " |\n";
    }
  }
  if (r.plots)
    md << "\n## Pictures\n\n![Root migration: each state's root against " << r.schedule_by
       << "](plots/roots.png)\n\n![Findings across points with their laws](plots/findings.png)\n";
  return md.str();
}

double law_value(const FindingLaw& l, double x) {
  if (l.law == "linear") return l.a + l.b * x;
  if (l.law == "power") return l.a * std::pow(x, l.b);
  return l.a;
}

std::vector<Finding> scheduled_findings(const std::vector<EnvelopePoint>& points, double x,
                                        const EnvelopeOptions& o,
                                        std::vector<std::string>* left_out) {
  if (points.size() < 2 || !(x >= points.front().x && x <= points.back().x))
    throw InputError(o.schedule_by + " " + num(x) +
                     ": outside the measured points' range; findings are never extrapolated");
  // Finding i of a point's diagnosis.json, and their count.
  auto finding = [](const EnvelopePoint& p, size_t i) {
    return finding_from_json(p.diagnosis["findings"][i],
                             {p.name + "/diagnosis.json", "/findings/" + std::to_string(i)});
  };
  auto count = [](const EnvelopePoint& p) {
    return p.diagnosis.is_object() && p.diagnosis.contains("findings")
               ? p.diagnosis["findings"].size()
               : size_t(0);
  };
  // At a measured point: that point's own findings, as its diagnosis gives them.
  for (const EnvelopePoint& p : points) {
    if (p.x != x) continue;
    std::vector<Finding> own;
    for (size_t i = 0; i < count(p); ++i) own.push_back(finding(p, i));
    return own;
  }
  size_t k = 1;
  while (k + 1 < points.size() && points[k].x < x) ++k;
  const EnvelopePoint &lo = points[k - 1], &hi = points[k];
  // The finding of a law at one point, as its diagnosis.json gives it.
  auto at = [&](const EnvelopePoint& p, const FindingLaw& l) -> std::optional<Finding> {
    for (size_t i = 0; i < count(p); ++i) {
      const Json& f = p.diagnosis["findings"][i];
      auto word = [&](const char* k) {
        return f.contains(k) && f[k].is_string() ? f[k].get<std::string>() : "";
      };
      if (word("cause") == l.cause && word("scope") == l.scope && word("input") == l.input &&
          word("output") == l.output)
        return finding(p, i);
    }
    return std::nullopt;
  };
  std::vector<Finding> out;
  const EnvelopeReport r = join_points(points, o);
  for (const FindingLaw& l : r.findings) {
    const auto a = at(lo, l), b = at(hi, l);
    if (!a || !b) {
      if (left_out)
        left_out->push_back(l.cause + " (" + l.scope + " " + l.input +
                            (l.output.empty() ? "" : " -> ") + l.output + "): not at both " +
                            lo.name + " and " + hi.name);
      continue;
    }
    const double t = (x - lo.x) / (hi.x - lo.x);
    Finding f = *a;
    for (auto& [key, v] : f.parameters) {
      const auto it = b->parameters.find(key);
      if (key == l.parameter)
        v = law_value(l, x);
      else if (it != b->parameters.end())
        v = v + (it->second - v) * t;  // the finding's other figures between its two points
    }
    out.push_back(f);
  }
  return out;
}

namespace {

// The scheduled extended model of the document j read from `file`, at x.
Model scheduled_model_of(const Json& j, const std::string& file, double x) {
  const JsonWhere w{file, ""};
  if (json_string_member(j, w, "format") != kScheduledModelFormat)
    json_fail(w / "format", std::string("not ") + kScheduledModelFormat);
  EnvelopeOptions o;
  o.schedule_by = json_string_member(j, w, "schedule_by");
  const Json& sims = json_array_member(j, w, "simulation");
  std::string set;
  for (size_t i = 0; i < sims.size(); ++i)
    set += (set.empty() ? "" : ",") + json_string(sims[i], w / "simulation" / i);
  if (sims.size() == 1) set += ",";  // one model: a list of one, not a family or folder
  InterpolationOptions io;
  io.schedule_by = o.schedule_by;
  Model m = model_at(load_model_set(set, o.schedule_by), x, io);
  const fs::path dir = fs::path(file).parent_path();
  std::vector<EnvelopePoint> points;
  const Json& ps = json_array_member(j, w, "points");
  for (size_t i = 0; i < ps.size(); ++i) {
    EnvelopePoint p;
    p.name = json_string_member(ps[i], w / "points" / i, "name");
    p.x = json_number_member(ps[i], w / "points" / i, "x");
    p.diagnosis =
        json_load_file((dir / json_string_member(ps[i], w / "points" / i, "diagnosis")).string());
    points.push_back(p);
  }
  std::sort(points.begin(), points.end(),
            [](const EnvelopePoint& a, const EnvelopePoint& b) { return a.x < b.x; });
  std::vector<std::string> left_out;
  Model ext = extend_model(m, scheduled_findings(points, x, o, &left_out));
  ext.name = "scheduled extended model at " + o.schedule_by + " " + num(x) + " (" + m.name + ")";
  ext.source = file + "@" + lossless(x);
  for (const std::string& l : left_out) ext.warnings.push_back(file + ": " + l + ": left out");
  return ext;
}

}  // namespace

Model scheduled_model_at(const std::string& file, double x) {
  return scheduled_model_of(json_load_file(file), file, x);
}

Model load_model_or_scheduled(const std::string& spec) {
  if (fs::is_regular_file(spec))
    if (const auto doc = state_space_document_if_mat(spec)) return parse_model(*doc, spec);
  if (!fs::exists(spec))
    if (const auto at = parse_model_at(spec); at && fs::is_regular_file(at->set)) {
      const Json j = json_load_file(at->set);
      if (j.is_object() && j.value("format", "") == kScheduledModelFormat) {
        const std::string key = j.value("schedule_by", "");
        if (at->schedule_by != key && at->schedule_by != "speed_pct")  // speed_pct: the default
          throw InputError(spec + ": the scheduled model is scheduled by " + key);
        return scheduled_model_of(j, at->set, at->x);
      }
    }
  return load_model_or_embedded(spec);
}

std::vector<LeaveOneOut> leave_one_out(const std::string& dir,
                                       const std::vector<EnvelopePoint>& points,
                                       const EnvelopeOptions& o) {
  std::vector<LeaveOneOut> out;
  auto ext = [&](const EnvelopePoint& p) { return dir + "/" + p.name + "/extended_model.json"; };
  for (size_t i = 1; i + 1 < points.size(); ++i) {
    const EnvelopePoint &lo = points[i - 1], &p = points[i], &hi = points[i + 1];
    LeaveOneOut l;
    l.point = p.name, l.x = p.x, l.from_lo = lo.name, l.from_hi = hi.name;
    try {
      const Model sim = load_model_or_embedded(p.simulation);
      const MeasuredFolder data = read_measured_folder(dir + "/" + p.name + "/measure");
      DiagnoseOptions opt;
      opt.chain = data.chain;
      // The point's own simulation extended by the findings of the others, their parameters
      // from laws fitted without this point.
      std::vector<EnvelopePoint> others = points;
      others.erase(others.begin() + long(i));
      const Model sched = extend_model(sim, scheduled_findings(others, p.x, o, &l.left_out));
      l.error_simulation = model_error(sim, sim, data.data, opt);
      l.error_scheduled = model_error(sched, sim, data.data, opt);
      l.error_extended = model_error(load_model(ext(p)), sim, data.data, opt);
    } catch (const std::exception& e) {
      l.refused = e.what();
    }
    out.push_back(l);
  }
  return out;
}

std::string envelope_point_name(const std::string& schedule_by, double x) {
  return schedule_by + "_" + lossless(x);
}

EnvelopeReport run_envelope(const EnvelopeCommand& c,
                            const std::function<void(const std::string&)>& log) {
  c.options.validate();
  auto say = [&](const std::string& s) {
    if (log) log(s);
  };
  const auto engines = load_model_set(c.engine, c.options.schedule_by);
  const auto sims = load_model_set(c.simulation, c.options.schedule_by);
  std::vector<std::pair<SetModel, SetModel>> pairs;
  for (const auto& e : engines) {
    const SetModel* s = nullptr;
    for (const auto& q : sims)
      if (q.x == e.x) s = &q;
    if (!s)
      throw InputError(e.spec + ": no simulation at " + c.options.schedule_by + " " + num(e.x) +
                       " in " + c.simulation);
    pairs.push_back({e, *s});
  }
  fs::create_directories(c.out);
  std::vector<EnvelopePoint> points;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const auto& [e, s] = pairs[i];
    const std::string name = envelope_point_name(c.options.schedule_by, e.x);
    const std::string dir = c.out + "/" + name;
    if (fs::exists(dir + "/diagnosis.json")) {
      say("point " + std::to_string(i + 1) + " of " + std::to_string(pairs.size()) + ", " + name +
          ": done before, kept");
    } else {
      if (fs::exists(dir)) {
        // Nothing recorded is lost: the interrupted point's folder (its tapes) is kept aside.
        std::string aside = dir + ".interrupted";
        for (int k = 2; fs::exists(aside); ++k) aside = dir + ".interrupted-" + std::to_string(k);
        fs::rename(dir, aside);
        say("point " + name + ": an interrupted run's folder, kept as " + aside +
            ", measured again");
      }
      say("point " + std::to_string(i + 1) + " of " + std::to_string(pairs.size()) + ", " + name +
          ": measuring " + e.spec + " and diagnosing " + s.spec + " ...");
      DiagnoseCommand d;
      d.simulation = s.spec;
      d.engine = e.spec;
      d.out = dir;
      d.measure = c.measure;
      d.measure.engine = e.spec;
      d.plots = c.plots;
      d.validation = c.validation;
      const DiagnoseResult res = run_diagnose(d);
      say("point " + name + ": " + res.summary);
    }
    EnvelopePoint p;
    p.name = name;
    p.x = e.x;
    p.simulation = s.spec;
    if (fs::exists(dir + "/measure/transfer_matrix.json"))
      p.transfer_matrix = json_load_file(dir + "/measure/transfer_matrix.json");
    if (fs::exists(dir + "/diagnosis.json")) p.diagnosis = json_load_file(dir + "/diagnosis.json");
    points.push_back(p);
  }
  EnvelopeReport r = join_points(points, c.options);
  // The scheduled extended model: the simulation set and the points' diagnoses.
  Json sm{{"format", kScheduledModelFormat},
          {"schedule_by", c.options.schedule_by},
          {"simulation", Json::array()},
          {"points", Json::array()}};
  for (const SetModel& q : sims)  // a file by its absolute path: the model is read from anywhere
    sm["simulation"].push_back(fs::exists(q.spec) ? fs::absolute(q.spec).string() : q.spec);
  for (const EnvelopePoint& p : points)
    sm["points"].push_back(
        {{"name", p.name}, {"x", p.x}, {"diagnosis", p.name + "/diagnosis.json"}});
  json_save_file(c.out + "/scheduled_model.json", sm);
  r.scheduled_model = "scheduled_model.json";
  say("the scheduled extended model: " + c.out + "/scheduled_model.json (a model at X: --engine " +
      c.out + "/scheduled_model.json@X)");
  r.leave_one_out = leave_one_out(c.out, points, c.options);
  for (const LeaveOneOut& l : r.leave_one_out)
    say("leave-one-out at " + l.point + ": " +
        (l.refused.empty()
             ? "error " + num(l.error_simulation) + " (simulation), " + num(l.error_scheduled) +
                   " (scheduled from " + l.from_lo + " and " + l.from_hi + "), " +
                   num(l.error_extended) + " (its own extended model)"
             : "refused: " + l.refused));
  if (c.plots) r.plots = render_envelope_plots(r, c.out);
  json_save_file(c.out + "/envelope.json", envelope_json(r));
  const std::string md = envelope_markdown(r);
  std::ofstream(c.out + "/envelope.md") << md;
  std::ofstream(c.out + "/report.md") << md;
  write_report_html(c.out, "Envelope: " + c.engine + " against " + c.simulation);
  return r;
}

}  // namespace fralab
