// A state model from a MATLAB/Octave .mat file (docs/formats.md §2b), read through matio (level 4,
// 5 and, with matio's HDF5 support, 7.3), in the layouts users save:
//   - variables A, B, C, D (D optional), with optional StateName, InputName, OutputName (cell
//     arrays of text) and InputDelay, OutputDelay (s), as MATLAB's `linearize` returns them and
//     `save` writes their fields;
//   - one struct variable holding those fields (or `inputs`, `outputs` and a per-path `delay_s`,
//     outputs x inputs, as `fralab export` writes the identified state model, its `ss`);
//   - Dymola's dslin.mat: ABCD = [A B; C D], nx (the number of states) and xuyName (a char matrix,
//     one name a row: the states, then the inputs, then the outputs).
// Names absent: x1..xn, u1..um, y1..yp. A file fralab wrote (write_state_space_mat) also holds
// `fralab_ss`, the rest of its fralab-ss/1 document as JSON text (the channels' units, full
// scales, actuators, nonlinearities and noise, the operating point), which the reader puts back.
#pragma once

#include <string>

#include "fralab/plant/state_space.h"

namespace fralab {

/// The state model in `path`. InputError naming the file and the variable that is missing or
/// wrong (not a real matrix, sizes that disagree, names that are not text, a file matio cannot
/// open, such as a v7.3 file without HDF5 support). The model is not validated here:
/// StateSpace::validate() does that.
StateSpace read_state_space_mat(const std::string& path);

/// `path` as a fralab-ss/1 document (state_space_document) when it is a .mat file, else nullopt.
/// A `fralab_ss` text the file holds gives the document's other keys; InputError naming the file
/// and `fralab_ss` when it is not such a document or names other channels than the matrices'.
std::optional<Json> state_space_document_if_mat(const std::string& path);

/// Writes the fralab-ss/1 document `doc` (model_state_space_document, plant/realisation.h) as a
/// level-5 .mat file that MATLAB's and Octave's `load` read, ready for
///   ss(A, B, C, D, 'StateName', StateName, 'InputName', InputName, 'OutputName', OutputName,
///      'InputDelay', InputDelay, 'OutputDelay', OutputDelay)
/// with, beside those variables: delay_s (outputs x inputs, s: each path's delay beyond its
/// input's and output's; MATLAB's `ss` has no such property: the paths whose entry is not zero
/// need it added, as `exp(-s*delay_s)` or an internal delay), actuators.<input> (num, den:
/// polynomials in s, highest power first, as Octave's `tf(num, den)`, and delay_s; an input
/// without an actuator has none) and fralab_ss (the document's other keys as JSON text).
/// InputError naming the file when it cannot be written.
void write_state_space_mat(const std::string& path, const Json& doc);

}  // namespace fralab
