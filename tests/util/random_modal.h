// A generator of structures for the diagnosis' self-check (`fralab-bench-diagnose --plants
// modal`): 2-8 light modes (wn 2-50 rad/s, at least 4 % apart, damping 0.01-0.05) common to every
// path, 1-3 inputs x 2-5 outputs, each path's residues rank one (a mode shape at the outputs times
// one at the inputs, of mixed sign and size, so some paths carry a mode weakly). The engine is the
// structure itself with its changes: 0-3 modes moved in frequency (1-5 %; a pole_shift), in damping
// (x 0.5 or x 1.5-3; a damping_error) or both (a pole_shift), the mode shapes kept (a real
// structure's change of stiffness or damping: its antiresonances move with the modes); and, with
// two or more inputs, sometimes an output's calibration (1.5-4 dB over every path into it). Each
// hidden effect says what the diagnosis must find (random_plant.h). The measurement is in-process
// (modal_measurement): each path's exact response on a logarithmic grid dense enough to put four
// lines in the lightest mode's half-power band, with complex noise of a known relative sigma.
// Deterministic in the seed.
#pragma once

#include <cstdint>
#include <vector>

#include "random_plant.h"

namespace fralab::testing {

/// Case `index` of the sequence drawn from `seed`; n_hidden < 0: 0-3 at random.
RandomCase random_modal_case(uint64_t seed, int index, int n_hidden = -1);

/// For measuring c through the lab (`fralab-bench-diagnose --plants modal --through-lab`): each
/// engine output's noise rms `rel` times its strongest response to an input at the lab's test
/// amplitude (2 % of the full scale), the largest |G| at the engine's modes over its paths.
void set_lab_noise(RandomCase& c, double rel = 0.002);

/// Every X:O pair of c's engine measured as above (relative sigma `rel_sigma`), its validation
/// measurement drawn with another seed; the grid spans the modes' band widened by 30 % each side.
std::vector<MeasuredPair> modal_measurement(const RandomCase& c, uint64_t seed,
                                            double rel_sigma = 0.002);

}  // namespace fralab::testing
