// `fralab bound`: the engine time a best-designed experiment would need for a diagnosis' findings.
#include <cstdio>
#include <memory>

#include "commands.h"
#include "fralab/lab/bound_command.h"

namespace fralab {

void add_bound_command(CLI::App& app) {
  auto bc = std::make_shared<BoundCommand>();
  auto* c = app.add_subcommand(
      "bound", "engine time: the measurement's against the best sine's for the same intervals");
  c->add_option("--simulation", bc->simulation, "the simulation the diagnosis was made against")
      ->required();
  c->add_option("--diagnosis", bc->diagnosis, "a diagnose (or run) output folder")->required();
  c->add_option("--measured", bc->measured, "its fitting measurement (default DIAGNOSIS/measure)");
  c->add_option("--json", bc->json, "write fralab-bound/1 JSON here");
  c->callback([bc] { std::printf("fralab bound: %s", run_bound(*bc).table.c_str()); });
}

}  // namespace fralab
