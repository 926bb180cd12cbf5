// fralab-plant: the engine emulator process. Subscribes to actuator command blocks (FRALAB_CMD),
// advances the model exactly as many samples as commanded, and publishes tape blocks (FRALAB_TAPE)
// with the commands echoed (u_<input>), every actuator position, every output and the reference
// channels. Lockstep: it never runs ahead and never drops a block.
#include <CLI/CLI.hpp>
#include <chrono>
#include <iostream>

#include "fralab/lcm_io.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/simulator.h"

using namespace fralab;

namespace {

struct Plant {
  Simulator sim;
  lcm::LCM* lcm;
  lcm::LCM* ctl;  // control URL: acknowledgements
  std::vector<std::string> input_names;
  int64_t next_seq = 0;
  std::string run_id;  // "" until given or fixed by the first command
  bool done = false;
  bool started = false;
  std::string error;

  void ack(int64_t seq) {
    ack_t a;
    a.run_id = run_id;
    a.consumer = "plant";
    a.seq = seq;
    ctl->publish(kAckChannel, &a);
  }

  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (done || !error.empty()) return;
    try {
      Block cmd = from_msg(decode_checked<command_block_t>(rbuf, channel));
      if (run_id.empty()) run_id = cmd.run_id;
      if (cmd.run_id != run_id) return;  // another run on the same URL: not ours
      if (cmd.seq != next_seq) {
        throw InputError("command block gap: expected seq " + std::to_string(next_seq) + ", got " +
                         std::to_string(cmd.seq) + " (a block was lost or reordered)");
      }
      if (cmd.start_sample != sim.samples_done()) {
        throw InputError("command block seq " + std::to_string(cmd.seq) + " starts at sample " +
                         std::to_string(cmd.start_sample) + ", plant is at " +
                         std::to_string(sim.samples_done()));
      }
      std::vector<int> idx;
      for (const auto& n : input_names) {
        int c = cmd.channel_index("u_" + n);
        if (c < 0) throw InputError("command block has no channel u_" + n);
        idx.push_back(c);
      }
      Block tape;
      tape.run_id = cmd.run_id;
      tape.seq = cmd.seq;
      tape.start_sample = cmd.start_sample;
      tape.sample_rate_hz = cmd.sample_rate_hz;
      tape.final_block = cmd.final_block;
      tape.n_samples = cmd.n_samples;
      std::vector<int> echo;
      for (const auto& n : input_names) tape.channels.push_back("u_" + n);
      for (const auto& n : sim.channel_names()) tape.channels.push_back(n);
      for (size_t c = 0; c < cmd.channels.size(); ++c) {
        if (cmd.channels[c].rfind("u_", 0) != 0) {
          echo.push_back(static_cast<int>(c));
          tape.channels.push_back(cmd.channels[c]);
        }
      }
      tape.samples.assign(tape.channels.size() * size_t(cmd.n_samples), 0.0);
      std::vector<double> u(input_names.size()), y(sim.n_channels());
      const int ni = static_cast<int>(input_names.size());
      for (int k = 0; k < cmd.n_samples; ++k) {
        for (int i = 0; i < ni; ++i) u[i] = cmd.at(idx[i], k);
        sim.step(u.data(), y.data());
        for (int i = 0; i < ni; ++i) tape.at(i, k) = u[i];
        for (size_t c = 0; c < y.size(); ++c) tape.at(ni + int(c), k) = y[c];
        for (size_t e = 0; e < echo.size(); ++e)
          tape.at(ni + int(y.size() + e), k) = cmd.at(echo[e], k);
      }
      started = true;
      tape_block_t msg = to_tape_msg(tape);
      lcm->publish(kTapeChannel, &msg);
      ack(cmd.seq);
      ++next_seq;
      if (cmd.final_block) done = true;
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
};

}  // namespace

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
  app.add_flag("--keep-running", keep_running, "do not exit after the final block");
  std::string run_id, ctl_url;
  app.add_option("--control-url", ctl_url,
                 "LCM URL for acknowledgements (default: --lcm-url with port + 1)");
  app.add_option("--run-id", run_id, "only this run (default: the first command's)");
  CLI11_PARSE(app, argc, argv);
  opt.noise = !no_noise;
  try {
    Model model = load_model_or_embedded(model_file);
    for (const auto& w : model.warnings) std::cerr << "fralab-plant: warning: " << w << "\n";
    lcm::LCM lcm(resolve_lcm_url(url));
    if (!lcm.good()) throw InputError("cannot open LCM at " + resolve_lcm_url(url));
    lcm::LCM ctl(ctl_url.empty() ? control_url_for(resolve_lcm_url(url))
                                 : resolve_lcm_url(ctl_url));
    if (!ctl.good()) throw InputError("cannot open the control LCM URL");
    Plant plant{Simulator(model, opt), &lcm, &ctl, {}, 0, run_id, false, false, ""};
    for (const auto& in : model.inputs) plant.input_names.push_back(in.name);
    lcm::Subscription* sub = lcm.subscribe(kCmdChannel, &Plant::on_command, &plant);
    sub->setQueueCapacity(100000);
    auto last_ready = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    while (keep_running || !plant.done) {
      if (!plant.started &&
          std::chrono::steady_clock::now() - last_ready > std::chrono::milliseconds(100)) {
        plant.ack(-1);  // ready: the acquisition waits for this before the first command
        last_ready = std::chrono::steady_clock::now();
      }
      lcm.handleTimeout(100);
      if (!plant.error.empty()) throw InputError(plant.error);
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-plant: " << e.what() << "\n";
    return 1;
  }
}
