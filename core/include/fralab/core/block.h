// The tape's records as plain structs, free of LCM: a block of sample-clocked multi-channel samples
// and an excitation status (docs/formats.md §3). The LCM adapters
// (lcmtypes/include/fralab/lcm/codec.h) convert them to and from fralab.tape_block_t /
// command_block_t / excitation_status_t; the libraries (acquire, analyze) only ever see these.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/error.h"
#include "fralab/core/measurement_chain.h"
#include "fralab/core/text.h"

namespace fralab {

/// The test signal. On the tape (StatusEvent, docs/formats.md §3) its words are "stepped_sine",
/// "sweep" and "multisine" (status_word); on the command line "stepped", "sweep", "multisine".
enum class Excitation { kStepped, kSweep, kMultisine };
/// The test signal's state: "start", "settle", "integrate", "done", "abort" on the tape.
enum class RunState { kStart, kSettle, kIntegrate, kDone, kAbort };

const char* status_word(Excitation e);
const char* to_string(RunState s);
/// InputError naming the word otherwise.
Excitation excitation_from_status_word(const std::string& word);
RunState run_state_from_string(const std::string& word);

/// The tape channel a free-running plant adds (plant/command_buffer.h): 1 at a sample it held
/// because its command buffer ran dry (not the excitation), 0 elsewhere.
inline constexpr const char* kUnderrunChannel = "underrun";

struct Block;

/// The samples a free-running plant held (its tape channel "underrun" nonzero), kept as runs
/// [first, last] whatever order the blocks arrive in: what the analyser and the acquisition ask
/// of a step.
class HeldSamples {
 public:
  /// Records the block's held samples (none when it has no "underrun" channel); returns how many.
  int64_t add(const Block& b);
  /// The first and last held sample within [a, b); nullopt when none.
  std::optional<std::pair<int64_t, int64_t>> within(int64_t a, int64_t b) const;
  int64_t count() const { return count_; }

 private:
  void add_sample(int64_t n);
  std::map<int64_t, int64_t> runs_;  // first -> last
  int64_t count_ = 0;
};

/// samples are channel-major: samples[c * n_samples + k] is channel c at sample start_sample + k.
struct Block {
  std::string run_id;
  int64_t seq = 0;
  int64_t start_sample = 0;
  double sample_rate_hz = 0.0;
  std::vector<std::string> channels;
  int n_samples = 0;
  std::vector<double> samples;
  bool final_block = false;

  double at(int channel, int k) const { return samples[size_t(channel) * n_samples + k]; }
  double& at(int channel, int k) { return samples[size_t(channel) * n_samples + k]; }
  int channel_index(const std::string& name) const { return index_of(channels, name); }
};

/// One state change of the test signal. From `sample` on (stepped sine), the reference phase is
/// ref_phase_rad + 2 pi frequency_hz (n - sample) / sample_rate_hz, and the excited inputs carry
/// dc + amplitude * sin(reference phase).
struct StatusEvent {
  std::string run_id;
  int64_t seq = 0;
  int64_t sample = 0;
  double sample_rate_hz = 0.0;
  Excitation excitation = Excitation::kStepped;
  RunState state = RunState::kStart;
  int step = 0;
  int n_steps = 0;
  double frequency_hz = 0.0;
  double ref_phase_rad = 0.0;
  int n_cycles = 0;
  int64_t n_samples = 0;
  std::vector<std::string> inputs;
  std::vector<double> amplitudes;  // per input (all plant inputs), peak; 0 = not excited
  std::string message;
  // Multisine ("multisine"): one period of period_samples; lines[j] is a harmonic of
  // sample_rate_hz / period_samples excited by inputs[line_input[j]].
  int period_samples = 0;
  std::vector<int> lines, line_input;
  // The start event: how the run was measured (docs/formats.md §12); absent on other events and
  // on runs measured without one.
  std::optional<MeasurementChain> measurement_chain;
  // A start event whose chain did not read (status events carry no checksum): why, naming the
  // event; the event itself is kept (what is recorded stays readable), the chain is unknown.
  std::string measurement_chain_error;
};

}  // namespace fralab
