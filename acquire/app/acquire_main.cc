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
#include <csignal>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <thread>

#include "acquisition_node.h"
#include "fralab/acquire/acquire_flags.h"
#include "fralab/core/measurement_chain.h"
#include "fralab/core/text.h"
#include "fralab/lcm/lab_lcm.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/simulator.h"

using namespace fralab;

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fralab-acquire: excitation campaign over LCM"};
  std::string engine = "j85_95", url, ctl_url, run_id = "run", consumers_csv = "plant", summary;
  AcquireOptions o;
  double ready_timeout = 30, stall_timeout = 60;
  int64_t lo_first_block = 0, lo_first_status = 0;
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
  app.add_option("--stall-timeout", stall_timeout,
                 "seconds a stream may stand still, retransmitted, before the run fails")
      ->capture_default_str();
  FlowOptions flow;
  app.add_option("--retransmit-after", flow.retransmit_after_s,
                 "seconds before what a consumer lacks is first retransmitted (then doubling)")
      ->capture_default_str();
  app.add_option("--first-block", lo_first_block, "resume: start at this command block")
      ->capture_default_str();
  app.add_option("--first-status", lo_first_status,
                 "resume: publish status events from this index on")
      ->capture_default_str();
  app.add_option("--summary", summary, "write a JSON summary here");
  std::string chain;
  auto* chain_opt = app.add_option(
      "--chain", chain,
      "the measurement chain (JSON, core/measurement_chain.h), put on the tape in the start event");
  bool emulator = false;
  app.add_flag("--emulator-chain", emulator,
               "put on the tape the chain of fralab's plant emulator running --engine at "
               "--sample-rate (plant/simulator.h: emulator_chain)")
      ->excludes(chain_opt);
  CLI11_PARSE(app, argc, argv);
  try {
    Model model = load_model_or_embedded(engine);
    o.validate();
    o.block = block_samples(model, o);
    const std::unique_ptr<Campaign> campaign = make_campaign(model, o, run_id);
    const Campaign& camp = *campaign;

    LabLcm io(url, ctl_url);
    lcm::LCM& lcm = io.data;
    lcm::LCM& ctl = io.control;
    AcquisitionLoopOptions lo;
    lo.run_id = run_id;
    lo.consumers = split_list(consumers_csv);
    lo.acquire = o;
    lo.ready_timeout_s = ready_timeout;
    lo.flow = flow;
    lo.first_block = lo_first_block;
    lo.first_status = lo_first_status;
    if (emulator) lo.measurement_chain = emulator_chain(model, o.sample_rate_hz);
    if (!chain.empty()) {
      lo.measurement_chain = chain_from_json(json_parse_text(chain, "--chain"), {"--chain", ""});
    }
    lo.flow.stall_timeout_s = stall_timeout;
    lo.stop_requested = [] { return g_stop != 0; };
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    // The adaptive stepped sine decides while running, on the tape of the model's outputs.
    const auto integrator = make_auto_integrator(*campaign, model, o, lo_first_block * o.block);
    lo.auto_integrator = integrator.get();
    AcquisitionNode node(lcm, ctl, camp, lo);
    const Json sj = acquisition_summary_to_json(node.run());
    std::cerr << "fralab-acquire: " << sj.dump() << "\n";
    if (!summary.empty()) json_save_file(summary, sj);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "fralab-acquire: " << e.what() << "\n";
    return 1;
  }
}
