// A state model from a MATLAB/Octave .mat file (docs/formats.md §2b), read through matio (level 4,
// 5 and, with matio's HDF5 support, 7.3), in the layouts users save:
//   - variables A, B, C, D (D optional), with optional StateName, InputName, OutputName (cell
//     arrays of text) and InputDelay, OutputDelay (s), as MATLAB's `linearize` returns them and
//     `save` writes their fields;
//   - one struct variable holding those fields (or `inputs`, `outputs` and a per-path `delay_s`,
//     outputs x inputs, as `fralab export` writes the identified state model, its `ss`);
//   - Dymola's dslin.mat: ABCD = [A B; C D], nx (the number of states) and xuyName (a char matrix,
//     one name a row: the states, then the inputs, then the outputs).
// Names absent: x1..xn, u1..um, y1..yp.
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
std::optional<Json> state_space_document_if_mat(const std::string& path);

}  // namespace fralab
