// Internal: the real-corner fit shared by missing_lag (F = 1/(1 + s/a)) and missing_lead
// (F = 1 + s/a): log-spaced corner a over the measured band widened by
// DiagnoseOptions::corner_decades_beyond on each side, grid then Brent's method.
#pragma once

#include "cause.h"

namespace fralab::diag {

/// One candidate {kind, corner_rad_s = a}.
Cause fit_corner(CauseKind kind, bool lead, const PairFit& p, const DiagnoseOptions& opt);

}  // namespace fralab::diag
