// A measured pair as the lab names it, "E1:E2" (docs/formats.md §4): E1 an input's position X or
// its command u_X, E2 an output or the input's own position. Parsed once where the text enters;
// the fields say what the prefix and the names mean.
#pragma once

#include <optional>
#include <string>

namespace fralab {

/// The tape channel of input X's command, "u_X" (the measured position is X itself).
std::string command_channel(const std::string& input);
/// X when `channel` is an input's command channel "u_X"; nullopt for any other channel.
std::optional<std::string> commanded_input(const std::string& channel);

struct PairId {
  std::string input;     // X, the input whose excitation drives the pair
  std::string output;    // E2: an output, or X itself (the actuator's own pair)
  bool command = false;  // E1 is the command u_X (else the measured position X)

  /// "X:O", "u_X:X" or "u_X:O"; InputError naming the text when it is not "E1:E2" or a name is
  /// empty.
  static PairId parse(const std::string& text);
  /// u_X:X, input X's actuator pair (its position over its command).
  static PairId actuator_pair(const std::string& x) { return {x, x, true}; }
  /// Back to "E1:E2".
  std::string str() const;
  /// E1's channel: u_X for a command pair, else X.
  std::string e1() const { return command ? command_channel(input) : input; }
  /// u_X:X, the actuator's position over its command.
  bool actuator() const { return command && output == input; }
  /// X:O, an output over an input's position: a path of the model.
  bool path() const { return !command; }
};

}  // namespace fralab
