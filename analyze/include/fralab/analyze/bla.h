// The best linear approximation (BLA) over random-phase multisine realisations, with its noise and
// its stochastic nonlinear distortion separated per line: Pintelon and Schoukens' robust method
// (System Identification: A Frequency Domain Approach, 2nd ed., sections 3.8 and 4.3).
//
// For a pair measured by R >= 2 independent random-phase realisations of the same multisine (the
// same lines, amplitudes and periods), each realisation r gives at line k a point G_r (the mean
// over its periods) with sigma_r, the standard deviation of G_r due to measurement noise alone
// (from the spread over periods: pair_analyzer.h). A nonlinear plant's G_r scatters from one
// realisation to the next beyond that noise: the stochastic nonlinear distortion, which has zero
// mean over realisations and is independent of them. Per line, with complex points:
//   G_BLA       = (1/R) sum_r G_r                                  (the BLA estimate)
//   var_total   = sum_r |G_r - G_BLA|^2 / (R (R - 1))              (var of G_BLA, noise + nonlin.)
//   var_noise   = sum_r sigma_r^2 / R^2                            (var of G_BLA, noise alone)
//   var_nl      = max(0, var_total - var_noise)                    (its nonlinear part)
// and the combined point carries sigma = sqrt(max(var_total, var_noise)) (what a fit weights by:
// the BLA's total uncertainty; never below the noise the periods show, which with few
// realisations is better determined than the spread), sigma_noise = sqrt(var_noise), sigma_nl =
// sqrt(var_nl) (each of G_BLA; times sqrt(R) they are one realisation's), realisations = R.
// mag, phase_deg from G_BLA; coherence and nl_rel the realisations' means; n_cycles, step,
// input, amplitude the first realisation's. var_nl is itself estimated from 2 (R - 1) real
// degrees of freedom: a linear plant's var_total / var_noise scatters about 1 as chi2 / dof.
#pragma once

#include <vector>

#include "fralab/core/frd.h"

namespace fralab {

/// Combines points of several realisations: those with the same input and w (exactly: a line's w
/// is computed the same way in every realisation) that are valid and carry a sigma (> 0) become
/// one BLA point as above when there are two or more; any other point (a single realisation, an
/// invalid one, one without sigma) is returned as it is. Output in ascending w; equal w keep the
/// order of `points` (a combined point stands where its first realisation did).
std::vector<FrdPoint> best_linear_approximation(const std::vector<FrdPoint>& points);

}  // namespace fralab
