// fralab-acquire: the oscillator. Holds every actuator at its operating point, adds the test signal
// on the selected inputs (stepped sine, one input after the other), publishes command blocks
// (FRALAB_CMD) with the reference channels and excitation status (FRALAB_STATUS), and drives the
// plant in lockstep. Flow control: it waits until the plant and every named consumer have
// acknowledged blocks up to seq - window before sending more, so nothing is ever dropped;
// --speed 1 additionally paces blocks at real time (a real test cell), --speed 0 goes as fast as
// the consumers keep up. The results depend only on the samples, never on the speed.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <thread>

#include "fralab/acquire/acquire_flags.h"
#include "fralab/core/text.h"
#include "fralab/lcm_io.h"
#include "fralab/plant/embedded_models.h"

using namespace fralab;
using Clock = std::chrono::steady_clock;

namespace {

// Acknowledgements on the control URL, for this run only.
struct AckListener {
  std::string run_id;
  AckTracker acks;
  std::string error;
  void on_ack(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    try {
      ack_t a = decode_checked<ack_t>(rbuf, ch);
      if (!a.run_id.empty() && a.run_id != run_id) return;
      acks.on_ack(a.consumer, a.seq);
    } catch (const std::exception& e) {
      error = e.what();
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-acquire: excitation campaign over LCM"};
  std::string engine = "j85_95", url, ctl_url, run_id = "run", consumers_csv = "plant", summary;
  AcquireOptions o;
  double ready_timeout = 30, stall_timeout = 60;
  app.add_option("--engine", engine, "engine model (file or embedded name)")->capture_default_str();
  add_acquire_flags(&app, o);
  app.add_option("--consumers", consumers_csv,
                 "who must acknowledge (plant is implicit via its tape)")
      ->capture_default_str();
  app.add_option("--run-id", run_id)->capture_default_str();
  app.add_option("--lcm-url", url);
  app.add_option("--control-url", ctl_url,
                 "LCM URL for acknowledgements (default: --lcm-url with port + 1)");
  app.add_option("--ready-timeout", ready_timeout, "seconds to wait for consumers to be ready")
      ->capture_default_str();
  app.add_option("--summary", summary, "write a JSON summary here");
  CLI11_PARSE(app, argc, argv);
  try {
    Model model = load_model_or_embedded(engine);
    const std::unique_ptr<Campaign> campaign = make_campaign(model, o, run_id);
    const Campaign& camp = *campaign;

    lcm::LCM lcm(resolve_lcm_url(url));
    if (!lcm.good()) throw InputError("cannot open LCM at " + resolve_lcm_url(url));
    AckListener acq;
    acq.run_id = run_id;
    lcm::LCM ctl(ctl_url.empty() ? control_url_for(resolve_lcm_url(url))
                                 : resolve_lcm_url(ctl_url));
    if (!ctl.good()) throw InputError("cannot open the control LCM URL");
    ctl.subscribe(kAckChannel, &AckListener::on_ack, &acq)->setQueueCapacity(100000);
    std::vector<std::string> consumers = split_list(consumers_csv);
    if (std::find(consumers.begin(), consumers.end(), "plant") == consumers.end())
      consumers.push_back("plant");

    // Waits until every consumer has acknowledged `target` (-1: ready); past `timeout` seconds the
    // error names the slowest consumer (`lag`) through `why`.
    std::string lag;
    auto wait_acks = [&](int64_t target, double timeout, int poll_ms,
                         const std::function<std::string()>& why) {
      const auto t = Clock::now();
      while (acq.acks.min_ack(consumers, &lag) < target) {
        handle_either(lcm, ctl, poll_ms);
        if (!acq.error.empty()) throw InputError(acq.error);
        if (std::chrono::duration<double>(Clock::now() - t).count() > timeout)
          throw InputError(why());
      }
    };
    wait_acks(-1, ready_timeout, 50, [&] {
      return "consumer \"" + lag + "\" never said ready within " + std::to_string(ready_timeout) +
             " s (is it running on the same LCM URL?)";
    });
    auto publish_status = [&](const StatusEvent& e) {
      excitation_status_t m = to_status_msg(e);
      lcm.publish(kStatusChannel, &m);
    };
    StatusEvent start = camp.events().front();
    start.state = RunState::kStart;
    start.seq = -1;
    start.sample = 0;
    start.n_samples = camp.total_samples();
    publish_status(start);

    const auto t0 = Clock::now();
    const int64_t total = camp.total_samples();
    const int64_t nblocks = command_block_count(camp, o.block);
    size_t ev = 0;
    for (int64_t b = 0; b < nblocks; ++b) {
      wait_acks(b - o.window, stall_timeout, 20, [&] {
        return "consumer \"" + lag + "\" stopped acknowledging at block " +
               std::to_string(acq.acks.min_ack(consumers, nullptr)) + " (sent up to " +
               std::to_string(b - 1) + ")";
      });
      const Block blk = command_block(camp, b, o.block, o.sample_rate_hz, run_id);
      if (o.speed > 0) {
        auto due = t0 + std::chrono::duration<double>(double(blk.start_sample) / o.sample_rate_hz /
                                                      o.speed);
        while (Clock::now() < due)
          handle_either(
              lcm, ctl,
              1 + int(std::chrono::duration<double, std::milli>(due - Clock::now()).count()));
      }
      while (ev < camp.events().size() &&
             (camp.events()[ev].sample < blk.start_sample + blk.n_samples || blk.final_block))
        publish_status(camp.events()[ev++]);
      command_block_t m = to_command_msg(blk);
      lcm.publish(kCmdChannel, &m);
    }
    // Wait for everyone to take the last block.
    wait_acks(nblocks - 1, stall_timeout, 20, [&] {
      return "consumer \"" + lag + "\" did not acknowledge the final block " +
             std::to_string(nblocks - 1);
    });
    const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
    const double engine_s = double(total) / o.sample_rate_hz;
    Json sj{{"run_id", run_id},
            {"engine_time_s", engine_s},
            {"wall_time_s", wall},
            {"speedup", engine_s / std::max(wall, 1e-9)},
            {"blocks", nblocks},
            {"samples", total},
            {"excitation", to_string(o.excitation)}};
    std::cerr << "fralab-acquire: " << sj.dump() << "\n";
    if (!summary.empty()) json_save_file(summary, sj);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-acquire: " << e.what() << "\n";
    return 1;
  }
}
