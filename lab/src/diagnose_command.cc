#include "fralab/lab/diagnose_command.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <sstream>

#include "fralab/acquire/model_info.h"
#include "fralab/core/measure_dir.h"
#include "fralab/diagnose/baseline.h"
#include "fralab/diagnose/data_faults.h"
#include "fralab/diagnose/extended_state_space.h"
#include "fralab/diagnose/report.h"
#include "fralab/envelope/envelope.h"
#include "fralab/exchange/data_quality.h"
#include "fralab/exchange/state_space_mat.h"
#include "fralab/lab/data_check.h"
#include "fralab/lab/run_lock.h"
#include "fralab/lcm/tape_file.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/realisation.h"

namespace fralab {

namespace fs = std::filesystem;

MeasuredFolder read_measured_folder(const std::string& dir) {
  MeasuredFolder f;
  f.data = read_measured_dir(dir);
  // The lab's measurement chain, as the measurement recorded it (else an ideal one).
  const std::string run_file = MeasureDir(dir).run_json();
  if (fs::exists(run_file)) {
    // Its measurement chain only (RunRecord's key, read alone): a folder measured by an older
    // fralab, whose run.json lacks most of today's keys, is diagnosed all the same.
    const Json run = json_load_file(run_file);
    if (run.contains("measurement_chain")) {
      f.chain = chain_from_json(run["measurement_chain"], {run_file, "/measurement_chain"});
      return f;
    }
  }
  // Else the tape's own record of it (the start event's), when the folder has the tape.
  const std::string tape = MeasureDir(dir).tape();
  if (fs::exists(tape)) {
    for (const StatusEvent& e : read_tape_run(tape).events) {
      if (e.state != RunState::kStart) continue;
      if (!e.measurement_chain_error.empty())  // compared against no chain would be wrong
        throw InputError(tape + ": " + e.measurement_chain_error);
      if (e.measurement_chain) {
        f.chain = *e.measurement_chain;
        break;
      }
    }
  }
  return f;
}

Json recorded_data_quality(const std::string& dir, DataNotes* notes) {
  Json runs = Json::array();
  auto take = [&](const DataQuality& q, const std::string& folder) {
    Json r = data_quality_to_json(q);
    r["folder"] = folder;
    runs.push_back(std::move(r));
    notes->checked = true;
    for (const DataFault& f : q.faults)
      notes->faults.push_back(folder + ": " + f.text + "; " + f.action + ".");
  };
  std::function<void(const MeasureDir&)> visit = [&](const MeasureDir& m) {
    if (fs::exists(m.run_json())) {
      const Json run = json_load_file(m.run_json());
      if (run.contains("data_quality"))
        take(data_quality_from_json(run["data_quality"], {m.run_json(), "/data_quality"}), m.root);
    }
    // A folder `fralab analyze --log` wrote (a tape from elsewhere): its section beside the curves.
    if (const std::string f = m.root + "/data_quality.json"; fs::exists(f))
      take(data_quality_from_json(json_load_file(f), {f, ""}), m.root);
    for (const MeasureDir& sub : {m.multisine(), m.sine(), m.validation()})
      if (fs::exists(sub.run_json())) visit(sub);
  };
  visit(MeasureDir(dir));
  return runs;
}

namespace {

// The further levels' curves attached to the measurement's pairs (MeasuredPair::levels, a pair a
// level's folder lacks left empty there) and the levels given; diagnosis.json's `levels`
// (null without --levels or --level-values).
Json attach_levels(const DiagnoseCommand& c, std::vector<MeasuredPair>& data) {
  if (!c.level_values.empty() && c.level_values.size() != 1 + c.levels.size())
    throw InputError("--level-values: " + std::to_string(c.level_values.size()) + " values for " +
                     std::to_string(1 + c.levels.size()) +
                     " measurements (the measured one, then each of --levels)");
  for (size_t k = 0; k < c.level_values.size(); ++k)
    if (!(c.level_values[k] > 0) || !std::isfinite(c.level_values[k]))
      throw InputError("--level-values: value " + std::to_string(k + 1) +
                       " is not a positive number");
  if (c.levels.empty() && c.level_values.empty()) return nullptr;
  auto level_of = [&](size_t k) { return c.level_values.empty() ? 0.0 : c.level_values[k]; };
  Json j = Json::array();
  j.push_back({{"folder", c.measured.empty() ? std::string("(measured)") : c.measured},
               {"level", c.level_values.empty() ? Json(nullptr) : Json(level_of(0))}});
  for (MeasuredPair& mp : data) {
    mp.level = level_of(0);
    mp.levels.assign(c.levels.size(), LevelCurve{});
  }
  for (size_t k = 0; k < c.levels.size(); ++k) {
    int matched = 0;
    for (const MeasuredPair& lp : read_measured_folder(c.levels[k]).data)
      for (MeasuredPair& mp : data)
        if (mp.pair == lp.pair) {
          mp.levels[k] = {level_of(k + 1), lp.frd};
          ++matched;
        }
    if (matched == 0)
      throw InputError("--levels " + c.levels[k] + ": none of the measured pairs is in it");
    j.push_back({{"folder", c.levels[k]},
                 {"level", c.level_values.empty() ? Json(nullptr) : Json(level_of(k + 1))},
                 {"pairs", matched}});
  }
  return j;
}

// Per channel the campaign's clock estimates pooled, for the channels the checks did not name
// (those are mended): the measured periods' mean time from the measurement's own runs (those
// under `measured`, not its validation).
std::map<std::string, ClockEvidence> clock_evidence(const std::vector<ClockEstimate>& all,
                                                    const std::string& measured) {
  const std::vector<std::string> named = pooled_clocks(all);
  const std::string validation = MeasureDir(measured).validation().root;
  std::vector<ClockEstimate> measurement;  // the measurement's runs' own, for the times
  for (const ClockEstimate& e : all)
    if (!e.run.starts_with(validation)) measurement.push_back(e);
  const std::map<std::string, ClockEstimate> times = pool_clocks(measurement);
  std::map<std::string, ClockEvidence> out;
  for (const auto& [ch, e] : pool_clocks(all)) {
    if (std::find(named.begin(), named.end(), ch) != named.end()) continue;
    const auto t = times.find(ch);
    out[ch] = {e.eps, e.sigma, t != times.end() ? t->second.t_mid_s : e.t_mid_s};
  }
  return out;
}

// Where the diagnosed data come from: the measure folder, its name in the report, and the clock
// estimates of the runs that made it (the clock alternative's evidence).
struct DataSource {
  std::string dir, name;
  std::vector<ClockEstimate> clocks;
};

// With --engine: the engine measured into OUT/measure (and, with validation, once more at another
// seed and 1.5x the amplitude into its validation/), the partial runs said in res.
DataSource measure_engine(const DiagnoseCommand& c, const Model& sim, DiagnoseResult& res) {
  MeasureOptions m = c.measure;
  m.engine = c.engine;
  if (m.acquire.inputs.empty()) {
    for (const auto& in : sim.inputs)
      m.acquire.inputs += (m.acquire.inputs.empty() ? "" : ",") + in.name;
  }
  if (m.auto_campaign) m.acquire.excitation = Excitation::kMultisine;  // its first run's
  if (c.zoom && m.acquire.excitation == Excitation::kMultisine && m.acquire.zoom.empty()) {
    const auto [lo, hi] = parse_band(m.acquire.band);
    m.acquire.zoom = light_modes(sim, lo, hi);
  }
  m.out = c.out + "/measure";
  const MeasureResult measured = measure(m);
  if (measured.partial()) res.partial.push_back(partial_run_message(measured, m.out));
  DataSource src{m.out, c.engine + " (measured by fralab, seed " + std::to_string(m.seed),
                 measured.clock_estimates};
  if (!c.validation) {
    src.name += "; no validation measurement)";
    return src;
  }
  // An independent measurement for validation, not used for fitting: another noise seed and a
  // second amplitude (1.5x), so amplitude-dependent effects (hysteresis, deadband) are verified.
  MeasureOptions v = m;
  v.seed = m.seed + 1;
  v.acquire.amplitude_scale = 1.5 * m.acquire.amplitude_scale;
  v.out = MeasureDir(m.out).validation().root;
  v.clock_estimates = measured.clock_estimates;  // the same recorder's clocks, pooled
  const MeasureResult validated = measure(v);
  if (validated.partial()) res.partial.push_back(partial_run_message(validated, v.out));
  src.clocks = validated.clock_estimates;
  // A clock the pool of both measurements names, which the measurement's own runs did not: they
  // are checked again, so the curves diagnosed are mended as the validation's are.
  ClockRecheck again = recheck_clocks(m.out, validated.clock_estimates);
  if (const std::string refit = refit_after_recheck(m.out, again, m.fit_delay, m.timeout_s);
      !refit.empty())
    again.lines.push_back(refit);
  for (const std::string& line : again.lines)
    std::cerr << "fralab: data quality, checked again: " << line << "\n";
  src.name += "; validation: seed " + std::to_string(v.seed) + " at 1.5x the amplitude)";
  return src;
}

// An output silent on every path where the simulation expects a response: over two or more
// inputs a dead sensor, its pairs set aside from `data` and named in `from_sim`; over one, left
// to the diagnosis, returned to be named beside what it finds there.
std::vector<SilentOutput> set_aside_silent_outputs(const Model& sim,
                                                   std::vector<MeasuredPair>& data,
                                                   const DiagnoseOptions& opt,
                                                   DataQuality& from_sim) {
  for (const ModelOutput& o : sim.outputs) from_sim.checked.push_back(o.name);
  std::vector<SilentOutput> silent_kept;
  for (const SilentOutput& s : silent_outputs(sim, data, opt)) {
    if (s.inputs.size() < 2) {
      silent_kept.push_back(s);
      continue;
    }
    std::erase_if(data, [&](const MeasuredPair& mp) {
      return std::find(s.pairs.begin(), s.pairs.end(), mp.pair) != s.pairs.end();
    });
    DataFault f;
    f.channel = s.output;
    f.kind = DataFaultKind::kNoResponse;
    f.text = s.text;
    f.action = "its pairs (" + join_list(s.pairs) +
               ") set aside: nothing is concluded from them; check the sensor and its wiring";
    from_sim.faults.push_back(std::move(f));
  }
  return silent_kept;
}

// diagnosis.json's data_quality section: every run's recorded faults (the data's, the baseline's
// and each level's), the channels checked against the simulation, and the data faults that could
// stand for a finding (notes.alternatives, from the clipped channels' largest shares, the silent
// outputs kept and the runs' clocks); the report's lines go to `notes`.
Json data_quality_section(const DiagnoseCommand& c, const Diagnosis& d, const Model& sim,
                          const std::vector<MeasuredPair>& data, const DiagnoseOptions& opt,
                          const DataSource& src, const DataQuality& from_sim,
                          const std::vector<SilentOutput>& silent_kept, DataNotes& notes) {
  Json runs = recorded_data_quality(src.dir, &notes);
  if (!c.baseline.empty()) {
    for (Json& r : recorded_data_quality(c.baseline, &notes)) runs.push_back(std::move(r));
  }
  for (const std::string& l : c.levels)
    for (Json& r : recorded_data_quality(l, &notes)) runs.push_back(std::move(r));
  std::map<std::string, double> clipped;  // per channel, the largest share over the runs
  for (const Json& r : runs)
    for (const Json& f : r["faults"])
      if (f["kind"] == "clipping") {
        double& share = clipped[f["channel"].get<std::string>()];
        share = std::max(share, f["size"].get<double>());
      }
  notes.alternatives = data_alternatives(d, sim, data, opt, clipped, silent_kept,
                                         clock_evidence(src.clocks, src.dir));
  for (const DataFault& f : from_sim.faults)
    notes.faults.push_back("the measurement against the simulation: " + f.text + "; " + f.action +
                           ".");
  return {{"runs", runs},
          {"channels", data_quality_to_json(from_sim)},
          {"alternatives", data_alternatives_to_json(notes.alternatives)}};
}

// The extended model as fralab-model/1 (read back: it must be one the plant can run) and as a
// state model (fralab-ss/1 and .mat); a model that has none (no path with dynamics) is said, and
// the diagnosis stands.
void write_extended_models(const Model& sim, const Diagnosis& d, const std::string& out) {
  Model ext = d.extended;
  ext.name = sim.name + " + diagnosis";
  ext.warnings.clear();
  save_model(out + "/extended_model.json", ext);
  load_model(out + "/extended_model.json");
  try {
    const Json ss = model_state_space_document(ext, extended_state_space(sim, d));
    json_save_file(out + "/extended_model_ss.json", ss);
    write_state_space_mat(out + "/extended_model.mat", ss);
  } catch (const InputError& e) {
    std::fprintf(stderr, "fralab: the extended model as a state model: %s\n", e.what());
  }
}

}  // namespace

DiagnoseResult run_diagnose(const DiagnoseCommand& c) {
  DiagnoseResult res;
  if (c.out.empty()) throw InputError("--out DIR is required");
  if (c.engine.empty() == c.measured.empty())
    throw InputError("give exactly one of --engine TRUTH.json or --measured DIR");
  Model sim = load_model_or_scheduled(c.simulation);
  // The diagnosis's folder is its own until it ends (its measurements take their sub-folders).
  const RunLock lock(c.out, "fralab diagnose");
  DataSource src =
      c.engine.empty() ? DataSource{c.measured, c.measured, {}} : measure_engine(c, sim, res);
  const MeasuredFolder folder = read_measured_folder(src.dir);
  DiagnoseOptions opt;
  opt.chain = folder.chain;
  std::vector<MeasuredPair> data = folder.data;
  DataQuality from_sim;
  const std::vector<SilentOutput> silent_kept = set_aside_silent_outputs(sim, data, opt, from_sim);
  const Json levels_json = attach_levels(c, data);
  Json baseline_json;
  if (!c.baseline.empty()) {
    BaselineSummary s;
    data = relative_to_baseline(sim, data, read_measured_folder(c.baseline).data, opt, &s);
    baseline_json = {{"folder", c.baseline},
                     {"pairs", s.pairs},
                     {"points", s.points},
                     {"left_out", s.left_out},
                     {"pairs_without", s.without}};
    src.name += ", relative to the baseline " + c.baseline +
                " (the simulation's misfit there is its own, not a finding)";
  }
  Diagnosis d = diagnose(sim, data, opt);
  Json dj = diagnosis_to_json(d);
  DataNotes notes;
  dj["data_quality"] =
      data_quality_section(c, d, sim, data, opt, src, from_sim, silent_kept, notes);
  if (!baseline_json.is_null()) dj["baseline"] = baseline_json;
  if (!levels_json.is_null()) dj["levels"] = levels_json;
  json_save_file(c.out + "/diagnosis.json", dj);
  write_extended_models(sim, d, c.out);
  const bool plots = c.plots && render_diagnosis_plots(d, c.out);
  write_diagnosis_report(d, sim.name, src.name, plots, c.out, notes);
  write_report_html(c.out, "Diagnosis: " + sim.name);
  res.summary = diagnosis_summary(d, c.out);
  return res;
}
}  // namespace fralab
