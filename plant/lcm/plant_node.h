// The plant on LCM (fralab-plant's loop as a library, the transport passed in): command blocks
// from FRALAB_CMD go through LockstepPlant, tape blocks out on FRALAB_TAPE, one acknowledgement per
// block (consumer "plant") on the control instance. Tests run it in-process over memq://.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <string>

#include "fralab/plant/lockstep.h"

namespace fralab {

class PlantNode {
 public:
  /// Subscribes to FRALAB_CMD on `data`; `control` carries the acknowledgements (may be `data`).
  PlantNode(lcm::LCM& data, lcm::LCM& control, LockstepPlant plant);
  /// "Ready" (ack -1): the acquisition waits for it before the first command.
  void announce_ready();
  bool started() const { return started_; }
  bool done() const { return plant_.done(); }
  /// The first error met (a gap, a wrong message); "" while all is well. Processing stops there.
  const std::string& error() const { return error_; }

 private:
  void on_command(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void ack(int64_t seq);
  LockstepPlant plant_;
  lcm::LCM& data_;
  lcm::LCM& control_;
  bool started_ = false;
  std::string error_;
};

}  // namespace fralab
