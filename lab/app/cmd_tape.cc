// `fralab tape`: a tape's summary as JSON (channels, blocks, gaps, excitation states).
#include <cstdio>
#include <memory>

#include "commands.h"
#include "fralab/lcm/tape_file.h"

namespace fralab {

void add_tape_command(CLI::App& app) {
  auto log = std::make_shared<std::string>();
  auto* c = app.add_subcommand(
      "tape", "summarise a tape: channels, blocks, gaps, excitation states (JSON)");
  c->add_option("--log", *log, "tape (LCM log)")->required();
  c->callback([log] { std::printf("%s\n", tape_summary(*log).dump(2).c_str()); });
}

}  // namespace fralab
