// The tape recorder inside the flow control: every message on the data instance is
// written to a standard LCM log file (lcm-logplayer and lcm::LogFile read it) in arrival order,
// retransmitted duplicates included, flushed, and the last tape block and status event on disk
// without a gap are acknowledged under the recorder's name on the control instance (streams
// "tape" and "status"; again on every duplicate). The acquisition counts the recorder among its
// consumers, so a busy machine slows the run instead of losing tape blocks, and a lost datagram is
// retransmitted until the tape holds it. Readers put retransmitted blocks back in order
// (TapeFeeder).
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>

#include "fralab/core/in_order.h"

namespace fralab {

class RecorderNode {
 public:
  /// Creates (truncates) `path`; InputError naming it when it cannot. run_id "": the first tape
  /// block's run id is taken (blocks of another run are written but not acknowledged).
  /// Resume: `append` adds to an existing tape, and the first tape block and status event expected
  /// are `first_block` and `first_status` (what comes before is on the tape already).
  RecorderNode(lcm::LCM& data, lcm::LCM& control, const std::string& path, std::string run_id = "",
               std::string name = "recorder", bool append = false, int64_t first_block = 0,
               int64_t first_status = 0);
  ~RecorderNode();
  RecorderNode(const RecorderNode&) = delete;
  RecorderNode& operator=(const RecorderNode&) = delete;

  /// "Ready" (stream "ready", seq -1, under the recorder's name).
  void announce_ready();
  /// A tape block of the run has been written and acknowledged (no more "ready" needed).
  bool started() const { return blocks_ > 0; }
  int64_t events() const { return events_; }
  /// The first error met (a write that failed, a malformed tape block); "" while all is well.
  const std::string& error() const { return error_; }

 private:
  void on_any(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void ack(const std::string& stream, int64_t seq);
  lcm::LCM& data_;
  lcm::LCM& control_;
  std::string path_, run_id_, name_;
  std::unique_ptr<lcm::LogFile> log_;
  lcm::Subscription* sub_ = nullptr;
  int64_t events_ = 0, blocks_ = 0;
  InOrder<char> tape_, status_;  // what is on disk, by seq (contents not kept)
  std::string error_;
};

}  // namespace fralab
