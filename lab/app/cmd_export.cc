// `fralab export`: results for MATLAB, Octave, Python and spreadsheets (exchange/results_export.h),
// or a run's tape as a time series and its schedule (exchange/tape_series.h), which `fralab
// import` turns back into the same tape; or a model as a state model (plant/realisation.h), for
// MATLAB, Octave and fralab (`--simulation`, `--engine`).
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.h"
#include "fralab/core/error.h"
#include "fralab/envelope/envelope.h"
#include "fralab/exchange/envelope_export.h"
#include "fralab/exchange/results_export.h"
#include "fralab/exchange/state_space_mat.h"
#include "fralab/exchange/tape_series.h"
#include "fralab/lcm/tape_file.h"
#include "fralab/plant/realisation.h"

namespace fs = std::filesystem;

namespace fralab {

namespace {

struct ExportCommand {
  std::string from, tape, model, run_id, to = "mat", out, schedule_out;
};

// Units of the tape's channels from the engine.json a measure directory keeps beside its tape.
void units_from_engine(const std::string& tape, TimeSeries* s) {
  const auto units = channel_units((fs::path(tape).parent_path() / "engine.json").string());
  for (size_t i = 0; i < s->channels.size(); ++i) {
    auto it = units.find(s->channels[i]);
    if (it != units.end()) s->units[i] = it->second;
  }
}

// A model (a file, a state model .mat, an embedded J85 model) as a state model: .mat or
// fralab-ss/1 JSON.
void export_model(const ExportCommand& c) {
  if (c.to != "mat" && c.to != "json") throw InputError("--to " + c.to + ": mat or json");
  const Model m = load_model_or_scheduled(c.model);
  const StateSpace ss = model_state_space(m);
  const Json doc = model_state_space_document(m, ss);
  const std::string out =
      !c.out.empty() ? c.out : fs::path(c.model).stem().string() + "_ss." + c.to;
  if (c.to == "mat")
    write_state_space_mat(out, doc);
  else
    json_save_file(out, doc);
  std::printf("fralab: %s as a state model: %lld states, %zu inputs, %zu outputs to %s\n",
              c.model.c_str(), static_cast<long long>(ss.A.rows()), ss.inputs.size(),
              ss.outputs.size(), out.c_str());
}

void run(const ExportCommand& c) {
  if (int(!c.from.empty()) + int(!c.tape.empty()) + int(!c.model.empty()) != 1)
    throw InputError(
        "give one of --from DIR (results), --tape TAPE (a time series) and --model MODEL (a "
        "state model)");
  if (!c.model.empty()) return export_model(c);
  if (c.to != "mat" && c.to != "csv") throw InputError("--to " + c.to + ": mat or csv");
  if (!c.from.empty() && is_envelope_dir(c.from)) {
    if (c.to != "mat")
      throw InputError(c.from +
                       ": an envelope exports to .mat (its tables are envelope.json and "
                       "envelope.md; each point's measurement exports from its measure/)");
    const std::string out = !c.out.empty() ? c.out : c.from + "/fralab.mat";
    export_envelope_mat(c.from, out);
    std::printf("fralab: exported the envelope (points, states, findings, leave-one-out) to %s\n",
                out.c_str());
    return;
  }
  if (!c.from.empty()) {
    const std::string out =
        !c.out.empty() ? c.out : c.from + (c.to == "mat" ? "/fralab.mat" : "/export");
    const ExportSummary s =
        c.to == "mat" ? export_results_mat(c.from, out) : export_results_csv(c.from, out);
    std::printf("fralab: exported %d frequency responses, %d transfer functions%s to %s\n", s.frd,
                s.tf, s.state_model ? " and the state model" : "", s.written.c_str());
    return;
  }
  const TapeRun run = read_tape_run(c.tape, c.run_id);
  TimeSeries series = blocks_to_series(run.blocks, c.tape);
  units_from_engine(c.tape, &series);
  Schedule schedule;
  schedule.sample_rate_hz = series.sample_rate_hz;
  schedule.run_id = run.run_id;
  schedule.events = run.events;
  const std::string out =
      !c.out.empty() ? c.out : fs::path(c.tape).replace_extension("." + c.to).string();
  const std::string sched_out = !c.schedule_out.empty()
                                    ? c.schedule_out
                                    : fs::path(out).replace_extension(".schedule.json").string();
  if (c.to == "mat")
    write_mat_series(out, series);
  else
    write_csv_series(out, series);
  json_save_file(sched_out, schedule_to_json(schedule));
  std::printf(
      "fralab: run %s: %lld samples of %zu channels at %g Hz to %s, %zu status events to %s\n",
      run.run_id.c_str(), static_cast<long long>(series.n_samples), series.channels.size(),
      series.sample_rate_hz, out.c_str(), schedule.events.size(), sched_out.c_str());
}

}  // namespace

void add_export_command(CLI::App& app) {
  auto ec = std::make_shared<ExportCommand>();
  auto* c = app.add_subcommand(
      "export",
      "results (frd, tf, transfer matrix, state model) or a tape's time series, to .mat or CSV");
  c->add_option("--from", ec->from,
                "a measure directory (its frd/, tf/, transfer_matrix.json) or an envelope's "
                "(envelope.json)");
  c->add_option("--tape", ec->tape, "a tape: its run as a time series and a schedule");
  c->add_option("--model", ec->model,
                "a model (fralab-model/1, fralab-ss/1, a state model .mat, or an embedded name "
                "such as j85_95_sim) as a state model: A, B, C, D with named states");
  c->add_option("--run", ec->run_id, "with --tape: the run id (default: the tape's first run)");
  c->add_option("--to,--format", ec->to, "mat (default) or csv; with --model mat or json");
  c->add_option("--out", ec->out,
                "the .mat file or CSV folder (default DIR/fralab.mat, DIR/export; with --tape "
                "TAPE.mat or TAPE.csv; with --model MODEL_ss.mat or MODEL_ss.json here)");
  c->add_option("--schedule-out", ec->schedule_out,
                "with --tape: the schedule (default OUT with .schedule.json)");
  c->callback([ec] { run(*ec); });
}

}  // namespace fralab
