#include "fralab/acquire/acquire_flags.h"

#include "fralab/core/text.h"

namespace fralab {

void add_acquire_flags(CLI::App* c, AcquireOptions& o, bool* auto_campaign) {
  c->add_option("--input", o.inputs, "input(s) NAME[,NAME...] to excite (default: all)");
  c->add_option("--band", o.band, "LO_HZ:HI_HZ")->capture_default_str();
  c->add_option_function<std::string>(
       "--excitation",
       [&o, auto_campaign](const std::string& word) {
         if (auto_campaign) *auto_campaign = word == "auto";
         o.excitation = excitation_from_string(word == "auto" ? "multisine" : word);
       },
       std::string("stepped (stepped sine), sweep (continuous log sweep) or multisine (all inputs "
                   "at once; --min-cycles = periods per experiment)") +
           (auto_campaign ? "; auto: multisine, then sine for the actuators that distort at its "
                            "level"
                          : ""))
      ->check(auto_campaign ? CLI::IsMember({"stepped", "sweep", "multisine", "auto"})
                            : CLI::IsMember({"stepped", "sweep", "multisine"}))
      ->default_str(auto_campaign && *auto_campaign ? "auto" : to_string(o.excitation));
  c->add_option("--multisine-phases", o.multisine_phases,
                "schroeder, random or low-crest (random, then envelope clipping)")
      ->capture_default_str();
  c->add_flag("--odd-lines", o.odd_lines, "multisine: odd harmonics only");
  c->add_option_function<std::string>(
       "--multisine-design",
       [&o](const std::string& w) { o.multisine_design = multisine_design_from_string(w); },
       "orthogonal (every input on every line, n_u experiments, DFT phase matrix) or zippered "
       "(disjoint lines, one experiment)")
      ->check(CLI::IsMember({"orthogonal", "zippered"}))
      ->default_str("orthogonal");
  c->add_option("--realisations", o.realisations,
                "orthogonal multisine: random-phase realisations (> 1: with --multisine-phases "
                "random; separates nonlinear distortion from noise)")
      ->capture_default_str();
  c->add_option("--points-per-decade", o.points_per_decade)->capture_default_str();
  c->add_option("--amplitude-pct", o.amplitude_pct,
                "% of full scale (default: the input's test_amplitude_pct, else 2)");
  c->add_option("--amplitude-scale", o.amplitude_scale, "multiplies every input's amplitude")
      ->capture_default_str();
  c->add_option("--min-cycles", o.min_cycles)->capture_default_str();
  c->add_option("--min-integrate-s", o.min_integrate_s)->capture_default_str();
  c->add_option("--settle-cycles", o.settle_cycles,
                "stepped sine: cycles of settle per step, at least (and >= 5 time constants)")
      ->capture_default_str();
  c->add_option("--sample-rate", o.sample_rate_hz, "Hz")->capture_default_str();
  c->add_option("--speed", o.speed, "1 = real time, 100 = 100x, 0 = as fast as consumers keep up")
      ->capture_default_str();
  c->add_option("--block", o.block, "samples per command block")->capture_default_str();
  c->add_option("--window", o.window, "blocks in flight ahead of the slowest consumer")
      ->capture_default_str();
  c->add_option("--settle-time-constant-s", o.slowest_time_constant_s,
                "settling time constant, s (default: the model's slowest)");
  c->add_flag("--free-running", o.free_running,
              "the plant runs on its own clock at --speed (not in lockstep); commands are kept "
              "--lead blocks ahead and a step an underrun touches is repeated");
  c->add_option("--lead", o.lead, "free-running: command blocks ahead of the plant's clock")
      ->capture_default_str();
  c->add_option("--max-repeats", o.max_repeats,
                "free-running: rounds of repeated steps before the run fails")
      ->capture_default_str();
  c->add_option("--sigma-target", o.adaptive.sigma_target,
                "stepped sine, adaptive: integrate each step until sigma / |G| on every pair of "
                "its input is at most this (e.g. 0.01), at most the fixed plan's cycles "
                "(--min-cycles, --min-integrate-s); 0: the fixed plan")
      ->capture_default_str();
  c->add_option("--pilot-cycles", o.adaptive.pilot_cycles,
                "adaptive: cycles of each step's first window, and the unit of its extensions")
      ->capture_default_str();
  c->add_option("--adaptive-decided", o.adaptive_decided,
                "adaptive, resume: the extensions taken before, STEP*CYCLES,... (from the tape)");
}

std::vector<std::string> acquire_flags(const AcquireOptions& o) {
  std::vector<std::string> f = {"--band",
                                o.band,
                                "--excitation",
                                to_string(o.excitation),
                                "--multisine-phases",
                                o.multisine_phases,
                                "--multisine-design",
                                to_string(o.multisine_design),
                                "--realisations",
                                std::to_string(o.realisations),
                                "--points-per-decade",
                                std::to_string(o.points_per_decade),
                                "--amplitude-pct",
                                lossless(o.amplitude_pct),
                                "--amplitude-scale",
                                lossless(o.amplitude_scale),
                                "--min-cycles",
                                std::to_string(o.min_cycles),
                                "--min-integrate-s",
                                lossless(o.min_integrate_s),
                                "--settle-cycles",
                                lossless(o.settle_cycles),
                                "--sample-rate",
                                lossless(o.sample_rate_hz),
                                "--speed",
                                lossless(o.speed),
                                "--block",
                                std::to_string(o.block),
                                "--window",
                                std::to_string(o.window),
                                "--settle-time-constant-s",
                                lossless(o.slowest_time_constant_s)};
  if (o.odd_lines) f.push_back("--odd-lines");
  if (o.free_running)
    f.insert(f.end(), {"--free-running", "--lead", std::to_string(o.lead), "--max-repeats",
                       std::to_string(o.max_repeats)});
  if (!o.inputs.empty()) f.insert(f.end(), {"--input", o.inputs});
  if (o.adaptive.enabled()) {
    f.insert(f.end(), {"--sigma-target", lossless(o.adaptive.sigma_target), "--pilot-cycles",
                       std::to_string(o.adaptive.pilot_cycles)});
    if (!o.adaptive_decided.empty()) f.insert(f.end(), {"--adaptive-decided", o.adaptive_decided});
  }
  return f;
}

}  // namespace fralab
