// Randomised frequency-response cases for the identifier's benchmark and tests: orders
// 1-8 with 0..n zeros, close resonance pairs, right-half-plane zeros, poles over four decades, a
// pole outside the band, sparse grids, delays; complex Gaussian noise relative to |G| or additive.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/core/tf.h"

namespace fralab::testing {

// Relative: the complex error's standard deviation is noise |G_i| (the analyser's sigma of a noisy
// input); additive: noise max_i |G_i| at every point (a measured path's output noise over a
// constant input amplitude: sigma / |G| grows where |G| falls).
enum class NoiseKind { kRelative, kAdditive };

struct RandomFrdCase {
  std::string category;
  Tf truth;                      // rational part and delay
  std::vector<FrdPoint> points;  // noisy data, sigma set when sigma_given
  double noise = 0;              // noise level (see NoiseKind)
  NoiseKind kind = NoiseKind::kRelative;
  bool sigma_given = false;
  double w_lo = 0, w_hi = 0;  // band, rad/s
};

/// Number of categories random_frd_case cycles through (index % kRandomCategories).
constexpr int kRandomCategories = 8;

/// Case `index` (its category is index % kRandomCategories): the truth depends on (index, seed)
/// only, so the same truth is drawn for every noise level; the noise on (index, seed, noise).
/// The truth and frequencies do not depend on the noise kind either.
RandomFrdCase random_frd_case(int index, double noise, bool sigma_given, uint64_t seed,
                              NoiseKind kind = NoiseKind::kRelative);

/// rms over `n` log-spaced frequencies in [w_lo, w_hi] of |G_fit - G_true| / |G_true|.
double model_error(const Tf& fit, const Tf& truth, double w_lo, double w_hi, int n = 200);

}  // namespace fralab::testing
