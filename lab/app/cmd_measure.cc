// `fralab measure`: plant, acquisition, analysers and identifier on one engine; tape and frd files.
#include <algorithm>
#include <cstdio>
#include <memory>

#include "commands.h"

namespace fralab {

void add_measure_flags(CLI::App* c, MeasureOptions& m) {
  c->add_option("--input", m.inputs, "input(s) NAME[,NAME...] (default: all)");
  c->add_option("--band", m.band, "LO_HZ:HI_HZ")->capture_default_str();
  c->add_option("--excitation", m.excitation, "stepped, sweep or multisine (all inputs at once)")
      ->capture_default_str();
  c->add_option("--multisine-phases", m.multisine_phases, "schroeder or random")
      ->capture_default_str();
  c->add_flag("--odd-lines", m.odd_lines, "multisine: odd harmonics only");
  c->add_option("--points-per-decade", m.points_per_decade)->capture_default_str();
  c->add_option("--amplitude-pct", m.amplitude_pct, "% of full scale (default: per input, 2)");
  c->add_option("--seed", m.seed, "plant noise seed")->capture_default_str();
  c->add_option("--amplitude-scale", m.amplitude_scale, "multiplies every input's amplitude")
      ->capture_default_str();
  c->add_option("--speed", m.speed, "1 = real time, 0 = as fast as possible")
      ->capture_default_str();
  c->add_option("--sample-rate", m.sample_rate_hz, "Hz")->capture_default_str();
  c->add_option("--min-cycles", m.min_cycles)->capture_default_str();
  c->add_option("--min-integrate-s", m.min_integrate_s)->capture_default_str();
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
