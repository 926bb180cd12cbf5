// Internal to the identify library: fit_tf's noise level for data without sigma
// (docs/method/identifier.md, "Data without sigma: the estimated noise";
// FitOptions::estimate_noise). Not installed.
#pragma once

#include <string>

#include "delay_search.h"
#include "fit_data.h"
#include "fralab/identify/tfns.h"

namespace fralab::tfns_detail {

// Without sigma: gives d a sigma from the noise level, the user's (FitOptions::tolerance) or
// estimated from deliberately over-fitted models, so that the reduced chi^2 against it is the stop
// rule, with a slack for the estimate's own uncertainty (d.chi2_slack). Estimated, the noise may
// have an absolute part (noise_model.h). Sets d's sigma, weights and has_sigma, and res.noise_rel
// (res.noise_abs with an absolute part); nothing when no over-fit could be made. False, with res
// no_response, when the data are noise against the estimated level.
bool estimate_noise(Data& d, const FitOptions& o, DelaySearch& delays, FitResult& res);

// The message's note on the noise's shape when it has an absolute part ("" otherwise).
std::string noise_note(const FitResult& res);

}  // namespace fralab::tfns_detail
