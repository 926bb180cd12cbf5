// `fralab measure`: plant, acquisition, analysers and identifier on one engine; tape and frd files.
#include <algorithm>
#include <cstdio>
#include <memory>

#include "commands.h"

namespace fralab {

void add_measure_flags(CLI::App* c, MeasureOptions& m) {
  add_acquire_flags(c, m.acquire);
  c->add_option("--seed", m.seed, "plant noise seed")->capture_default_str();
  c->add_option("--lcm-url", m.lcm_url, "LCM URL (default: a private one per run)");
  c->add_flag("--no-noise", m.no_noise, "plant noise off");
}

void print_measure(const MeasureResult& r, const std::string& out) {
  std::printf(
      "fralab: %zu pairs measured; engine time %.0f s (%.2f h), wall time %.1f s (%.0fx); tape "
      "%s/tape.lcmlog (%lld blocks); frd in %s/frd\n",
      r.pairs.size(), r.engine_time_s, r.engine_time_s / 3600, r.wall_time_s,
      r.engine_time_s / std::max(r.wall_time_s, 1e-9), out.c_str(), (long long)r.tape_blocks,
      out.c_str());
}

void add_measure_command(CLI::App& app) {
  auto mo = std::make_shared<MeasureOptions>();
  auto* c = app.add_subcommand("measure", "plant, acquisition, analysers: tape and frd files");
  c->add_option("--engine", mo->engine, "engine model file or embedded name")->required();
  c->add_option("--out", mo->out)->required();
  add_measure_flags(c, *mo);
  c->callback([mo] { print_measure(run_measure(*mo), mo->out); });
}

}  // namespace fralab
