// The plant on LCM (fralab-plant's loop as a library, the transport passed in): command blocks
// from FRALAB_CMD go through LockstepPlant in sequence order (a duplicate is dropped, a block that
// arrives early is held until the gap before it is retransmitted), tape blocks go out on
// FRALAB_TAPE, and the last command block processed is acknowledged on the control instance
// (consumer "plant", stream "command"; again on every duplicate). The last `keep_blocks` tape
// blocks are kept and republished when the acquisition asks (FRALAB_FLOW "resend", stream
// "tape": a consumer lost them); "close" ends the run. Tests run it in-process over memq://.
//
// Free-running (tick_samples > 0): the plant is not in lockstep; command blocks go into a
// CommandBuffer (plant/command_buffer.h) by the samples they stamp, the contiguous part is still
// acknowledged (so lost commands are retransmitted), and the caller's clock calls tick(): the next
// tick_samples samples are played from the buffer, held where it ran dry (channel "underrun"),
// and published as tape block seq = tick index.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <map>
#include <optional>
#include <string>

#include "fralab/core/in_order.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/lab_lcm.h"
#include "fralab/plant/command_buffer.h"
#include "fralab/plant/lockstep.h"

namespace fralab {

class PlantNode {
 public:
  /// Subscribes to FRALAB_CMD and FRALAB_FLOW on `data`; acknowledges on `control` (may be
  /// `data`). The first
  /// command expected is the plant's next_seq() (0, or where a replayed plant stands: resume).
  PlantNode(lcm::LCM& data, lcm::LCM& control, LockstepPlant plant, size_t keep_blocks = 1024,
            int tick_samples = 0);
  /// Free-running: plays and publishes the next tick; false before the first command (the clock
  /// has not started) and after the final tick.
  bool tick();
  /// Free-running: samples held because the buffer ran dry, and command blocks that came too late.
  int64_t underrun_samples() const { return buffer_ ? buffer_->underrun_samples() : 0; }
  int64_t late_blocks() const { return buffer_ ? buffer_->late_blocks() : 0; }
  /// "Ready" (stream "ready", seq -1): the acquisition waits for it before the first command.
  void announce_ready();
  bool started() const { return started_; }
  bool done() const { return plant_.done(); }
  /// The acquisition said the run is over.
  bool closed() const { return closed_; }
  /// Tape blocks republished on request so far.
  int64_t resent() const { return resent_; }
  /// Requests for tape blocks no longer kept (each named), "" when none.
  const std::string& warnings() const { return warnings_; }
  /// The first error met (a wrong message, a block that does not fit); "" while all is well.
  /// Processing stops there.
  const std::string& error() const { return error_; }

 private:
  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_flow(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void ack(const std::string& stream, int64_t seq);
  void publish_tape(const Block& b);
  LockstepPlant plant_;
  std::optional<CommandBuffer> buffer_;
  lcm::LCM& data_;
  lcm::LCM& control_;
  size_t keep_;
  InOrder<Block> commands_;
  std::map<int64_t, tape_block_t> kept_;
  bool started_ = false, closed_ = false;
  int64_t resent_ = 0;
  std::string warnings_, error_;
};

/// How fralab-plant serves its node until the run ends (serve()).
struct ServeOptions {
  bool keep_running = false;  // do not return after the final block
  double linger_s = 20;       // after the final block, wait this long for the acquisition's close
  // Free-running: tick k is due at t0 + (k + 1) T + jitter_k, T = tick / (sample_rate_hz speed),
  // jitter_k uniform in +-jitter_ms (seeded by seed), t0 the first command's arrival.
  bool free_running = false;
  int tick = 100;  // samples per tape block
  double speed = 1.0, jitter_ms = 0.0, sample_rate_hz = 1000;
  uint64_t seed = 0;
  /// InputError unless speed > 0, tick >= 1 and jitter_ms >= 0 when free-running.
  void validate() const;
};

/// fralab-plant's loop: handles `lcm` (the node's data instance) until the node is done and the
/// acquisition has closed the run (or linger_s has passed without it), announcing readiness every
/// 0.1 s until the first command and, free-running, calling tick() on the wall clock. InputError
/// with the node's error when it has one.
void serve(PlantNode& plant, lcm::LCM& lcm, const ServeOptions& o);

}  // namespace fralab
