// A measurement made in-process for the diagnosis's self-checks: every X:O pair of an engine that
// has a path, its exact response at each frequency of a grid with complex Gaussian noise of
// relative size rel_sigma (sigma = rel_sigma |G|, given with each point), and a validation
// measurement of the same grid with another noise seed. Deterministic in the seed.
#pragma once

#include <cstdint>
#include <vector>

#include "fralab/diagnose/diagnose.h"
#include "fralab/plant/model.h"

namespace fralab::testing {

/// Pairs in the engine's order (outputs, then inputs); w in rad/s; the fitting curves drawn with
/// seed, the validation curves with seed + 1.
std::vector<MeasuredPair> exact_measurement(const Model& engine, const std::vector<double>& w,
                                            uint64_t seed, double rel_sigma);

}  // namespace fralab::testing
