// Internal to the identify library: what fit_tf refuses in a model and how it simplifies the
// chosen one (docs/method/identifier.md, steps 8 and 9). Not installed.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fit_data.h"
#include "fralab/identify/tfns.h"
#include "order_search.h"

namespace fralab::tfns_detail {

// Reflects t's unstable poles into the left half plane (a pair's damping to |zeta|, at least
// 1e-6; a real pole's to -|p|, at least 1e-9 from 0); returns how many.
int reflect_unstable(Tf& t);

// A model the data cannot support physically: a light pole or zero pair (|zeta| < 1e-3) the grid
// w (rad/s) does not resolve (fewer than 2 points within 2 zeta wn of wn: a resonance that sharp
// between two points is noise fitted, the refinement's floor being 1e-9), or a cancelling dipole: a
// pole and zero of the same kind within 1e-3 of each other relative to the pole's modulus, or, when
// either is a light pair, within 1 % of the larger of their real parts. Such candidates are
// refused: any physical candidate is preferred.
bool nonphysical(const Tf& t, const std::vector<double>& w);

// Removes from t each cancelling dipole of nonphysical's, the closest couples first; true when any
// was removed.
bool remove_dipoles(Tf& t);

// A reduced model keeps the orders the options ask for (min_num_order, den_order_start) and stays
// proper.
bool orders_allowed(const Tf& t, const FitOptions& o);

// Refines a candidate to convergence and scores it (the order search's).
using RefineCandidate = std::function<void(Candidate&)>;

// Pruning of a fit: the order search can end above the data's order with roots the data do not
// determine, kept because the SK fit at that order needed them to pass. Removed in turn, the rest
// refined, each of: a zero and the nearest pole of its kind closer than half the pole's modulus (a
// near-cancelling couple), and a root whose relative sigma is 0.5 or more, within orders_allowed.
// The best (adequate first, then the criterion) replaces the fit while it is better.
void prune(Candidate& fit, const Data& d, const FitOptions& o, const RefineCandidate& refine);

// A real right-half-plane zero above the band is replaced by the lag it imitates there, unless the
// data give evidence for the zero (with a sigma given or estimated). *note says what was replaced.
void prefer_lags(Candidate& fit, const Data& d, const RefineCandidate& refine, std::string* note);

}  // namespace fralab::tfns_detail
