// The live identifier on LCM (fralab-identify's loop as a library, the transport passed in): it
// collects the analysers' finished curves of a run (FRALAB_FRD, complete true; the growing curves'
// messages are passed over), acknowledges each copy on FRALAB_FRD_ACK (consumer "identify", stream
// "frd:<pair>", seq 0, on the data instance, so a lost acknowledgement is mended by the next copy),
// announces itself there (stream "ready") so the analysers hand their curves over, then fits them
// (identify/fit_io.h), writes the files and publishes each fit on FRALAB_TF. Tests run it
// in-process over memq://.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/identify/fit_io.h"

namespace fralab {

class IdentifierNode {
 public:
  /// Listens on `data` for run `run_id`'s curves ("" takes every run's).
  IdentifierNode(lcm::LCM& data, std::string run_id);
  ~IdentifierNode();
  IdentifierNode(const IdentifierNode&) = delete;
  IdentifierNode& operator=(const IdentifierNode&) = delete;
  /// "Ready" (stream "ready", seq -1): the analysers republish their complete curves until taken.
  void announce_ready();
  /// The complete curves taken so far, by pair (the first copy of each).
  const std::map<std::string, Frd>& curves() const { return curves_; }
  /// Fits every curve taken (in pair order), writes DIR/tf/ and the transfer matrix into `out`
  /// (fit_and_write) and publishes each fit on FRALAB_TF (fit error e_n, status word). Returns the
  /// fits in pair order.
  std::vector<FitResult> fit_and_publish(const FitOptions& o, const std::string& out,
                                         const std::string& title);
  /// The first message that did not decode (the node stops taking curves), else "".
  const std::string& error() const { return error_; }

 private:
  void on_frd(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  lcm::LCM& data_;
  std::string run_id_;
  lcm::Subscription* sub_ = nullptr;
  std::map<std::string, Frd> curves_;
  std::string error_;
};

}  // namespace fralab
