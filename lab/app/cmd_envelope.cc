// `fralab envelope`: an engine across its operating points, each measured, identified and
// diagnosed as `fralab run` does, then joined: states across paths and points, findings across
// points with their laws in the scheduling variable (lab/envelope.h).
#include <cstdio>
#include <memory>

#include "commands.h"
#include "fralab/lab/envelope.h"

namespace fralab {

void add_envelope_command(CLI::App& app) {
  auto ec = std::make_shared<EnvelopeCommand>();
  ec->measure.auto_campaign = true;  // the campaign that decides itself, as `fralab run`
  auto* c = app.add_subcommand("envelope",
                               "an engine across its operating points: each measured and "
                               "diagnosed, then states and findings joined across them");
  c->add_option("--engine", ec->engine,
                "the engines: an embedded family (j85), a comma list of model files or names, or "
                "a folder of model files, each with its operating_point")
      ->required();
  c->add_option("--simulation", ec->simulation,
                "the simulations, the same way (j85_sim), paired by the scheduling variable")
      ->required();
  c->add_option("--out", ec->out, "DIR: DIR/<point>/ as fralab run's, DIR/envelope.{json,md}")
      ->required();
  c->add_option("--schedule-by", ec->options.schedule_by,
                "the operating_point key the points are ordered and the laws fitted by")
      ->capture_default_str();
  c->add_flag("!--no-plots", ec->plots, "skip the gnuplot figures");
  auto* with = c->add_flag("--validation", ec->validation,
                           "a validation measurement at each point too (as fralab diagnose's: "
                           "another seed, 1.5x the amplitude; twice the engine time)");
  c->add_flag("!--no-validation", ec->validation,
              "each point measured once (the default; the leave-one-out checks the schedule)")
      ->excludes(with);
  add_measure_flags(c, ec->measure);
  c->callback([ec] {
    const EnvelopeReport r = run_envelope(
        *ec, [](const std::string& s) { std::printf("fralab: envelope: %s\n", s.c_str()); });
    std::printf("fralab: envelope of %zu points: %zu states, %zu findings; %s/envelope.md\n",
                r.points.size(), r.tracks.size(), r.findings.size(), ec->out.c_str());
    for (const FindingLaw& f : r.findings) std::printf("  %s\n", f.text.c_str());
  });
}

}  // namespace fralab
