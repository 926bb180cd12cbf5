// Random identification sets of every shape the lab can hand the transfer matrix and state model:
// 1-8 inputs x 1-8 outputs, paths missing, paths with no response (pure noise), failed fits,
// fits at the maximum order, a single point, repeated frequencies, each path on its own grid or a
// shared one, data with and without sigma, invalid and zero points, delays, shared poles (real and
// pairs, light and heavy) and mixed units. For the randomised robustness test and the "shapes" fuzz
// target: the same draw for the same seed.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/identify/transfer_matrix.h"

namespace fralab::testing {

struct RandomShapeSet {
  std::vector<std::string> inputs, outputs;
  std::vector<MatrixEntry> entries;                   // the paths with a fit
  std::map<std::string, std::vector<FrdPoint>> data;  // "input:output" -> its points
  std::string description;                            // the shape, for a failure message
};

/// The draw for `seed`. Fits are the truth's tfs with the drawn status (no fitting here: the
/// shapes, not the identifier, are under test); data are the truth at the drawn grid plus complex
/// Gaussian noise.
RandomShapeSet random_shape_set(uint64_t seed);

/// The same, the draw's choices taken from `bytes` (a fuzzer's input) instead of a seed: every
/// byte string makes a valid set.
RandomShapeSet random_shape_set_from_bytes(const uint8_t* bytes, size_t size);

}  // namespace fralab::testing
