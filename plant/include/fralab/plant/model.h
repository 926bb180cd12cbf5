// The model file `fralab-model/1` (docs/formats.md §2): one operating point of a plant. The same
// format describes the engine the plant emulator runs and the simulation diagnosis checks against
// data.
//
// Signal flow for one path: command u -> actuator tf -> actuator nonlinearities (in order) ->
// actuator position (the input's channel) -> path tf -> sum over inputs -> sensor tf -> + white
// Gaussian noise of noise_rms -> output channel. All tfs act on deviations from the operating
// point's steady state (`operating_point.steady_state`, absolute values in channel units).
//
// fralab extensions (optional keys, kept when absent from other tools' files):
//   inputs[i].noise_rms            position-measurement noise, input units (default 0)
//   inputs[i].test_amplitude_pct   the input's default test amplitude, % of full scale (the report
//                                  oscillated A8 at +-5 %); `--amplitude-pct` overrides it
//   inputs[i].measurement_coupling [{"output": "P3", "gain": g}]: the recorded position channel
//                                  sees g * (noise-free deviation of that output), as the report's
//                                  fuel-flow measurement dPfn = Pfn - P3 sees P3 (Appendix A)
//   inputs[i].faults, outputs[i].faults  recording faults the emulator puts into the channel
//                                  (plant/faults.h); a simulation's are ignored
#pragma once

#include <complex>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/tf.h"
#include "fralab/plant/faults.h"

namespace fralab {

inline constexpr const char* kModelFormat = "fralab-model/1";

/// An actuator's nonlinear element (a model file's `type`: "deadband", "hysteresis", "rate_limit",
/// "saturation").
enum class NonlinearityKind { kDeadband, kHysteresis, kRateLimit, kSaturation };
/// The model file's word for `k`, and back (nullopt for a word that is none).
const char* to_string(NonlinearityKind k);
std::optional<NonlinearityKind> nonlinearity_kind_from_word(const std::string& word);
/// A deadband or a hysteresis (backlash): rate-independent, sized by a width.
inline bool has_width(NonlinearityKind k) {
  return k == NonlinearityKind::kDeadband || k == NonlinearityKind::kHysteresis;
}

struct NonlinearitySpec {
  NonlinearityKind kind = NonlinearityKind::kHysteresis;
  double width = 0.0;  // deadband/hysteresis, input units (total width)
  double rate = 0.0;   // rate_limit, input units per second
  double min = 0.0;    // saturation, absolute input units
  double max = 0.0;
};

struct MeasurementCoupling {
  std::string output;
  double gain = 0.0;  // input units per output unit
};

struct ModelInput {
  std::string name;
  std::string units;
  double full_scale = 0.0;     // > 0, input units
  std::optional<Tf> actuator;  // identity when absent
  std::vector<NonlinearitySpec> nonlinearity;
  double noise_rms = 0.0;
  double test_amplitude_pct = 0.0;  // 0: not set
  std::vector<MeasurementCoupling> measurement_coupling;
  std::vector<ChannelFault> faults;  // its position channel's, and `stuck` (plant/faults.h)
  Json extra = Json::object();
};

struct ModelOutput {
  std::string name;
  std::string units;
  double noise_rms = 0.0;
  std::optional<Tf> sensor;          // identity when absent
  std::vector<ChannelFault> faults;  // its recorded channel's (plant/faults.h)
  Json extra = Json::object();
};

struct ModelPath {
  std::string output;
  std::string input;
  Tf tf;
  Json extra = Json::object();
};

struct StateSpace;  // plant/state_space.h

struct Model {
  std::string name;
  std::string source;  // file the model was read from (for messages)
  double speed_pct = 0.0;
  std::map<std::string, double> steady_state;
  std::vector<ModelInput> inputs;
  std::vector<ModelOutput> outputs;
  std::vector<ModelPath> paths;
  std::vector<std::string> warnings;  // unknown keys etc., for the caller to print
  Json extra = Json::object();
  Json operating_point_extra = Json::object();
  /// The state model the paths were derived from, when the model was given as one
  /// (plant/state_space.h); the diagnosis takes its entries as candidate causes. Not written by
  /// model_to_json (a model file holds the paths).
  std::shared_ptr<const StateSpace> state_space;

  /// Index of an input/output by name, or -1.
  int input_index(const std::string& name) const;
  int output_index(const std::string& name) const;
  /// The path output <- input, or nullptr when the model has none (a zero path).
  const ModelPath* path(const std::string& output, const std::string& input) const;
  ModelPath* path(const std::string& output, const std::string& input);
  /// Steady-state value of a channel (0 when the model gives none).
  double dc(const std::string& channel) const;

  // Linear frequency responses at w rad/s (delays exact, nonlinearities excluded):
  Complex actuator_response(int input, double w) const;          // position / command
  Complex sensor_response(int output, double w) const;           // channel / true output
  Complex path_response(int output, int input, double w) const;  // 0 for a zero path
  /// Output channel / actuator position (path and sensor).
  Complex position_to_output(int output, int input, double w) const;
  /// Output channel / command: sensor * path * actuator.
  Complex command_to_output(int output, int input, double w) const;
  /// The tf from the command of `input` to `channel` (an input's position, an output, or the
  /// command u_<input> itself), linear parts only; nullopt for a zero path or another input.
  std::optional<Tf> command_chain(const std::string& input, const std::string& channel) const;
};

/// Reads and validates a model file. Errors (malformed JSON, wrong format tag, missing keys,
/// unknown nonlinearity types, units of the wrong kind, unstable poles, unknown channels in paths,
/// duplicate names) throw InputError naming the file and the JSON path.
Model load_model(const std::string& file);
/// The same from a parsed document; `source` names it in messages.
Model parse_model(const Json& doc, const std::string& source);
Json model_to_json(const Model& m);
void save_model(const std::string& file, const Model& m);

/// The kind of a unit string ("mass_flow", "area", "speed", "pressure", "temperature",
/// "dimensionless") or "" when unknown.
std::string unit_kind(const std::string& units);
/// The kind a known J85 channel name must have, or "" for names fralab does not know.
std::string channel_kind(const std::string& name);

}  // namespace fralab
