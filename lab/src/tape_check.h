// Reading a run's tape back before its recorder is stopped: the proof that the run's data are on
// disk whole (every tape block and status event, without gaps, and the final "done" status).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "fralab/lcm/tape_file.h"

namespace fralab {

// Reads the tape back as the recorder writes it (each call reads only what was added since the
// last): every tape block and status event of the run, without gaps (retransmitted copies and
// their order do not matter), and the final "done" status. The command blocks are on the tape
// too, but not required: every tape block echoes its commands.
class TapeCheck {
 public:
  TapeCheck(std::string path, std::string run_id)
      : path_(std::move(path)), run_id_(std::move(run_id)) {}

  // The number of tape blocks; -1 while incomplete (recorder still writing), -2 when a block was
  // lost.
  int64_t update(std::string* problem);

 private:
  void take(const TapeEvent& ev);
  void decode(const TapeEvent& ev);

  std::string path_, run_id_;
  int64_t offset_ = 0;
  std::map<std::string, std::vector<int64_t>> seqs_;
  bool done_ = false, final_tape_ = false;
  std::string bad_;
};

// Reads the tape of run `run_id` back until the recorder has written all of it (up to 200 times,
// 50 ms apart, while it is still incomplete): the number of tape blocks, or < 0 with `problem`
// saying what is missing (a lost block or status event, or a tape still incomplete).
int64_t read_back_tape(const std::string& tape, const std::string& run_id, std::string* problem);

}  // namespace fralab
