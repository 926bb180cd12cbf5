#include "fralab/lab/bound_command.h"

#include <cstdio>
#include <filesystem>

#include "fralab/core/error.h"
#include "fralab/core/json_util.h"
#include "fralab/core/measure_dir.h"
#include "fralab/envelope/envelope.h"
#include "fralab/lab/diagnose_command.h"

namespace fralab {

namespace fs = std::filesystem;

namespace {

double engine_time_of(const std::string& dir) {
  const std::string file = MeasureDir(dir).run_json();
  if (!fs::exists(file))
    throw InputError(file + ": no run record, so the measurement's engine time is unknown");
  return json_number_member(json_load_file(file), {file, ""}, "engine_time_s");
}

std::string line(const char* format, auto... args) {
  char buf[320];
  std::snprintf(buf, sizeof buf, format, args...);
  return buf;
}

std::string table(const EngineTimeBound& b, const std::vector<Finding>& findings,
                  double validation_s) {
  std::string t = line("engine time %.1f s (validation %.1f s more); ", b.campaign_s, validation_s);
  if (b.status != EngineTimeBound::Status::kOk) return t + b.message + "\n";
  t += line("the best sine needs %.3g s: ratio %.3g\n", b.bound_s, b.ratio);
  t += line("  %-34s %-12s %12s %11s  %-22s %10s %9s\n", "finding", "parameter", "value", "sigma",
            "best sine (input, rad/s)", "bound s", "ratio");
  for (const ParameterBound& p : b.parameters)
    t += line("  %-34s %-12s %12.6g %11.3g  %-8s %13.4g %10.3g %9.3g\n",
              finding_label(findings[p.finding]).c_str(), to_string(p.parameter), p.value,
              p.sigma_data, p.best_input.c_str(), p.best_w_rad_s, p.bound_s,
              b.campaign_s / p.bound_s);
  return t;
}

Json bound_json(const EngineTimeBound& b, const std::vector<Finding>& findings,
                double validation_s) {
  Json j{{"format", "fralab-bound/1"},
         {"status", b.status == EngineTimeBound::Status::kOk ? "ok" : "no_parameter"},
         {"message", b.message},
         {"campaign_s", b.campaign_s},
         {"validation_s", validation_s},
         {"bound_s", b.bound_s},
         {"ratio", b.ratio},
         {"input_amplitude", b.input_amplitude},
         {"parameters", Json::array()}};
  for (const ParameterBound& p : b.parameters) {
    const Finding& f = findings[p.finding];
    j["parameters"].push_back({{"finding", p.finding},
                               {"cause", to_string(f.cause)},
                               {"scope", to_string(f.scope)},
                               {"input", f.input},
                               {"output", f.output},
                               {"parameter", to_string(p.parameter)},
                               {"value", p.value},
                               {"sigma_data", p.sigma_data},
                               {"best_input", p.best_input},
                               {"best_w_rad_s", p.best_w_rad_s},
                               {"best_amplitude", p.best_amplitude},
                               {"rate", p.rate},
                               {"bound_s", p.bound_s},
                               {"ratio", b.campaign_s / p.bound_s}});
  }
  return j;
}

}  // namespace

BoundResult run_bound(const BoundCommand& c) {
  const std::string file = c.diagnosis + "/diagnosis.json";
  if (!fs::exists(file)) throw InputError(file + ": no diagnosis there (give a diagnose folder)");
  const Json dj = json_load_file(file);
  if (dj.is_object() && dj.contains("baseline"))
    throw InputError(file +
                     ": a diagnosis relative to a baseline (its data are ratios of two "
                     "measurements); the bound needs the measurement itself");
  const std::vector<Finding> findings = findings_from_json(dj, file);
  const std::string measured = c.measured.empty() ? c.diagnosis + "/measure" : c.measured;
  if (!fs::is_directory(measured))
    throw InputError(measured + ": no measure folder (give --measured DIR)");
  const Model sim = load_model_or_scheduled(c.simulation);
  const MeasuredFolder folder = read_measured_folder(measured);
  BoundResult r;
  const std::string validation = measured + "/validation";
  if (fs::exists(MeasureDir(validation).run_json())) r.validation_s = engine_time_of(validation);
  r.bound = engine_time_bound(sim, findings, folder.data, folder.chain, engine_time_of(measured));
  r.table = table(r.bound, findings, r.validation_s);
  if (!c.json.empty()) json_save_file(c.json, bound_json(r.bound, findings, r.validation_s));
  return r;
}

}  // namespace fralab
