// A model's linear part as one state model (docs/formats.md §2b, "A model as a state model"):
// A, B, C, D from the inputs' positions (after their actuators) to the output channels (after
// their sensors), so that for every path
//   C_i (jwI - A)^-1 B_j + D_ij  e^{-jw (InputDelay_j + OutputDelay_i + delay_s_ij)}
//     = sensor_i(jw) path_ij(jw)      (Model::position_to_output, w in rad/s)
// to rounding. The actuators and nonlinearities stay the inputs' own (they sit before the
// position, a nonlinearity between actuator and position), so the state model holds what lies
// between the channels fralab records.
//
// The realisation, exact by construction:
//   - a model that carries the state model it came from (Model::state_space: a simulation given
//     as state space, the state entries its diagnosis moved included) keeps it, its states and
//     their names, when what the model adds to each path is one factor common to every path from
//     an input (put before that column of B) or into an output (after that row of C, with the
//     sensor); added states are named by `namer`;
//   - any other model: one block per path, in series with its output's sensor, each block a
//     cascade of first- and second-order sections, one section per pole factor (two real poles
//     share a section where a pair of zeros needs one), each state named by `namer`.
// A section with pole factor P and zero factor Z (unity DC gain, sigma = s / wn) is
//   first order (P = 1 + sigma, wn = -real): x' = -wn x + wn u, y = z1 u + (1 - z1) x;
//   second order (P = sigma^2 + 2 zeta sigma + 1): x1' = wn x2, x2' = -wn x1 - 2 zeta wn x2 + wn u,
//   y = (z0 - z2) x1 + (z1 - 2 zeta z2) x2 + z2 u   (Z = z2 sigma^2 + z1 sigma + z0, z0 = 1),
// so x (x1) is the section's output before its zeros, in the units of its input; the path's gain
// scales its last section's output.
// Delays: a path's delay (its own and its sensor's) is split into a part common to its input
// (the least over the input's paths), then one common to its output (the least of what remains
// over the output's paths), and the rest per path.
#pragma once

#include <functional>
#include <string>

#include "fralab/core/tf.h"
#include "fralab/plant/model.h"
#include "fralab/plant/state_space.h"

namespace fralab {

/// Where a state of the realisation sits: in the block of a path (output, input), in a factor
/// before an input's column of B (input), or after an output's row of C (output: its sensor and
/// what the model adds there).
struct StatePlace {
  enum class Kind { kPath, kInput, kOutput };
  Kind kind = Kind::kPath;
  std::string output, input;
  /// "Wf:N" (a path, fralab's pair notation input:output), "A8 input", "T5 output".
  std::string str() const;
};

/// A state's name from its place and the pole factor its section realises; the two states of a
/// second-order section get the same name with " (1)" and " (2)" appended, and a name already
/// given gets " #2", " #3", ...
using StateNamer = std::function<std::string(const StatePlace&, const Root& pole)>;

/// The default name: the place and the pole ("Wf:N pole -2.86 rad/s", "Wf:P3 mode 49.6 rad/s
/// zeta 0.021").
std::string default_state_name(const StatePlace& place, const Root& pole);

/// The model's linear part from positions to output channels as a state model, inputs and
/// outputs named as the model's, states named by `namer` (default_state_name when empty). The
/// result passes StateSpace::validate. InputError naming the model when a path is improper.
StateSpace model_state_space(const Model& m, const StateNamer& namer = {});

/// A `fralab-ss/1` document of `m` realised as `ss` (model_state_space): the model's name,
/// operating point and channels (inputs with their actuators, nonlinearities and the rest;
/// outputs without their sensors, which `ss` holds), the delays as the channels' `delay_s` and
/// the per-path `delay_s`. parse_state_space_model reads it back as a model whose responses are
/// the model's.
Json model_state_space_document(const Model& m, const StateSpace& ss);

}  // namespace fralab
