// Repeated measurements of the same line combined: the adaptive stepped sine's passes
// (acquire/adaptive_sine.h) measure a step again at exactly its frequency, with the plant, its
// noise and the excitation amplitude unchanged; each measurement r gives a point G_r (the mean of
// its Fourier filter over n_r cycles) with sigma_r its standard deviation (pair_analyzer.h). They
// are independent estimates of the same G, combined by inverse-variance weighting:
//   w_r = 1 / sigma_r^2,  G = sum_r w_r G_r / sum_r w_r,  sigma = 1 / sqrt(sum_r w_r)
// (the minimum-variance unbiased combination; with equal noise per cycle, w_r is proportional to
// n_r and G is the mean over every cycle measured). coherence, h2_rel, h3_rel are the weighted
// means, n_cycles the sum; step, input, amplitude, note those of the first measurement.
#pragma once

#include "fralab/core/frd.h"

namespace fralab {

/// `base` with `more`'s points merged in: a valid point of `more` with a sigma (> 0) is combined
/// as above with the valid point with a sigma of `base` (or merged before it from `more`) of the
/// same input and step at its w (|dw| <= 1e-9 w: the windows of a step are at exactly its
/// frequency); any other point is added as it is (an invalid window stays beside the valid ones).
/// Points in ascending w, equal w in the order met. InputError when the pairs differ.
Frd merge_repeated(const Frd& base, const Frd& more);

}  // namespace fralab
