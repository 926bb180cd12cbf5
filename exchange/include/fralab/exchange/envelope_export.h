// `fralab export --from DIR` for an envelope's folder (DIR/envelope.json, docs/formats.md §26):
// the envelope for MATLAB, Octave and Python in one .mat file:
//
//   schedule_by        text: the scheduling variable's name (speed_pct: % N/Nmax)
//   points             struct: name (cell row), x (column)
//   states.state_NN    struct per state (NN from 01, in envelope.json's order): label, kind
//                      ("real" or "pair"), x, point (cell row), root_rad_s (|root|: 1/tau or wn),
//                      tau_s (real; NaN for a pair), wn_rad_s and zeta (pairs; NaN for a real
//                      pole), rel_sigma (NaN unknown), spread (rows x 2, the paths' own roots in
//                      the value's units), at_every_point, monotone (1/0), flags (text)
//   slow_states.state_NN  struct per slow state (the report's tables): label, outputs (cell
//                      row), x, point, tau_s (the mean over its paths), sem,
//                      tau_of_mean_pole_s, range (rows x 2),
//                      flags; empty for an envelope.json written before them
//   findings.finding_NN  struct per finding: cause, scope, input, output, parameter, text, x,
//                      value, sigma (NaN unknown), simulated (NaN none), law (form, a, b, b_sigma
//                      (NaN unknown): constant a, linear a + b x, power a x^b), missing_at
//   leave_one_out      struct: point (cell row), x, error_simulation, error_scheduled,
//                      error_extended (NaN where refused), refused (cell row, "" when built)
//
// The points' own measurements export from their folders (DIR/<point>/measure).
#pragma once

#include <string>

namespace fralab {

/// true when `dir` holds an envelope (DIR/envelope.json).
bool is_envelope_dir(const std::string& dir);

/// Writes the .mat described above. InputError naming the file and key when envelope.json is not
/// a fralab-envelope/1 document.
void export_envelope_mat(const std::string& dir, const std::string& out_file);

}  // namespace fralab
