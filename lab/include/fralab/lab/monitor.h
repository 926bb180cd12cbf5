// `fralab monitor`: the report's on-line pair. Rows of one pair's points as they arrive (from a
// running lab's FRALAB_FRD, or from a tape still being written), beside the simulation's response
// when one is given. LCM-free formatting here; the subcommand wires the sources.
//
//   f_hz        mag          phase_deg  |  sim_mag      sim_deg    |  d_dB     d_deg   sigma
//   0.5         0.0301       -6.2       |  0.0300       -6.1       |  +0.03    -0.1    0.0004
//
// d_dB = 20 log10(mag / sim_mag), d_deg = phase - sim phase wrapped to (-180, 180]. Invalid points
// are shown with their note.
#pragma once

#include <complex>
#include <optional>
#include <string>

#include "fralab/core/frd.h"

namespace fralab {

/// The header line (with or without the simulation's columns).
std::string monitor_header(bool with_simulation);
/// One point's row; `sim` the simulation's response at the point's w (nullopt: none).
std::string monitor_row(const FrdPoint& p, const std::optional<std::complex<double>>& sim);

}  // namespace fralab
