// hysteresis and deadband: an actuator nonlinearity seen through its sinusoidal describing
// function N(A) at the measured amplitude (plant/nonlinearity.h), width in input units. The
// trigger is odd harmonics in the actuator's position (mean h3_rel > 0.01 on the low points);
// the width is fitted on the actuator pair's points below low_corner_fraction of the simulated
// actuator's slowest corner, where the actuator's own dynamics do not bias it.
// A curve measured by a multisine (PairFit::ms) is seen through the element's best linear
// approximation under that multisine instead (multisine_bla, the lines at their command
// amplitude times |simulated actuator x linear causes found|: the element's input); the trigger
// is the median level on the non-excited lines (nl_rel); every line is fitted.
#pragma once

#include <string>
#include <vector>

#include "../pair_fit.h"

namespace fralab::diag {

/// The describing function of a `kind` (kHysteresis or kDeadband) of `width` at the input
/// amplitude that produces the measured output amplitude y (bisection: y grows with A).
C nl_describing_function(CauseKind kind, double width, double y);

/// The best of hysteresis and deadband on the points `low` of the actuator pair p, against
/// sim * base * lin (lin: linear causes found so far); *c0 is chi2 on those points without it.
/// Width searched over [1e-4 A, 1.9 A] (A the excitation amplitude at low[0]: a multisine's
/// peak). A multisine curve (fits_by_multisine): its factor is the BLA.
Cause fit_nonlinearity(const PairFit& p, const std::vector<size_t>& low, const std::vector<C>& base,
                       const std::vector<C>& lin, double* c0);

/// The factor of `kind` (hysteresis or deadband) of `width` on p's points: the describing function
/// at each point's amplitude, or for a multisine curve the BLA (*var_nl: its scatter).
std::vector<C> nonlinear_factor(const PairFit& p, CauseKind kind, double width,
                                const std::vector<C>& lin, std::vector<double>* var_nl = nullptr);

/// Whether p is a multisine curve its multisine's lines describe (the same usable lines).
bool fits_by_multisine(const PairFit& p);

/// "odd harmonics in the position (...); below X Hz the actuator lags ..." for the report (a
/// multisine: the distortion on the non-excited lines and the BLA at the lowest line).
std::string explain_nonlinearity(const PairFit& p, const Cause& nl, const std::vector<size_t>& low,
                                 double mean_h3, double corner_rad_s, double low_fraction);

}  // namespace fralab::diag
