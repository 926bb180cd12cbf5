// The stabilisation diagram of a pole set: the poles vector fitting reaches at each model order,
// each marked against the order below, as modal analysts read it to tell a structure's modes
// (columns of poles that stay put as the order grows) from the poles a fit adds to bend its curve
// (they wander). docs/method/identifier.md, "Stabilisation diagram".
//
// Row n: relocated_poles at n pairs (pole_set_fit.h; independent fits, no warm start, so that a
// pole's persistence is the data's and not the start's). A pair of row n is
//   stable     when row n-1 holds a pair within `frequency_rel` in wn and `damping_rel` in zeta;
//   frequency  when within `frequency_rel` in wn only;
//   new        otherwise.
// A pole of a final fit is physical when it is a lightly damped pair (zeta <= `max_zeta`) inside
// the band and `min_stable_rows` rows of the diagram hold a pair within both tolerances of it.
// Units: rad/s; zeta the damping ratio -Re p / |p|.
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"

namespace fralab {

struct StabilisationOptions {
  int max_pairs = 50;           // rows 1 .. max_pairs (fewer when the points allow fewer)
  int relocations = 8;          // per row
  double frequency_rel = 0.01;  // |wn - wn'| <= frequency_rel wn
  double damping_rel = 0.1;     // |zeta - zeta'| <= damping_rel zeta
  double max_zeta = 0.2;        // a physical mode is lighter than this
  int min_stable_rows = 5;
  /// Throws InputError naming the bad option.
  void validate() const;
};

enum class PoleStability { kNew, kFrequency, kStable };
const char* to_string(PoleStability s);

struct StabilisationRow {
  int pairs = 0;
  std::vector<std::complex<double>> poles;  // rad/s, pairs by their upper member
  std::vector<PoleStability> stability;     // per pole; a real pole is always kNew
};

struct StabilisationDiagram {
  std::vector<StabilisationRow> rows;
  double w_lo = 0, w_hi = 0;  // the band, rad/s
};

/// The diagram of curves g[c][i] on the grid w (rad/s), weights W[c][i] (pole_set_fit.h).
StabilisationDiagram stabilisation_diagram(const std::vector<double>& w,
                                           const std::vector<std::vector<std::complex<double>>>& g,
                                           const std::vector<std::vector<double>>& W,
                                           const StabilisationOptions& o = {});

/// How many rows hold a pair within both tolerances of pole p (rad/s); 0 for a real pole.
int stable_rows(const StabilisationDiagram& d, std::complex<double> p,
                const StabilisationOptions& o = {});

/// Whether pole p of a final fit is one of the structure's modes (see above).
bool physical_pole(const StabilisationDiagram& d, std::complex<double> p,
                   const StabilisationOptions& o = {});

/// {"rows": [{"pairs", "poles": [{"f_hz", "zeta", "stability"}]}], "band_hz": [lo, hi]}.
Json stabilisation_to_json(const StabilisationDiagram& d);

/// The diagram as a PNG (gnuplot): order against frequency (Hz), new, frequency-stable and stable
/// poles marked apart, the physical poles of the final fit as vertical lines, and the curves'
/// magnitudes (each over its largest, dB) beneath. The data and script stay beside the PNG. false
/// when gnuplot is missing or fails.
bool render_stabilisation_diagram(const StabilisationDiagram& d,
                                  const std::vector<std::complex<double>>& physical,
                                  const std::vector<double>& w,
                                  const std::vector<std::vector<std::complex<double>>>& g,
                                  const std::string& png);

}  // namespace fralab
