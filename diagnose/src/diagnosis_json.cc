// diagnosis.json (docs/formats.md §6 and §15): a diagnosis written, a finding read back (the
// envelope's scheduled model and the self-check read findings a run wrote); words at this edge,
// enums inside (names.cc).
#include <cmath>

#include "fralab/diagnose/diagnose.h"

namespace fralab {

namespace {
// A parameter per level (diagnosis.json's level_dependence; formats.md).
Json level_json(const LevelDependence& l) {
  Json iv = Json::array();
  for (const auto& x : l.intervals)
    iv.push_back({std::isfinite(x[0]) ? Json(x[0]) : Json(nullptr),
                  std::isfinite(x[1]) ? Json(x[1]) : Json(nullptr)});
  Json j = {{"parameter", to_string(l.parameter)},
            {"levels", l.levels},
            {"values", l.values},
            {"intervals", iv},
            {"slope", std::isfinite(l.slope) ? Json(l.slope) : Json(nullptr)},
            {"apart", l.apart}};
  if (std::isfinite(l.slope_sigma)) j["slope_sigma"] = l.slope_sigma;
  return j;
}

// The parameter a key of diagnosis.json names; InputError naming `where` and the key otherwise.
Param param_of(const std::string& key, const JsonWhere& where) {
  if (const auto p = param_from_string(key)) return *p;
  throw InputError((where / key).str() + ": '" + key +
                   "' is not a parameter of a finding (docs/formats.md §6 and §15)");
}

// {"delay_s": [lo, hi]}, null for an unbounded side.
Json intervals_json(const Finding& f) {
  Json j = Json::object();
  for (const auto& [k, v] : f.intervals)
    j[to_string(k)] = {std::isfinite(v[0]) ? Json(v[0]) : Json(nullptr),
                       std::isfinite(v[1]) ? Json(v[1]) : Json(nullptr)};
  return j;
}
}  // namespace

Finding finding_from_json(const Json& j, const JsonWhere& where) {
  json_require_object(j, where);
  Finding f;
  f.cause = cause_from_string(json_string_member(j, where, "cause"));
  f.scope = scope_from_string(json_string_member(j, where, "scope"));
  for (const char* k : {"input", "output"}) {
    const Json& v = json_member(j, where, k);
    (std::string(k) == "input" ? f.input : f.output) = v.is_null() ? "" : json_string(v, where / k);
  }
  const Json& p = json_member(j, where, "parameters");
  json_require_object(p, where / "parameters");
  for (auto it = p.begin(); it != p.end(); ++it) {
    if (it->is_string())
      f.text_parameters[it.key()] = it->get<std::string>();
    else
      f.parameters[param_of(it.key(), where / "parameters")] =
          json_number(*it, where / "parameters" / it.key());
  }
  const Json& pairs = json_array_member(j, where, "pairs");
  for (size_t i = 0; i < pairs.size(); ++i)
    f.pairs.push_back(json_string(pairs[i], where / "pairs" / i));
  if (j.contains("tf")) f.tf = tf_from_json(j["tf"], where / "tf", nullptr, true);
  if (j.contains("intervals")) {  // optional; null is an unbounded side
    const Json& iv = j["intervals"];
    json_require_object(iv, where / "intervals");
    for (auto it = iv.begin(); it != iv.end(); ++it) {
      const JsonWhere at = where / "intervals" / it.key();
      if (!it->is_array() || it->size() != 2)
        throw InputError(at.str() + ": an interval is [low, high] (null for an unbounded side)");
      std::array<double, 2> v{-INFINITY, INFINITY};
      for (size_t side = 0; side < 2; ++side)
        if (!(*it)[side].is_null()) v[side] = json_number((*it)[side], at / side);
      f.intervals[param_of(it.key(), where / "intervals")] = v;
    }
  }
  return f;
}

std::vector<Finding> findings_from_json(const Json& diagnosis, const std::string& file) {
  const JsonWhere root{file, ""};
  json_require_object(diagnosis, root);
  const Json& fs = json_array_member(diagnosis, root, "findings");
  std::vector<Finding> v;
  for (size_t k = 0; k < fs.size(); ++k)
    v.push_back(finding_from_json(fs[k], root / "findings" / k));
  return v;
}

namespace {
// A finding's cause, scope, channels, parameters (text ones among them), explanation, errors,
// pairs, intervals, and a missing path's tf.
Json finding_json(const Finding& f) {
  Json p = Json::object();
  for (const auto& [k, v] : f.parameters) p[to_string(k)] = v;
  for (const auto& [k, v] : f.text_parameters) p[k] = v;
  Json j{{"cause", to_string(f.cause)},
         {"scope", to_string(f.scope)},
         {"output", f.output.empty() ? Json(nullptr) : Json(f.output)},
         {"input", f.input.empty() ? Json(nullptr) : Json(f.input)},
         {"parameters", p},
         {"explanation", f.explanation},
         {"error_before", f.error_before},
         {"error_after", f.error_after},
         {"pairs", f.pairs},
         {"intervals", intervals_json(f)}};
  if (f.tf) j["tf"] = tf_to_json(*f.tf);
  return j;
}
}  // namespace

Json diagnosis_to_json(const Diagnosis& d) {
  Json j{{"format", "fralab-diagnosis/1"}, {"findings", Json::array()}};
  for (const auto& f : d.findings) {
    j["findings"].push_back(finding_json(f));
    if (f.level) {
      Json& lj = j["findings"].back()["level_dependence"] = level_json(*f.level);
      for (const LevelDependence& l : f.level_secondary) lj["secondary"].push_back(level_json(l));
    }
  }
  for (const StateAlternative& a : d.state_alternatives) {
    Json fs = Json::array();
    for (const Finding& f : a.findings) fs.push_back(finding_json(f));
    j["state_alternatives"].push_back({{"findings", fs}, {"chi2_above", a.chi2_above}});
  }
  j["measurement_chain"] = chain_to_json(d.chain);
  j["dropped"] = Json::array();
  for (const auto& x : d.dropped) {
    Json p = Json::object();
    for (const auto& [k, v] : x.finding.parameters) p[to_string(k)] = v;
    j["dropped"].push_back(
        {{"cause", to_string(x.finding.cause)},
         {"scope", to_string(x.finding.scope)},
         {"output", x.finding.output.empty() ? Json(nullptr) : Json(x.finding.output)},
         {"input", x.finding.input.empty() ? Json(nullptr) : Json(x.finding.input)},
         {"parameters", p},
         {"pairs", x.finding.pairs},
         {"intervals", intervals_json(x.finding)},
         {"reason", x.reason}});
  }
  j["unexplained"] = Json::array();
  for (const auto& u : d.unexplained) {
    j["unexplained"].push_back({{"pair", u.pair},
                                {"band_hz", {u.band_hz[0], u.band_hz[1]}},
                                {"residual", u.residual},
                                {"chi2", u.chi2},
                                {"explanation", u.explanation}});
  }
  j["summary"] = {
      {"metric", d.metric}, {"error_before", d.error_before}, {"error_after", d.error_after}};
  if (d.validation_before >= 0) {
    j["summary"]["validation_error_before"] = d.validation_before;
    j["summary"]["validation_error_after"] = d.validation_after;
  }
  j["pairs"] = Json::array();
  for (const auto& p : d.pairs) {
    j["pairs"].push_back({{"pair", p.pair},
                          {"beyond_uncertainty", p.beyond},
                          {"chi2_simulation", p.chi2_sim},
                          {"chi2_extended", p.chi2_ext},
                          {"n_points", p.w.size()},
                          {"error_before", p.error_sim},
                          {"error_after", p.error_ext}});
  }
  return j;
}

}  // namespace fralab
