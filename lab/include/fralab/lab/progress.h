// The face of a long run: one progress line, redrawn on the terminal as the excitation's status
// events arrive (`fralab measure`, `fralab run`). LCM-free: the launcher feeds it the status events
// it hears and the tape blocks re-sent, and prints line() when it changed.
//
//   Wf  step 12/33  2.51 Hz  engine 412/1151 s (739 s left)  wall 1:02 left  re-sent 3
//
// input: the input excited (the first with a non-zero amplitude; "all" for a multisine exciting
// several); step i of N from the event (1-based); engine time done = the event's sample over the
// sample rate, of the run's total (from the start event); wall time left = wall time so far times
// engine time left over engine time done (shown once 1 % is done); re-sent: tape blocks
// retransmitted on request so far.
#pragma once

#include <cstdint>
#include <string>

#include "fralab/core/block.h"

namespace fralab {

class ProgressLine {
 public:
  /// A status event of the run (start: the total; settle/integrate/done: where the run stands).
  void on_status(const StatusEvent& e);
  /// `n` tape blocks were asked for again.
  void on_resent(int64_t n) { resent_ += n; }
  /// The line at wall time `wall_s` since the run started ("" before the first status).
  std::string line(double wall_s) const;

 private:
  double total_s_ = 0, done_s_ = 0, freq_hz_ = 0;
  int step_ = 0, n_steps_ = 0;
  std::string input_;
  int64_t resent_ = 0;
  bool seen_ = false;
};

}  // namespace fralab
