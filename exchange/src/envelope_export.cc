#include "fralab/exchange/envelope_export.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>

#include "fralab/core/json_util.h"
#include "fralab/exchange/mat_file.h"

namespace fralab {

namespace {

constexpr double kAbsent = std::numeric_limits<double>::quiet_NaN();

// A number of `j` (NaN when the key is absent or null).
double number_or_nan(const Json& j, const JsonWhere& w, const std::string& key) {
  if (!j.contains(key) || j[key].is_null()) return kAbsent;
  return json_number(j[key], w / key);
}

std::string text_or_empty(const Json& j, const JsonWhere& w, const std::string& key) {
  if (!j.contains(key) || j[key].is_null()) return "";
  return json_string(j[key], w / key);
}

std::string numbered(const std::string& stem, size_t i) {
  const std::string n = std::to_string(i + 1);
  return stem + "_" + (n.size() < 2 ? "0" + n : n);
}

// The [lo, hi] array `key` of `v` appended to lo and hi (NaN both when it is not two numbers).
void add_interval(const Json& v, const JsonWhere& vw, const std::string& key,
                  std::vector<double>* lo, std::vector<double>* hi) {
  const Json& a = json_array_member(v, vw, key);
  lo->push_back(a.size() == 2 ? json_number(a[0], vw / key / 0) : kAbsent);
  hi->push_back(a.size() == 2 ? json_number(a[1], vw / key / 1) : kAbsent);
}

// A state's `values` (tw the state's place): each one's x and point appended, then `each` called
// with it; their columns added to s as "x" and "point".
void per_value(const Json& t, const JsonWhere& tw, MatValue& s,
               const std::function<void(const Json&, const JsonWhere&)>& each) {
  std::vector<double> x;
  std::vector<std::string> point;
  const Json& values = json_array_member(t, tw, "values");
  for (size_t k = 0; k < values.size(); ++k) {
    const JsonWhere vw = tw / "values" / k;
    x.push_back(json_number_member(values[k], vw, "x"));
    point.push_back(json_string_member(values[k], vw, "point"));
    each(values[k], vw);
  }
  s.add("x", MatValue::column(x));
  s.add("point", MatValue::str_list(point));
}

// Rows x 2: lo, hi.
MatValue two_columns(const std::vector<double>& lo, const std::vector<double>& hi) {
  std::vector<double> both = lo;
  both.insert(both.end(), hi.begin(), hi.end());
  return MatValue::matrix(lo.size(), 2, both);
}

MatValue states_of(const Json& states, const JsonWhere& w) {
  MatValue all = MatValue::structure();
  for (size_t i = 0; i < states.size(); ++i) {
    const Json& t = states[i];
    const JsonWhere tw = w / i;
    MatValue s = MatValue::structure();
    s.add("label", MatValue::str(json_string_member(t, tw, "label")));
    const std::string kind = json_string_member(t, tw, "kind");
    s.add("kind", MatValue::str(kind));
    std::vector<double> root, tau, wn, zeta, sig, spread_lo, spread_hi;
    per_value(t, tw, s, [&](const Json& v, const JsonWhere& vw) {
      const double t_s = number_or_nan(v, vw, "tau_s"), w_n = number_or_nan(v, vw, "wn_rad_s");
      tau.push_back(t_s);
      wn.push_back(w_n);
      zeta.push_back(number_or_nan(v, vw, "zeta"));
      root.push_back(kind == "pair" ? w_n : 1 / t_s);
      sig.push_back(number_or_nan(v, vw, "rel_sigma"));
      add_interval(v, vw, "spread", &spread_lo, &spread_hi);
    });
    s.add("root_rad_s", MatValue::column(root));
    s.add("tau_s", MatValue::column(tau));
    s.add("wn_rad_s", MatValue::column(wn));
    s.add("zeta", MatValue::column(zeta));
    s.add("rel_sigma", MatValue::column(sig));
    s.add("spread", two_columns(spread_lo, spread_hi));
    s.add("at_every_point",
          MatValue::scalar(json_bool(json_member(t, tw, "at_every_point"), tw / "at_every_point")));
    s.add("monotone", MatValue::scalar(json_bool(json_member(t, tw, "monotone"), tw / "monotone")));
    s.add("flags", MatValue::str(text_or_empty(t, tw, "flags")));
    all.add(numbered("state", i), s);
  }
  return all;
}

// The slow states (envelope.json `slow_states`; absent from a file written before them: empty).
MatValue slow_states_of(const Json& j, const JsonWhere& w) {
  MatValue all = MatValue::structure();
  if (!j.contains("slow_states")) return all;
  const Json& states = json_array_member(j, w, "slow_states");
  for (size_t i = 0; i < states.size(); ++i) {
    const Json& t = states[i];
    const JsonWhere tw = w / "slow_states" / i;
    MatValue s = MatValue::structure();
    s.add("label", MatValue::str(json_string_member(t, tw, "label")));
    std::vector<std::string> outputs;
    const Json& os = json_array_member(t, tw, "outputs");
    for (size_t k = 0; k < os.size(); ++k)
      outputs.push_back(json_string(os[k], tw / "outputs" / k));
    s.add("outputs", MatValue::str_list(outputs));
    std::vector<double> tau, sem, pole_tau, lo, hi;
    per_value(t, tw, s, [&](const Json& v, const JsonWhere& vw) {
      tau.push_back(json_number_member(v, vw, "tau_s"));
      sem.push_back(number_or_nan(v, vw, "sem"));
      pole_tau.push_back(number_or_nan(v, vw, "tau_of_mean_pole_s"));
      add_interval(v, vw, "range", &lo, &hi);
    });
    s.add("tau_s", MatValue::column(tau));
    s.add("sem", MatValue::column(sem));
    s.add("tau_of_mean_pole_s", MatValue::column(pole_tau));
    s.add("range", two_columns(lo, hi));
    s.add("flags", MatValue::str(text_or_empty(t, tw, "flags")));
    all.add(numbered("state", i), s);
  }
  return all;
}

MatValue findings_of(const Json& findings, const JsonWhere& w) {
  MatValue all = MatValue::structure();
  for (size_t i = 0; i < findings.size(); ++i) {
    const Json& f = findings[i];
    const JsonWhere fw = w / i;
    MatValue s = MatValue::structure();
    for (const char* k : {"cause", "scope", "input", "output", "parameter", "text"})
      s.add(k, MatValue::str(text_or_empty(f, fw, k)));
    std::vector<double> x, value, sigma, simulated;
    const Json& values = json_array_member(f, fw, "values");
    for (size_t k = 0; k < values.size(); ++k) {
      const JsonWhere vw = fw / "values" / k;
      x.push_back(json_number_member(values[k], vw, "x"));
      value.push_back(json_number_member(values[k], vw, "value"));
      sigma.push_back(number_or_nan(values[k], vw, "sigma"));
      simulated.push_back(number_or_nan(values[k], vw, "simulated"));
    }
    s.add("x", MatValue::column(x));
    s.add("value", MatValue::column(value));
    s.add("sigma", MatValue::column(sigma));
    s.add("simulated", MatValue::column(simulated));
    const Json& law = json_member(f, fw, "law");
    MatValue l = MatValue::structure();
    l.add("form", MatValue::str(json_string_member(law, fw / "law", "form")));
    for (const char* k : {"a", "b", "b_sigma"})
      l.add(k, MatValue::scalar(number_or_nan(law, fw / "law", k)));
    s.add("law", l);
    std::vector<std::string> missing;
    if (f.contains("missing_at"))
      for (size_t k = 0; k < f["missing_at"].size(); ++k)
        missing.push_back(json_string(f["missing_at"][k], fw / "missing_at" / k));
    s.add("missing_at", MatValue::str_list(missing));
    all.add(numbered("finding", i), s);
  }
  return all;
}

}  // namespace

bool is_envelope_dir(const std::string& dir) {
  return std::filesystem::is_regular_file(dir + "/envelope.json");
}

void export_envelope_mat(const std::string& dir, const std::string& out_file) {
  const std::string file = dir + "/envelope.json";
  const Json j = json_load_file(file);
  const JsonWhere w{file, ""};
  if (json_string_member(j, w, "format") != "fralab-envelope/1")
    json_fail(w / "format", "not fralab-envelope/1");
  const std::string schedule_by = json_string_member(j, w, "schedule_by");
  MatValue points = MatValue::structure();
  std::vector<std::string> names;
  std::vector<double> xs;
  const Json& ps = json_array_member(j, w, "points");
  for (size_t i = 0; i < ps.size(); ++i) {
    names.push_back(json_string_member(ps[i], w / "points" / i, "name"));
    xs.push_back(json_number_member(ps[i], w / "points" / i, "x"));
  }
  points.add("name", MatValue::str_list(names));
  points.add("x", MatValue::column(xs));
  const MatValue states = states_of(json_array_member(j, w, "states"), w / "states");
  const MatValue slow_states = slow_states_of(j, w);
  const MatValue findings = findings_of(json_array_member(j, w, "findings"), w / "findings");
  MatValue loo = MatValue::structure();
  std::vector<std::string> point, refused;
  std::vector<double> x, sim, sched, ext;
  if (j.contains("leave_one_out")) {
    const Json& ls = json_array_member(j, w, "leave_one_out");
    for (size_t i = 0; i < ls.size(); ++i) {
      const JsonWhere lw = w / "leave_one_out" / i;
      point.push_back(json_string_member(ls[i], lw, "point"));
      x.push_back(json_number_member(ls[i], lw, "x"));
      sim.push_back(number_or_nan(ls[i], lw, "error_simulation"));
      sched.push_back(number_or_nan(ls[i], lw, "error_scheduled"));
      ext.push_back(number_or_nan(ls[i], lw, "error_extended"));
      refused.push_back(text_or_empty(ls[i], lw, "refused"));
    }
  }
  loo.add("point", MatValue::str_list(point));
  loo.add("x", MatValue::column(x));
  loo.add("error_simulation", MatValue::column(sim));
  loo.add("error_scheduled", MatValue::column(sched));
  loo.add("error_extended", MatValue::column(ext));
  loo.add("refused", MatValue::str_list(refused));
  write_mat_file(out_file, {{"schedule_by", MatValue::str(schedule_by)},
                            {"points", points},
                            {"states", states},
                            {"slow_states", slow_states},
                            {"findings", findings},
                            {"leave_one_out", loo}});
}

}  // namespace fralab
