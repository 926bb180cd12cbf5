// `fralab diagnose`: what the simulation gets wrong, why, and the extended model.
#include <cstdio>
#include <memory>

#include "commands.h"
#include "fralab/lab/diagnose_command.h"

namespace fralab {

void add_diagnose_command(CLI::App& app) {
  auto dc = std::make_shared<DiagnoseCommand>();
  // With --engine it measures with the campaign that decides itself, as `fralab run` does
  // (lab/auto_campaign.h); `--excitation stepped` keeps the report's procedure. (`fralab measure`
  // keeps the report's test, one tape in its folder: docs/formats.md §5.)
  dc->measure.auto_campaign = true;
  auto* c =
      app.add_subcommand("diagnose", "what the simulation gets wrong, why, and the extended model");
  c->add_option("--simulation", dc->simulation,
                "the simulation (a fralab-model/1 or fralab-ss/1 file, a state model .mat, or an "
                "embedded name)")
      ->required();
  c->add_option("--engine", dc->engine,
                "measure this engine model first (every flag of measure applies)");
  c->add_option("--measured", dc->measured, "or: a measure output folder");
  c->add_option("--baseline", dc->baseline,
                "a measure folder the simulation was fitted to or last agreed with: what differed "
                "there is the simulation's own misfit; the findings are what changed since");
  c->add_option("--levels", dc->levels,
                "measure folders of the same pairs at further excitation levels: each finding's "
                "parameters per level and their law (relative to --baseline when given)");
  c->add_option("--level-values", dc->level_values,
                "the levels of --measured and of each --levels folder, in that order, in your unit "
                "(e.g. force rms in N); default: each measurement's median excitation amplitude")
      ->delimiter(',');
  c->add_option("--out", dc->out)->required();
  c->add_flag("!--no-plots", dc->plots, "skip the gnuplot figures");
  c->add_flag("!--no-validation", dc->validation,
              "with --engine: no second measurement to validate on (each finding earns its place "
              "on the fitting data; half the engine time)");
  c->add_flag("!--no-zoom", dc->zoom,
              "with --engine by multisine: no zoom on the simulation's light modes (the grid "
              "alone)");
  add_measure_flags(c, dc->measure);
  auto op = std::make_shared<std::string>();
  add_operating_point_flag(c, *op);
  c->callback([dc, op] {
    dc->simulation = at_operating_point(dc->simulation, *op);
    dc->engine = at_operating_point(dc->engine, *op);
    const DiagnoseResult r = run_diagnose(*dc);
    std::printf("fralab: %s\n", r.summary.c_str());
    throw_if_partial(r.partial);
  });
}

}  // namespace fralab
