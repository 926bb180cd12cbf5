// The free-running plant's command buffer: what a DAQ's output FIFO does, free of LCM and of the
// clock. Command blocks (docs/formats.md §3: u_<input>, ref_phase, ref_freq_hz) are buffered by
// the samples they stamp (start_sample ..), in any order; the plant's own clock takes the next
// `tick` samples at a time. A sample with a buffered command plays it; a sample without one
// (the buffer ran dry: an underrun) holds the last command played (a DAC's hold), the reference
// frequency 0, and is marked 1 in the extra channel "underrun" (0 elsewhere), which the plant
// echoes onto the tape like the reference channels: the analyser refuses a window with an
// underrun and the acquisition repeats its step (never silently wrong). A block whose samples are
// all in the past when it arrives is too late: counted and dropped. The run ends with the tick
// that plays the last sample of the final command block (or the first tick after it, when that
// block came too late).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/block.h"

namespace fralab {

class CommandBuffer {
 public:
  /// `tick_samples` >= 1: samples per tick (the tape block size of the free-running plant).
  explicit CommandBuffer(int tick_samples);
  /// Buffers a command block; false when it came too late (every sample already played). The
  /// first block fixes the channels; InputError when a later one's differ.
  bool add(const Block& cmd);
  /// The command for the next tick, as a LockstepPlant command block: samples [clock, clock +
  /// tick) (fewer on the final tick), seq = the tick's index, the channels of the commands plus
  /// "underrun". nullopt before the first command has arrived (the clock has not started) and
  /// after the final tick. The clock starts at the earliest sample buffered before the first tick.
  std::optional<Block> next();
  int64_t clock() const { return clock_; }
  int64_t underrun_samples() const { return underrun_; }
  int64_t late_blocks() const { return late_; }
  bool done() const { return done_; }

 private:
  int tick_;
  std::map<int64_t, Block> blocks_;  // by start_sample
  std::vector<std::string> channels_;
  std::vector<double> last_;  // the last command played, per channel
  std::string run_id_;
  double fs_ = 0;
  int64_t clock_ = 0, ticks_ = 0, underrun_ = 0, late_ = 0;
  int64_t final_end_ = -1;  // the end of the final block, once known
  bool started_ = false, done_ = false;
};

}  // namespace fralab
