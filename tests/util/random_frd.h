// Randomised frequency-response cases for the identifier's benchmark and tests (issue 14): orders
// 1-8 with 0..n zeros, close resonance pairs, right-half-plane zeros, poles over four decades, a
// pole outside the band, sparse grids, delays; complex Gaussian noise relative to |G|.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/core/tf.h"

namespace fralab::testing {

struct RandomFrdCase {
  std::string category;
  Tf truth;                      // rational part and delay
  std::vector<FrdPoint> points;  // noisy data, sigma set when sigma_given
  double noise = 0;              // relative noise level (std of the complex error / |G|)
  bool sigma_given = false;
  double w_lo = 0, w_hi = 0;  // band, rad/s
};

/// Number of categories random_frd_case cycles through (index % kRandomCategories).
constexpr int kRandomCategories = 8;

/// Case `index` (its category is index % kRandomCategories): the truth depends on (index, seed)
/// only, so the same truth is drawn for every noise level; the noise on (index, seed, noise).
RandomFrdCase random_frd_case(int index, double noise, bool sigma_given, uint64_t seed);

/// rms over `n` log-spaced frequencies in [w_lo, w_hi] of |G_fit - G_true| / |G_true|.
double model_error(const Tf& fit, const Tf& truth, double w_lo, double w_hi, int n = 200);

}  // namespace fralab::testing
