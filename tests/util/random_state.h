// A generator of random state-model plants for the diagnosis's self-check (stage 3a): 2-12
// named states with dense coupling (modes shared by many paths), 1-3 inputs, 2-5 outputs, the
// simulation given as a state model (plant/state_space.h); each case hides 0-3 changed entries in
// the engine (a state's time constant, a coupling, how an input drives a state, how a state shows
// at an output), and in about one case in four a state the simulation lacks (a first-order lag
// before an input or after an output, its corner within A's modes), and says which finding must
// name each (`state_parameter` at the entry; `missing_lag` at the input or output); in about one
// case in five a delay the simulation lacks at an input or an output, its phase at the band's
// top 0.2-2 rad (`time_delay` there). In about half the cases the simulation names parameters
// (a state's inertia J_Sk: the inverse of its row of A and B), one of which is moved in half of
// those (`state_parameter` naming it). Measured in-process (exact responses, 0.2 % noise, a
// validation measurement), as random_modal.h. Deterministic in the seed.
#pragma once

#include <cstdint>
#include <vector>

#include "random_plant.h"

namespace fralab::testing {

/// Case `index` of the sequence drawn from `seed`; n_hidden < 0: 0-3 at random.
RandomCase random_state_case(uint64_t seed, int index, int n_hidden = -1);

/// Every X:O pair of c's engine over the band of its modes (a decade beyond each end), 10 points
/// a decade, relative sigma `rel_sigma`; the validation measurement with another seed.
std::vector<MeasuredPair> state_measurement(const RandomCase& c, uint64_t seed,
                                            double rel_sigma = 0.002);

/// Whether the data resolve hidden entry `e` of case c: undoing it alone (the engine's entry back
/// at the simulation's value, the other changes kept) moves the responses on the measurement's
/// grid (state_measurement's) by chi2 = sum |G - G_undone|^2 / (rel_sigma |G|)^2 over every path
/// and point of more than ln 2N, N the points, what one parameter must earn in the diagnosis.
/// An entry that does not move them that far is not in the data to be found.
bool state_effect_resolved(const RandomCase& c, const HiddenEffect& e, double rel_sigma = 0.002);

}  // namespace fralab::testing
