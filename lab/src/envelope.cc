// `fralab envelope`'s campaign and leave-one-out (lab/envelope.h).
#include "fralab/lab/envelope.h"

#include <filesystem>
#include <fstream>

#include "fralab/core/error.h"
#include "fralab/core/text.h"
#include "fralab/diagnose/report.h"
#include "fralab/lab/diagnose_command.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/schedule.h"

namespace fs = std::filesystem;

namespace fralab {
namespace {

std::string num(double v) { return significant(v, 4); }

}  // namespace

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

namespace {

using Say = std::function<void(const std::string&)>;

// The engine set's models, each with the simulation at its operating point.
std::vector<std::pair<SetModel, SetModel>> engine_simulation_pairs(
    const EnvelopeCommand& c, const std::vector<SetModel>& engines,
    const std::vector<SetModel>& sims) {
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
  return pairs;
}

// Point i of n: measured and diagnosed into its folder unless a diagnosis is there (an
// interrupted run's folder kept aside); read back as an envelope point.
EnvelopePoint measure_point(const EnvelopeCommand& c, const SetModel& e, const SetModel& s,
                            size_t i, size_t n, const Say& say) {
  const std::string name = envelope_point_name(c.options.schedule_by, e.x);
  const std::string dir = c.out + "/" + name;
  if (fs::exists(dir + "/diagnosis.json")) {
    say("point " + std::to_string(i + 1) + " of " + std::to_string(n) + ", " + name +
        ": done before, kept");
  } else {
    if (fs::exists(dir)) {
      // Nothing recorded is lost: the interrupted point's folder (its tapes) is kept aside.
      std::string aside = dir + ".interrupted";
      for (int k = 2; fs::exists(aside); ++k) aside = dir + ".interrupted-" + std::to_string(k);
      fs::rename(dir, aside);
      say("point " + name + ": an interrupted run's folder, kept as " + aside + ", measured again");
    }
    say("point " + std::to_string(i + 1) + " of " + std::to_string(n) + ", " + name +
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
  return p;
}

// The scheduled extended model's file (the simulation set and the points' diagnoses).
void save_scheduled_model(const EnvelopeCommand& c, const std::vector<SetModel>& sims,
                          const std::vector<EnvelopePoint>& points) {
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
}

}  // namespace

EnvelopeReport run_envelope(const EnvelopeCommand& c,
                            const std::function<void(const std::string&)>& log) {
  c.options.validate();
  const Say say = [&](const std::string& s) {
    if (log) log(s);
  };
  const auto engines = load_model_set(c.engine, c.options.schedule_by);
  const auto sims = load_model_set(c.simulation, c.options.schedule_by);
  const auto pairs = engine_simulation_pairs(c, engines, sims);
  fs::create_directories(c.out);
  std::vector<EnvelopePoint> points;
  for (size_t i = 0; i < pairs.size(); ++i)
    points.push_back(measure_point(c, pairs[i].first, pairs[i].second, i, pairs.size(), say));
  EnvelopeReport r = join_points(points, c.options);
  save_scheduled_model(c, sims, points);
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
