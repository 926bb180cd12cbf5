// The live analyser on LCM (fralab-analyze's loop as a library, the transport passed in): tape
// blocks and status events from `data` feed the pair analysers in sequence order (TapeFeeder:
// duplicates dropped, gaps held until retransmitted), each pair's new points are published on
// FRALAB_FRD as they complete (the finished curve whole), and the last tape block and status event
// held without a gap are acknowledged under the consumer's name on the control instance (streams
// "tape" and "status"; again on every duplicate, so a lost acknowledgement is mended). From the
// data instance it also hears the acquisition's "close" (FRALAB_FLOW) and the identifier's
// acknowledgements of complete curves (FRALAB_FRD_ACK, consumer "identify", streams "ready" and
// "frd:<pair>"); it never reads the control instance (every consumer's acknowledgements). Tests run
// it in-process over memq://.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <set>
#include <string>
#include <vector>

#include "fralab/lcm/lab_lcm.h"
#include "tape_analysis.h"

namespace fralab {

class AnalyzerNode {
 public:
  AnalyzerNode(lcm::LCM& data, lcm::LCM& control, const std::vector<std::string>& pairs,
               const AnalyzerOptions& opt, std::string name, std::string run_id = "");
  /// "Ready" (stream "ready", seq -1, under the node's name).
  void announce_ready();
  bool started() const { return started_; }
  /// The run's final block has arrived and every window is resolved.
  bool done() const { return feeder_.all_done(); }
  /// The acquisition said the run is over (every consumer holds everything).
  bool closed() const { return closed_; }
  /// Publishes every curve as complete and returns them.
  std::vector<Frd> finish();
  /// An identifier announced itself on the control instance (it will acknowledge curves).
  bool identifier_heard() const { return identifier_heard_; }
  /// The identifier acknowledged every pair's complete curve.
  bool curves_taken() const;
  /// Publishes the complete curves the identifier has not acknowledged yet (after finish()).
  void republish_untaken();
  const std::string& error() const { return error_; }

 private:
  void on_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_control(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void ack(const std::string& stream, int64_t seq);
  TapeFeeder feeder_;
  lcm::LCM& data_;
  lcm::LCM& control_;
  std::string name_;
  bool started_ = false, closed_ = false, identifier_heard_ = false;
  int64_t frd_seq_ = 0;
  std::vector<Frd> final_;
  std::set<std::string> taken_;
  std::string error_;
};

}  // namespace fralab
