// Internal to the identify library: the output-error refinement of TFNS (see tfns.h, step 4:
// weighted Levenberg-Marquardt on the roots, MINPACK's lmder/lmpar) and the parameter sigmas at
// its optimum. Not installed.
#pragma once

#include <vector>

#include "fit_data.h"

namespace fralab::tfns_detail {

/// LM from `start` on sum W |G - t|^2 (t's delay free in [0, d.max_delay] when free_delay).
/// max_evaluations > 0 caps the residual evaluations (a screening refinement; *budget_hit tells
/// whether it stopped there), 0: 200 (p + 1). Returns `start` when the result cannot be evaluated
/// on the data (a root run off to 0 or infinity) or a zero sits at s = 0.
Tf refine(const Data& d, const Tf& start, bool free_delay, int max_evaluations = 0,
          bool* budget_hit = nullptr);

// Standard deviations of the fit's parameters from the Jacobian at the optimum:
// cov = (J^T J)^-1 (residuals already weighted by 1/sigma; scaled by the residual variance sse /
// dof when the data carry no sigma). Relative sigmas per root (listing order) and of the gain;
// the delay's in seconds; -1 where not computed.
struct Sigmas {
  std::vector<double> zeros, poles;
  double gain = -1, delay = -1;
};
Sigmas parameter_sigmas(const Data& d, const Tf& t, bool free_delay, double sse);

}  // namespace fralab::tfns_detail
