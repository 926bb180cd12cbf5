// The envelope's report: `fralab-envelope/1` and its markdown (envelope.h).
#include <cmath>
#include <sstream>

#include "envelope_text.h"
#include "fralab/core/text.h"
#include "fralab/envelope/envelope.h"

namespace fralab {
namespace {

using envelope_text::num;

}  // namespace

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

// The value of `values` (a track's or a slow state's, each naming its point) at point `name`,
// the last one there; nullptr where it has none.
template <class Value>
const Value* value_at(const std::vector<Value>& values, const std::string& name) {
  const Value* v = nullptr;
  for (const auto& x : values)
    if (x.point == name) v = &x;
  return v;
}

// The states' table: each track's root per point with its spread and sigma, and its flags.
void tracks_table(std::ostringstream& md, const EnvelopeReport& r) {
  md << ".\n\n## States across paths and points\n\nEach state's root per point: a real pole as "
        "its time constant (s), a pair as wn (rad/s) and zeta; in brackets the spread over its "
        "paths' own fits; sigma the paths' median relative sigma.\n\n| state | kind |";
  point_columns(md, r.points);
  for (const auto& t : r.tracks) {
    md << "| " << t.label << " | " << (t.pair ? "pair" : "real") << " |";
    for (const auto& p : r.points) {
      const TrackValue* v = value_at(t.values, p.name);
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
}

// The slow states' table, as the report's Section III averages them (none: nothing).
void slow_states_table(std::ostringstream& md, const EnvelopeReport& r) {
  if (r.slow_states.empty()) return;
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
      const SlowState::Value* v = value_at(t.values, p.name);
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

// The leave-one-out table (none: nothing).
void leave_one_out_table(std::ostringstream& md, const EnvelopeReport& r) {
  if (r.leave_one_out.empty()) return;
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

}  // namespace

std::string envelope_markdown(const EnvelopeReport& r) {
  std::ostringstream md;
  md << "# Envelope\n\nOperating points by " << r.schedule_by << ":";
  for (const auto& p : r.points) md << " " << num(p.x) << " (`" << p.name << "/`)";
  tracks_table(md, r);
  slow_states_table(md, r);
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
  leave_one_out_table(md, r);
  if (r.plots)
    md << "\n## Pictures\n\n![Root migration: each state's root against " << r.schedule_by
       << "](plots/roots.png)\n\n![Findings across points with their laws](plots/findings.png)\n";
  return md.str();
}

}  // namespace fralab
