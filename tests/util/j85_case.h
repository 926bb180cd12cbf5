// The J85 at 95 % N/Nmax as a self-check case (`fralab-bench-diagnose --plants j85`): the
// simulation j85_95_sim against the engine j85_95, hiding the nine differences the report found
// (the embedded engine holds their values): the BLD, A8 and IGV actuators faster than modelled
// (35.8, 38.2, 19.9 rad/s), A8's hysteresis (9.24 %), the 11 ms combustion delay on Wf -> P3, P5
// and DPP3, and the spool's missing lags on Wf -> N (76.7 rad/s) and A8 -> N (53.9 rad/s), each
// with the tolerance the lab's integration tests hold it to. Recording faults are drawn beside it
// (random_faults.h) to test that they do not become findings.
#pragma once

#include "random_plant.h"

namespace fralab::testing {

/// Case `index`: every case is the same plant (its name carries the index).
RandomCase j85_case(int index);

}  // namespace fralab::testing
