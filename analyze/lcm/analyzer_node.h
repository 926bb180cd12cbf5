// The live analyser on LCM (fralab-analyze's loop as a library, the transport passed in): tape
// blocks and status events from `data` feed the pair analysers, each pair's curve is republished
// on FRALAB_FRD as it grows, and every tape block is acknowledged under the consumer's name on the
// control instance (flow control). Tests run it in-process over memq://.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "tape_analysis.h"

namespace fralab {

class AnalyzerNode {
 public:
  AnalyzerNode(lcm::LCM& data, lcm::LCM& control, const std::vector<std::string>& pairs,
               const AnalyzerOptions& opt, std::string name, std::string run_id = "");
  /// "Ready" (ack -1 under the node's name).
  void announce_ready();
  bool started() const { return started_; }
  /// The run's final block has arrived and every window is resolved.
  bool done() const { return feeder_.all_done(); }
  /// Publishes every curve as complete and returns them.
  std::vector<Frd> finish();
  const std::string& error() const { return error_; }

 private:
  void on_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void ack(int64_t seq);
  TapeFeeder feeder_;
  lcm::LCM& data_;
  lcm::LCM& control_;
  std::string name_;
  bool started_ = false;
  int64_t frd_seq_ = 0;
  std::string error_;
};

}  // namespace fralab
