// A simulation given as state space (docs/formats.md §2b, `fralab-ss/1`): A, B, C, D at an
// operating point with named states, inputs and outputs, as a linearised component model reaches
// the test cell (MATLAB's `linearize`, Dymola's `dslin.mat`, OpenModelica's `linearize`). fralab
// runs and diagnoses it as the transfer functions it implies, one per path:
//   G_ij(s) = C_i (sI - A)^-1 B_j + D_ij,   s = j w, w in rad/s, time in s,
// each path's poles the eigenvalues of A, its zeros the finite generalised eigenvalues of
// ([A B_j; C_i D_ij], [I 0; 0 0]), a pole and a zero that coincide (the mode is not controllable
// from that input or not observable at that output) cancelled, the gain G_ij(0) = D_ij -
// C_i A^-1 B_j; a path that is zero at every frequency is no path. Delays: an input's delay, an
// output's and the path's own add to the path's delay.
#pragma once

#include <Eigen/Dense>
#include <complex>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"
#include "fralab/core/tf.h"
#include "fralab/plant/model.h"

namespace fralab {

inline constexpr const char* kStateSpaceFormat = "fralab-ss/1";

/// A parameter of the model its owner names (an inertia, a time constant, a gain), and the
/// entries of A, B, C and D it sets: each proportional to it (`inverse` false: entry = its value
/// at `value` x p / value) or to its inverse (true: x value / p). Set to p, every entry scales.
struct NamedParameter {
  struct Entry {
    char matrix = 'A';     // 'A', 'B', 'C' or 'D'
    int row = 0, col = 0;  // 0-based
    bool inverse = false;
  };
  std::string name, units;
  double value = 1;  // at the matrices as given; finite, nonzero
  std::vector<Entry> entries;
};

/// The matrices and names of a state model. Sizes: A n x n, B n x m, C p x n, D p x m; states n
/// names, inputs m, outputs p; delays (s, >= 0) one per input and one per output, and one per path
/// (path_delay_s, p x m: a delay not common to an input or an output); each empty: none; the
/// owner's named parameters, if any.
struct StateSpace {
  Eigen::MatrixXd A, B, C, D;
  std::vector<std::string> states, inputs, outputs;
  std::vector<double> input_delay_s, output_delay_s;
  Eigen::MatrixXd path_delay_s;
  std::vector<NamedParameter> parameters;
  /// InputError naming `source` and the matrix or name that is wrong: sizes that disagree, a
  /// value that is not finite, a mode not in the open left half plane, a name empty or given
  /// twice, a negative delay, a parameter's value zero or its entry outside its matrix or zero.
  void validate(const std::string& source) const;
};

/// ss with named parameter k set to p (every entry it sets scaled; its value p). Precondition:
/// p finite, nonzero.
StateSpace with_parameter(const StateSpace& ss, size_t k, double p);

/// The state model's frequency response at s (rad/s, s = jw on the axis): C (sI - A)^-1 B + D,
/// outputs x inputs, delays left out. Precondition: s is not an eigenvalue of A.
Eigen::MatrixXcd state_space_response(const StateSpace& ss, std::complex<double> s);

/// The transfer function of the path from input j to output i (no value when it is zero at every
/// frequency). Precondition: validate() passed. InputError naming the path when it has a zero at
/// s = 0 (fralab's transfer functions are in DC-gain form).
std::optional<Tf> state_space_path(const StateSpace& ss, int output, int input,
                                   const std::string& source);
/// Every path, outputs x inputs, as state_space_path gives each (A's eigenvalues and the checks'
/// responses computed once for all).
std::vector<std::vector<std::optional<Tf>>> state_space_paths(const StateSpace& ss,
                                                              const std::string& source);

/// A `fralab-ss/1` document as the model fralab runs: its inputs and outputs (the objects of
/// `fralab-model/1`, with `delay_s`), its states, A, B, C and D (arrays of rows; D optional, zero)
/// and `delay_s` (optional, outputs x inputs), and each nonzero path as a transfer function.
/// InputError naming `source` and the JSON path when malformed.
Model parse_state_space_model(const Json& doc, const std::string& source);

/// The mode of A nearest `s` (rad/s, a pole of a path) within `rel` of |s|, and each state's
/// participation in it: p_k = |v_k w_k| / sum_j |v_j w_j|, v the mode's right eigenvector and w
/// its left one (a row of V^-1), largest first; empty when no mode of A lies that near.
struct ModeParticipation {
  std::complex<double> eigenvalue;
  std::vector<std::pair<std::string, double>> states;
};
std::optional<ModeParticipation> mode_participation(const StateSpace& ss, std::complex<double> s,
                                                    double rel = 1e-3);

/// The matrices and names of a `fralab-ss/1` document (read only, not validated).
StateSpace state_space_from_json(const Json& doc, const std::string& source);

/// A `fralab-ss/1` document of `ss`: its channels named, with `units` "1" and `full_scale` 1 (the
/// form a state model read from elsewhere, a .mat, takes before the user gives its channels).
Json state_space_document(const StateSpace& ss, const std::string& name);

}  // namespace fralab
