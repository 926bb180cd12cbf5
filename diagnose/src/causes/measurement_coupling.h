// measurement_coupling: the position channel X records X + g O (an output leaking into the
// actuator's position measurement). u_X:X then sees F = 1 + g H_OX and every X:O' sees
// 1 / (1 + g H_OX), where H_OX is the simulated position-to-output response; channel, coupled_to,
// gain g. Fitted jointly over u_X:X and every X:O (g in +-0.9 / max|H_OX|, grid then Brent's
// method, for each output O with a path). Accepted only when the channel's own actuator response is
// beyond its uncertainty and explained by the coupling, and the joint chi2 drops by more than
// max(ln 2N, min_improvement chi2).
#pragma once

#include <optional>
#include <vector>

#include "../pair_fit.h"

namespace fralab::diag {

/// The coupling finding of input `input` (scope input), or nullopt. On acceptance every pair of
/// that input has the coupling's factor applied to its `factor`.
std::optional<Finding> fit_measurement_coupling(const Model& sim, const ModelInput& input,
                                                std::vector<PairFit>& pairs,
                                                const DiagnoseOptions& opt);

}  // namespace fralab::diag
