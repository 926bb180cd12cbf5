// fralab-plant: the engine emulator process. Subscribes to actuator command blocks (FRALAB_CMD),
// advances the model exactly as many samples as commanded, and publishes tape blocks (FRALAB_TAPE)
// with the commands echoed (u_<input>), every actuator position, every output and the reference
// channels. Lockstep by default: it never runs ahead and never drops a block. --free-running: it
// runs on its own clock like hardware (--speed x real time, --tick samples per tape block, tick
// times jittered by --jitter-ms), playing commands from a buffer that can run dry (PlantNode).
#include <CLI/CLI.hpp>
#include <iostream>

#include "fralab/lcm/lab_lcm.h"
#include "fralab/lcm/tape_file.h"
#include "fralab/plant/embedded_models.h"
#include "plant_node.h"

using namespace fralab;

int main(int argc, char** argv) {
  CLI::App app{"fralab-plant: the engine emulator (fralab-model/1) in lockstep over LCM"};
  std::string model_file, url;
  SimulatorOptions opt;
  ServeOptions serve_opt;
  bool no_noise = false;
  app.add_option("--model", model_file, "model file (or embedded name, e.g. j85_95)")->required();
  app.add_option("--lcm-url", url, "LCM URL (default $LCM_DEFAULT_URL or udpm ...?ttl=0)");
  app.add_option("--sample-rate", opt.sample_rate_hz, "plant sample rate, Hz")
      ->capture_default_str();
  app.add_option("--seed", opt.seed, "noise seed")->capture_default_str();
  app.add_flag("--no-noise", no_noise, "turn every noise source off");
  app.add_option("--linger", serve_opt.linger_s,
                 "seconds to wait after the final block for the acquisition's close")
      ->capture_default_str();
  app.add_flag("--keep-running", serve_opt.keep_running, "do not exit after the final block");
  std::string run_id, ctl_url;
  app.add_option("--control-url", ctl_url,
                 "LCM URL for acknowledgements (default: --lcm-url with port + 1)");
  app.add_option("--run-id", run_id, "only this run (default: the first command's)");
  std::string replay;
  int64_t replay_blocks = 0;
  app.add_option("--replay", replay,
                 "resume: first replay this run's tape blocks 0..N-1 from this tape (bit-exact "
                 "check), then take command blocks from N on");
  app.add_option("--replay-blocks", replay_blocks, "N for --replay")->capture_default_str();
  app.add_flag("--free-running", serve_opt.free_running,
               "run on the plant's own clock (not in lockstep): commands from a buffer that can "
               "run dry");
  app.add_option("--speed", serve_opt.speed, "free-running: x real time")->capture_default_str();
  app.add_option("--tick", serve_opt.tick, "free-running: samples per tape block")
      ->capture_default_str();
  app.add_option("--jitter-ms", serve_opt.jitter_ms,
                 "free-running: each tick's time off by up to this much (uniform, seeded)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  opt.noise = !no_noise;
  serve_opt.sample_rate_hz = opt.sample_rate_hz;
  serve_opt.seed = opt.seed;
  try {
    Model model = load_model_or_embedded(model_file);
    for (const auto& w : model.warnings) std::cerr << "fralab-plant: warning: " << w << "\n";
    LabLcm io(url, ctl_url);
    LockstepPlant lockstep(model, opt, run_id);
    if (!replay.empty()) {  // resume: back to the exact state where the recorded run stands
      if (run_id.empty()) throw InputError("--replay needs --run-id");
      for (const Block& b : read_tape_blocks(replay, run_id, replay_blocks)) lockstep.replay(b);
      std::cerr << "fralab-plant: replayed " << replay_blocks << " tape blocks of " << replay
                << ": the plant makes them again bit for bit\n";
    }
    if (serve_opt.free_running && !replay.empty())
      throw InputError(
          "--free-running needs --speed > 0, --tick >= 1, --jitter-ms >= 0 and no --replay");
    serve_opt.validate();  // before the node subscribes: a bad clock is refused first
    PlantNode plant(io.data, io.control, std::move(lockstep), 1024,
                    serve_opt.free_running ? serve_opt.tick : 0);
    serve(plant, io.data, serve_opt);
    if (!plant.warnings().empty()) std::cerr << "fralab-plant: warning: " << plant.warnings();
    if (plant.resent() > 0)
      std::cerr << "fralab-plant: " << plant.resent() << " tape blocks republished on request\n";
    if (plant.underrun_samples() > 0 || plant.late_blocks() > 0)
      std::cerr << "fralab-plant: the command buffer ran dry for " << plant.underrun_samples()
                << " samples (held); " << plant.late_blocks() << " command blocks came too late\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-plant: " << e.what() << "\n";
    return 1;
  }
}
