// A generator of plants shaped like real machines, for the diagnosis' self-check
// (`fralab-bench-diagnose --plants machine`): 1-3 inputs x 2-5 outputs in mixed units and full
// scales; a slow mode in every path (a rotor's inertia, 0.3-3 s), fast dynamics shared by the
// paths into one output (10-60 rad/s), each path its own gain and sign, a quarter of the paths
// weak (3-10 % of their output's strongest, near the noise); output noise 0.3-1 % of the output's
// strongest response at the test amplitude. Each case hides 0-3 effects at places that may share
// pairs, as real data do: a sensor's lag or delay (every path into an output), an input's or an
// output's calibration (a gain over every path from or into it), an actuator's pole or backlash,
// the rotor's mode moved in every path, a path's delay, gain or missing lag, a path the simulation
// lacks. Each hidden effect says what the diagnosis must find (random_plant.h's HiddenEffect).
// Deterministic in the seed.
#pragma once

#include <cstdint>
#include <string>

#include "random_plant.h"

namespace fralab::testing {

/// Case `index` of the sequence drawn from `seed`; n_hidden < 0: 0-3 at random; inputs, outputs
/// > 0 set the size (a test cell's dozens of channels), else 1-3 x 2-5 at random.
RandomCase random_machine_case(uint64_t seed, int index, int n_hidden = -1, int inputs = 0,
                               int outputs = 0);

/// Case `index` of `seed` with nothing hidden and the recording fault `f` on the engine's `output`.
RandomCase random_machine_case_with_fault(uint64_t seed, int index, const std::string& output,
                                          const ChannelFault& f);

}  // namespace fralab::testing
