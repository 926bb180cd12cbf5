// Recording faults the emulator can put into a channel (docs/formats.md §2c), so that the lab's
// data-quality checks can be tested on known answers: a model file's `faults` array on an output
// (its recorded channel) or on an input (its position channel; `stuck` acts on the actuator
// itself). Each fault acts at the sample clock, deterministic by the plant's seed.
//
// A recorded sample k of a channel with value s_k = dc + x_k (x_k the noise-free deviation from the
// operating point) and noise e_k passes, in this order:
//   clock     the channel's own clock runs fast by rate_error (>= 0) and lags by offset_s (>= 0):
//             sample k holds the signal at the true time t = k h / (1 + rate_error) - offset_s,
//             linearly interpolated between the two samples either side (a slow clock is every
//             other channel's fast one);
//   hum       + amplitude sum_m sin(2 pi m frequency_hz t + phase_deg), m over `harmonics`;
//   drift     + rate (t - from_s) for t >= from_s, channel units per second;
//   clip      the value clamped to [min, max] (absolute channel units; either may be absent);
//   sign      dc - (value - dc): the deviation's sign flipped (a wiring fault);
//   scale     value x factor (a units mix-up: psi read as kPa is 6.894757);
//   dead      from from_s on the channel reads `value` (default dc) plus its noise;
//   dropouts  from each sample a dropout starts with probability rate_hz h, lasting `length`
//             samples, the last good sample held ("held") or NaN ("lost");
//   swap      after every channel's faults, the channel and `with` are exchanged (wiring).
// `stuck` (inputs only): the actuator position holds its value from from_s for for_s seconds.
// h = 1 / sample rate; t = k h. Faults act only where listed: a model without them simulates
// sample for sample as before.
#pragma once

#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"

namespace fralab {

enum class ChannelFaultKind {
  kClock,
  kHum,
  kDrift,
  kClip,
  kSign,
  kScale,
  kDead,
  kDropouts,
  kSwap,
  kStuck
};
/// "clock", "hum", "drift", "clip", "sign", "scale", "dead", "dropouts", "swap", "stuck".
const char* to_string(ChannelFaultKind k);
/// The kind named by `s`, nullopt when none is.
std::optional<ChannelFaultKind> channel_fault_kind(const std::string& s);

struct ChannelFault {
  ChannelFaultKind kind = ChannelFaultKind::kClip;
  std::optional<double> min, max;  // clip, absolute channel units
  double frequency_hz = 50.0;      // hum, Hz
  double amplitude = 0.0;          // hum, channel units (peak, each harmonic)
  std::vector<int> harmonics{1};   // hum, multiples of frequency_hz
  double phase_deg = 0.0;          // hum
  double rate = 0.0;               // drift, channel units per second
  double factor = 1.0;             // scale
  double from_s = 0.0;             // drift, dead, stuck: s
  double for_s = std::numeric_limits<double>::infinity();  // stuck: s
  std::optional<double> value;  // dead: what it reads (default the channel's dc)
  double rate_hz = 0.0;         // dropouts: mean starts per second
  int length = 1;               // dropouts: samples each
  bool held = true;             // dropouts: "held" (true) or "lost" (false)
  double rate_error = 0.0;      // clock: relative, >= 0
  double offset_s = 0.0;        // clock: s, >= 0
  std::string with;             // swap: the other channel
};

/// A channel's `faults` array; InputError naming the JSON path of what is wrong (an unknown kind,
/// a clip with neither min nor max or min >= max, a negative rate, a clock error outside
/// [0, 0.01], a dropout length < 1, a mode other than "held"/"lost"). `on_input`: the channel is
/// an input's position (`stuck` is allowed only there).
std::vector<ChannelFault> channel_faults_from_json(const Json& j, const JsonWhere& where,
                                                   bool on_input);
Json channel_faults_to_json(const std::vector<ChannelFault>& faults);

/// One channel's faults applied sample by sample (all but swap and stuck, which the simulator
/// applies: they involve another channel or the actuator).
class FaultyChannel {
 public:
  /// `dc`: the channel's operating-point value; `seed`, `channel`: the dropout generator's seed
  /// (independent of the noise's, so a channel's noise is the same with or without faults).
  FaultyChannel(std::vector<ChannelFault> faults, double dc, double sample_rate_hz, uint64_t seed,
                int channel);
  /// Recorded value of sample k (k = 0, 1, ... in order) from the clean signal `signal` (dc plus
  /// deviation) and its noise.
  double apply(int64_t k, double signal, double noise);
  bool empty() const { return faults_.empty(); }
  void reset();

 private:
  std::vector<ChannelFault> faults_;
  double dc_, h_;
  std::mt19937_64 rng_;
  uint64_t seed_;
  int channel_;
  std::deque<double> past_;  // clock: signal + noise from sample past_base_ on
  int64_t past_base_ = 0;
  int64_t drop_left_ = 0;
  double last_ = 0.0;
};

}  // namespace fralab
