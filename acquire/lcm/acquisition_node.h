// The acquisition on LCM (fralab-acquire's loop as a library, the transport passed in): waits for
// every consumer's "ready", publishes the status events (FRALAB_STATUS) and command blocks
// (FRALAB_CMD) of a campaign under flow control (acquire/flow_control.h): a command block goes out
// when every consumer holds the tape up to `window` blocks before it and every status event
// published before it; paced at `speed` x real time when > 0. What a consumer lacks is
// retransmitted (commands and status events by this node, tape blocks by the plant on request,
// FRALAB_FLOW "resend"); when every consumer holds everything, "close" (three times) ends the
// run. The plant and the analysers may share the instances (memq:// in tests: everything runs in
// the caller's thread, dispatched while this waits for acknowledgements).
//
// Free-running plant (AcquireOptions::free_running): no acknowledgement from the plant
// is awaited; command blocks go out while they are less than `lead` blocks ahead of the plant's
// clock (the tape it publishes, watched here). The campaign's "done" and final block are held
// back: idle blocks (every input at its operating point) keep the plant fed until it has played
// everything; each step whose settle or integration held a sample (the tape's "underrun" channel)
// is repeated at the end with its own settle (same step index; the analyser has marked the first
// point invalid), round after round, at most max_repeats; then "done" and the final block. The
// summary adds plant_clock, held_samples and repeated_steps.
#pragma once

#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fralab/acquire/acquisition.h"
#include "fralab/acquire/acquisition_summary.h"
#include "fralab/acquire/flow_control.h"
#include "fralab/core/json_util.h"
#include "fralab/core/measurement_chain.h"

namespace fralab {

struct AcquisitionLoopOptions {
  std::string run_id = "run";
  std::vector<std::string> consumers = {"plant"};  // who must acknowledge ("plant" is added)
  AcquireOptions acquire;  // block (sized: >= 1), window, speed and sample rate are its
  double ready_timeout_s = 30;
  FlowOptions flow;  // retransmission waits and the stall timeout
  /// Polled while running: true stops the run (a signal): an "abort" status and a block holding
  /// every actuator at its operating point go out, then run() throws InputError saying so.
  std::function<bool()> stop_requested;
  /// Resume: start at this command block, and publish the status events from this index on (what
  /// comes before is on the tape; the plant stands at the block's first sample).
  int64_t first_block = 0;
  int64_t first_status = 0;
  /// The adaptive stepped sine (acquire/adaptive_sine.h): decides while running; the campaign
  /// given to the node is its campaign, which grows as it decides. The node watches the tape for
  /// it (asking the plant again for what is lost on the way) and publishes no command block
  /// beyond a pending decision. The summary adds "adaptive": per step its input, frequency,
  /// cycles, worst sigma / |G| and state, with the counts met / limit.
  AutoIntegrator* auto_integrator = nullptr;
  /// The measurement chain (core/measurement_chain.h), carried by the start event so that the
  /// tape says how it was measured.
  std::optional<MeasurementChain> measurement_chain;
};

class AcquisitionNode {
 public:
  /// Subscribes to the acknowledgements on `control` (may be `data`) from construction on.
  AcquisitionNode(lcm::LCM& data, lcm::LCM& control, const Campaign& campaign,
                  AcquisitionLoopOptions o);
  ~AcquisitionNode();
  AcquisitionNode(const AcquisitionNode&) = delete;
  AcquisitionNode& operator=(const AcquisitionNode&) = delete;

  /// Runs the campaign to its end; returns its summary (acquire/acquisition_summary.h).
  /// InputError naming the consumer that never said ready or a stream that stalled
  /// (flow_control.h), or a decoding error on the control channel.
  AcquisitionSummary run();

 private:
  struct Acks;
  struct TapeWatch;
  class Run;
  lcm::LCM& data_;
  lcm::LCM& control_;
  const Campaign& campaign_;
  AcquisitionLoopOptions o_;
  std::unique_ptr<Acks> acks_;
  lcm::Subscription* sub_ = nullptr;
  std::unique_ptr<TapeWatch> tape_;  // free-running plant, or an adaptive stepped sine
  lcm::Subscription* tape_sub_ = nullptr;
};

}  // namespace fralab
