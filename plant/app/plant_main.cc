// fralab-plant: the engine emulator process. Subscribes to actuator command blocks (FRALAB_CMD),
// advances the model exactly as many samples as commanded, and publishes tape blocks (FRALAB_TAPE)
// with the commands echoed (u_<input>), every actuator position, every output and the reference
// channels. Lockstep by default: it never runs ahead and never drops a block. --free-running: it
// runs on its own clock like hardware (--speed x real time, --tick samples per tape block, tick
// times jittered by --jitter-ms), playing commands from a buffer that can run dry (PlantNode).
#include <CLI/CLI.hpp>
#include <chrono>
#include <iostream>
#include <random>

#include "fralab/lcm/lab_lcm.h"
#include "fralab/lcm/tape_file.h"
#include "fralab/plant/embedded_models.h"
#include "plant_node.h"

using namespace fralab;

int main(int argc, char** argv) {
  CLI::App app{"fralab-plant: the engine emulator (fralab-model/1) in lockstep over LCM"};
  std::string model_file, url;
  SimulatorOptions opt;
  bool no_noise = false, keep_running = false;
  app.add_option("--model", model_file, "model file (or embedded name, e.g. j85_95)")->required();
  app.add_option("--lcm-url", url, "LCM URL (default $LCM_DEFAULT_URL or udpm ...?ttl=0)");
  app.add_option("--sample-rate", opt.sample_rate_hz, "plant sample rate, Hz")
      ->capture_default_str();
  app.add_option("--seed", opt.seed, "noise seed")->capture_default_str();
  app.add_flag("--no-noise", no_noise, "turn every noise source off");
  double linger = 20;
  app.add_option("--linger", linger,
                 "seconds to wait after the final block for the acquisition's close")
      ->capture_default_str();
  app.add_flag("--keep-running", keep_running, "do not exit after the final block");
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
  bool free_running = false;
  double speed = 1.0, jitter_ms = 0.0;
  int tick = 100;
  app.add_flag("--free-running", free_running,
               "run on the plant's own clock (not in lockstep): commands from a buffer that can "
               "run dry");
  app.add_option("--speed", speed, "free-running: x real time")->capture_default_str();
  app.add_option("--tick", tick, "free-running: samples per tape block")->capture_default_str();
  app.add_option("--jitter-ms", jitter_ms,
                 "free-running: each tick's time off by up to this much (uniform, seeded)")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  opt.noise = !no_noise;
  try {
    Model model = load_model_or_embedded(model_file);
    for (const auto& w : model.warnings) std::cerr << "fralab-plant: warning: " << w << "\n";
    LabLcm io(url, ctl_url);
    lcm::LCM& lcm = io.data;
    lcm::LCM& ctl = io.control;
    LockstepPlant lockstep(model, opt, run_id);
    if (!replay.empty()) {  // resume: back to the exact state where the recorded run stands
      if (run_id.empty()) throw InputError("--replay needs --run-id");
      for (const Block& b : read_tape_blocks(replay, run_id, replay_blocks)) lockstep.replay(b);
      std::cerr << "fralab-plant: replayed " << replay_blocks << " tape blocks of " << replay
                << ": the plant makes them again bit for bit\n";
    }
    if (free_running && (!(speed > 0) || tick < 1 || jitter_ms < 0 || !replay.empty()))
      throw InputError(
          "--free-running needs --speed > 0, --tick >= 1, --jitter-ms >= 0 and no --replay");
    PlantNode plant(lcm, ctl, std::move(lockstep), 1024, free_running ? tick : 0);
    using Clock = std::chrono::steady_clock;
    auto last_ready = Clock::now() - std::chrono::seconds(1);
    // After the final block the plant stays to republish tape blocks a consumer lost, until the
    // acquisition's close (or `linger` s without it: the acquisition is gone).
    Clock::time_point done_at{};
    // Free-running: tick k is due at t0 + (k + 1) T + jitter_k, T = tick / (fs speed), from the
    // first command on.
    const double period_s = double(tick) / (opt.sample_rate_hz * speed);
    std::mt19937_64 rng(opt.seed ^ 0x6a09e667f3bcc909ULL);
    std::uniform_real_distribution<double> jitter(-jitter_ms * 1e-3, jitter_ms * 1e-3);
    Clock::time_point t0{}, due{};
    int64_t ticks = 0;
    while (keep_running || !(plant.done() && plant.closed())) {
      if (free_running && plant.started() && !plant.done()) {
        if (t0 == Clock::time_point{}) {
          t0 = Clock::now();
          due = t0 + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(period_s + jitter(rng)));
        }
        while (!plant.done() && Clock::now() >= due) {
          plant.tick();
          ++ticks;
          due = t0 + std::chrono::duration_cast<Clock::duration>(
                         std::chrono::duration<double>(double(ticks + 1) * period_s + jitter(rng)));
        }
        const double wait_ms =
            std::chrono::duration<double, std::milli>(due - Clock::now()).count();
        lcm.handleTimeout(std::max(1, std::min(100, int(wait_ms))));
        if (!plant.error().empty()) throw InputError(plant.error());
        continue;
      }
      if (!plant.started() &&
          std::chrono::duration<double>(Clock::now() - last_ready).count() > 0.1) {
        plant.announce_ready();  // the acquisition waits for this before the first command
        last_ready = Clock::now();
      }
      lcm.handleTimeout(100);  // the control URL is only published to
      if (!plant.error().empty()) throw InputError(plant.error());
      if (plant.done() && done_at == Clock::time_point{}) done_at = Clock::now();
      if (!keep_running && plant.done() &&
          std::chrono::duration<double>(Clock::now() - done_at).count() > linger)
        break;
    }
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
