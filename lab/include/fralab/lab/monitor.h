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
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/frd.h"

namespace fralab {

/// The header line (with or without the simulation's columns).
std::string monitor_header(bool with_simulation);
/// One point's row; `sim` the simulation's response at the point's w (nullopt: none).
std::string monitor_row(const FrdPoint& p, const std::optional<std::complex<double>>& sim);

/// The live plot (`fralab monitor --plot PAGE.html`): the pair's valid points so far as a Bode plot
/// (analyze/bode_plot.h: gain, phase, residual) against the simulation when `sim` gives it,
/// rendered to SVG by gnuplot in PAGE.html's folder (`<stem>.plot/`) and written inline into
/// PAGE.html, replaced atomically (a browser never reads half a page). While `live`, the page
/// reloads itself every `refresh_s` seconds; the final page does not. Returns false (the page
/// then says so in words) when gnuplot is missing or fails.
bool write_monitor_page(
    const std::string& page, const std::string& title, const std::vector<FrdPoint>& points,
    const std::function<std::optional<std::complex<double>>(const FrdPoint&)>& sim, bool live,
    int refresh_s = 2);

}  // namespace fralab
