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
#include "fralab/core/text.h"
#include "fralab/lab/diagnose_command.h"
#include "fralab/lab/run_record.h"
#include "fralab/plant/embedded_models.h"

namespace fralab {

namespace {

struct RunCommand {
  MeasureOptions measure;
  std::string simulation;
  std::string operating_point;
  bool zoom = true;  // the multisine's zoom on the simulation's light modes
};

void run(RunCommand c) {
  std::string sim = c.simulation;
  if (sim.empty()) {
    // The engine's embedded _sim model, or family (j85 -> j85_sim) at an operating point.
    const std::string base = std::filesystem::path(c.measure.engine).stem().string();
    auto in_family = [&](const std::string& n) {  // base_<digits>_sim.json
      const std::string head = base + "_", tail = "_sim.json";
      if (n.size() <= head.size() + tail.size() || n.rfind(head, 0) != 0 ||
          n.compare(n.size() - tail.size(), tail.size(), tail) != 0)
        return false;
      const std::string digits = n.substr(head.size(), n.size() - head.size() - tail.size());
      return digits.find_first_not_of("0123456789") == std::string::npos;
    };
    for (const auto& e : embedded_models())
      if (std::string(e.name) == base + "_sim.json" ||
          (!c.operating_point.empty() && in_family(e.name)))
        sim = base + "_sim";
  }
  c.measure.engine = at_operating_point(c.measure.engine, c.operating_point);
  sim = at_operating_point(sim, c.operating_point);
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
  d.zoom = c.zoom;
  std::printf("fralab: measuring %s and diagnosing %s ...\n", c.measure.engine.c_str(),
              sim.c_str());
  const DiagnoseResult res = run_diagnose(d);
  const std::string m = c.measure.out + "/measure";
  const MeasureDir md(m);
  const AnyRunRecord record = load_any_run_record(md.run_json());
  std::string tapes = md.tape();
  double engine_s = 0, wall_s = 0, speedup = 0;
  if (const auto* run = std::get_if<RunRecord>(&record)) {
    engine_s = run->engine_time_s.value_or(0.0);
    wall_s = run->wall_time_s.value_or(0.0);
    speedup = run->speedup.value_or(0.0);
  } else {
    const auto& campaign = std::get<AutoRunRecord>(record);
    engine_s = campaign.engine_time_s;
    wall_s = campaign.wall_time_s;
    speedup = campaign.speedup;
    tapes = md.multisine().tape();
    if (!campaign.sine.inputs.empty()) {
      const std::string ins = join_list(campaign.sine.inputs, ",");
      tapes += " and " + md.sine().tape();
      std::printf(
          "fralab: auto campaign: orthogonal multisine %.0f s, sine for %s (it distorts at the "
          "multisine's level) %.0f s\n",
          campaign.multisine.engine_time_s, ins.c_str(), campaign.sine.engine_time_s);
    }
  }
  std::printf(
      "fralab: engine time %.0f s (%.2f h) measured in %.1f s (%.0fx), tape %s, transfer matrix "
      "%s/transfer_matrix.md\n",
      engine_s, engine_s / 3600, wall_s, speedup, tapes.c_str(), m.c_str());
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
  c->add_flag("!--no-zoom", rc->zoom,
              "by multisine: no zoom on the simulation's light modes (the grid alone)");
  add_measure_flags(c, rc->measure);
  add_operating_point_flag(c, rc->operating_point);
  c->callback([rc] { run(*rc); });
}

}  // namespace fralab
