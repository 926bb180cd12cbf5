// The plant emulator's protocol logic, free of LCM: a command block in, the tape block out, in
// lockstep (docs/formats.md §3, docs/plant-protocol.md). fralab-plant wires it to FRALAB_CMD /
// FRALAB_TAPE; tests call it directly. The tape block carries, per sample, the commands echoed
// (u_<input>, in model order), the simulator's channels (every actuator position, then every
// output) and every non-command channel of the command block (the reference: ref_phase,
// ref_freq_hz), in that order.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fralab/core/block.h"
#include "fralab/plant/simulator.h"

namespace fralab {

class LockstepPlant {
 public:
  /// run_id "": the first command block's run id is taken.
  LockstepPlant(const Model& model, const SimulatorOptions& opt, std::string run_id = "");

  /// Whether a block of this run id is ours (another run on the same URL is ignored).
  bool accepts(const std::string& run_id);
  /// Advances the model by the block's samples and returns the tape block. InputError when the
  /// block is not the next one (a gap names the expected and received seq), does not start at
  /// the plant's sample, or lacks a u_<input> channel.
  Block advance(const Block& cmd);

  /// An aborted run's last block (seq -1, final): the actuators are commanded to the block's values
  /// (their operating point) for its length, from wherever the plant stands, outside the sequence.
  /// Returns the tape block (seq -1). The plant is done afterwards.
  Block hold(const Block& abort);

  /// Resume: advances the model through a tape block recorded earlier (its u_<input> commands and
  /// reference channels are the command) and checks that the plant made exactly that block again,
  /// bit for bit (same model, seed and history). InputError naming the block and the first
  /// differing channel and sample otherwise.
  void replay(const Block& recorded);

  int64_t next_seq() const { return next_seq_; }
  bool done() const { return done_; }
  const std::string& run_id() const { return run_id_; }

 private:
  Simulator sim_;
  std::vector<std::string> input_names_;
  std::string run_id_;
  int64_t next_seq_ = 0;
  bool done_ = false;
};

}  // namespace fralab
