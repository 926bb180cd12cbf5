// `fralab run`: the lab end to end. With a simulation to compare with (given, or the engine's
// embedded `_sim` model), the diagnosis measures the engine (and once more for validation),
// identifies every path and compares; otherwise it measures only. The excitation defaults to the
// auto campaign (an orthogonal multisine, a sine for the actuators that distort:
// lab/auto_campaign.h); `--excitation stepped` is the report's stepped sine, one actuator after
// the other.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "commands.h"
#include "fralab/core/measure_dir.h"
#include "fralab/lab/diagnose_command.h"
#include "fralab/plant/embedded_models.h"

namespace fralab {

namespace {

struct RunCommand {
  MeasureOptions measure;
  std::string simulation;
};

void run(const RunCommand& c) {
  std::string sim = c.simulation;
  if (sim.empty()) {
    const std::string base = std::filesystem::path(c.measure.engine).stem().string();
    for (const auto& e : embedded_models())
      if (std::string(e.name) == base + "_sim.json") sim = base + "_sim";
  }
  if (sim.empty()) {
    const MeasureResult r = measure(c.measure);
    print_measure(r, c.measure.out);
    if (r.partial()) throw_if_partial({partial_run_message(r, c.measure.out)});
    return;
  }
  DiagnoseCommand d;
  d.simulation = sim;
  d.engine = c.measure.engine;
  d.out = c.measure.out;
  d.measure = c.measure;
  std::printf("fralab: measuring %s and diagnosing %s ...\n", c.measure.engine.c_str(),
              sim.c_str());
  const DiagnoseResult res = run_diagnose(d);
  const std::string m = c.measure.out + "/measure";
  const MeasureDir md(m);
  const Json rj = json_load_file(md.run_json());
  std::string tapes = md.tape();
  if (rj.value("excitation", "") == "auto") {
    tapes = md.multisine().tape();
    if (!rj["sine"]["inputs"].empty()) {
      std::string ins;
      for (const auto& x : rj["sine"]["inputs"])
        ins += (ins.empty() ? "" : ",") + x.get<std::string>();
      tapes += " and " + md.sine().tape();
      std::printf(
          "fralab: auto campaign: orthogonal multisine %.0f s, sine for %s (it distorts at the "
          "multisine's level) %.0f s\n",
          rj["multisine"]["engine_time_s"].get<double>(), ins.c_str(),
          rj["sine"]["engine_time_s"].get<double>());
    }
  }
  std::printf(
      "fralab: engine time %.0f s (%.2f h) measured in %.1f s (%.0fx), tape %s, transfer matrix "
      "%s/transfer_matrix.md\n",
      rj["engine_time_s"].get<double>(), rj["engine_time_s"].get<double>() / 3600,
      rj["wall_time_s"].get<double>(), rj["speedup"].get<double>(), tapes.c_str(), m.c_str());
  std::printf("fralab: %s\n", res.summary.c_str());
  throw_if_partial(res.partial);
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto rc = std::make_shared<RunCommand>();
  rc->measure.out = "out/lab";
  // The campaign that decides itself by default (lab/auto_campaign.h); `--excitation stepped`
  // keeps the report's procedure.
  rc->measure.auto_campaign = true;
  rc->measure.acquire.excitation = Excitation::kMultisine;
  auto* c =
      app.add_subcommand("run", "the lab end to end on an engine (default: embedded J85 95 %)");
  c->add_option("--engine", rc->measure.engine, "engine model file or embedded name")
      ->capture_default_str();
  c->add_option("--out", rc->measure.out)->capture_default_str();
  c->add_option(
      "--simulation", rc->simulation,
      "diagnose against this simulation (default: the engine's _sim model when embedded)");
  add_measure_flags(c, rc->measure);
  c->callback([rc] { run(*rc); });
}

}  // namespace fralab
