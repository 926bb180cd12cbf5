// The lab's own measurement chain: how a command becomes a sample, so that a simulation can be
// compared with data *as the lab would have measured it* (nothing the lab does itself may appear
// as an engine effect).
//
// Commands are samples at fs = sample_rate_hz (h = 1/fs), turned into a continuous drive by a hold:
//   first-order hold (the plant emulator: linear interpolation between samples):
//       Hold(jw) = sinc^2(w h / 2)                       (real: gain only, no phase)
//   zero-order hold (a real DAC: steps):
//       Hold(jw) = sinc(w h / 2) e^{-j w h / 2}          (half a sample of delay)
// with sinc(x) = sin(x)/x, then a converter delay e^{-j w converter_delay_s}. The responses then
// sampled are, to first order (aliased images, below 1e-3 for the lab's low-pass chains up to
// fs/10, left out), the continuous ones times that factor. A pair referred to the command (u_X:X,
// u_X:O) carries it; a pair between two recorded channels (X:O) does not (both carry the same
// factor, which cancels), except for an input listed in reheld_inputs: the plant emulator drives
// the paths of an actuator with a nonlinearity from its sampled position, held again, so its X:O
// pairs carry the factor once more. sample_rate_hz = 0 is an ideal chain (factor 1).
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"
#include "fralab/core/pair_id.h"

namespace fralab {

struct MeasurementChain {
  enum class Hold { kFirstOrder, kZeroOrder };
  double sample_rate_hz = 0;  // 0: ideal (no hold, no delay)
  Hold hold = Hold::kFirstOrder;
  double converter_delay_s = 0;            // DAC/ADC latency, s (>= 0)
  std::vector<std::string> reheld_inputs;  // paths driven from the held position samples

  /// The factor a pair E1:E2 carries: command_factor for u_X:* and for X:O of a reheld input X,
  /// else 1.
  std::complex<double> pair_factor(const std::string& e1, double w) const;
  /// The same for a parsed pair: command_factor when it is referred to the command or its input
  /// is reheld, else 1.
  std::complex<double> pair_factor(const PairId& pair, double w) const;

  /// The factor above at w rad/s.
  std::complex<double> command_factor(double w) const;
  /// InputError naming the value (negative rate or delay).
  void validate() const;
};

/// {"sample_rate_hz", "hold": "first_order" | "zero_order", "converter_delay_s",
///  "reheld_inputs": [...]}.
Json chain_to_json(const MeasurementChain& c);
/// Errors name `where`.
MeasurementChain chain_from_json(const Json& j, const JsonWhere& where);

/// The chain as tapes recorded before it had a field of its own carry it: the start status
/// event's message, "measurement_chain: " followed by chain_to_json's text (a tape's start event
/// now carries it typed, core/block.h StatusEvent::measurement_chain). chain_from_message: nullopt
/// for any other message; InputError naming `where` for a chain that does not read.
inline constexpr const char* kChainMessagePrefix = "measurement_chain: ";
std::string chain_to_message(const MeasurementChain& c);
std::optional<MeasurementChain> chain_from_message(const std::string& message,
                                                   const std::string& where);

}  // namespace fralab
