// missing_path: a pair X:O the simulation has no path for, whose usable points stand beyond their
// uncertainty against zero (chi2 = sum |G_meas|^2 / sigma_eff^2 > N + 4 sqrt N, N >= 3 usable
// points: a response in the noise has sigma > 0.3 |G| and none). The path is what the data say
// once divided by what the model puts around a path (the output's sensor, the lab's measurement
// chain, the position channel's coupling: the model's response with a unit path in place),
// fitted by TFNS (identify/tfns.h: orders, roots and delay chosen by the fit, the delay within
// DiagnoseOptions' delay_max_s). The finding (scope path) carries the tf (Finding::tf) and the
// parameters gain (its DC gain, output units per input unit), delay_s, poles and zeros (counts).
#pragma once

#include <optional>

#include "../pair_fit.h"

namespace fralab::diag {

/// The pair's usable points (sigma_eff as the diagnosis weighs them), for chi2 and the errors.
PairFit absent_pair_points(const MeasuredPair& mp, const DiagnoseOptions& opt);

/// The finding for pair `p` (absent_pair_points) of input X and output O, or nullopt (with *why
/// set when the data stand beyond the noise yet no path could be fitted).
std::optional<Finding> fit_missing_path(const Model& sim, const PairFit& p,
                                        const DiagnoseOptions& opt, std::string* why);

}  // namespace fralab::diag
