// The scheduled extended model: the findings at a scheduling value from the points' laws, and the
// model files that hold them (envelope.h).
#include <cmath>
#include <filesystem>
#include <regex>

#include "envelope_text.h"
#include "fralab/core/error.h"
#include "fralab/core/text.h"
#include "fralab/envelope/envelope.h"
#include "fralab/exchange/state_space_mat.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/schedule.h"

namespace fs = std::filesystem;

namespace fralab {
namespace {

using envelope_text::num;

// A finding's primary parameter from its law at x.
double law_value(const FindingLaw& l, double x) {
  if (l.law == "linear") return l.a + l.b * x;
  if (l.law == "power") return l.a * std::pow(x, l.b);
  return l.a;
}

}  // namespace

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
      if (to_string(key) == l.parameter)
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
  if (sims.empty()) json_fail(w / "simulation", "no simulation: the set needs a model at least");
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

std::string envelope_point_name(const std::string& schedule_by, double x) {
  return schedule_by + "_" + lossless(x);
}

}  // namespace fralab
