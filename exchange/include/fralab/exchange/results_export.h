// `fralab export`: a measurement's results for MATLAB, Octave, Python and spreadsheets. Reads a
// measure directory (DIR/frd/*.json, DIR/tf/*.json, DIR/transfer_matrix.json, DIR/engine.json for
// units) and writes, with channel names and units:
//
// .mat (one file; load with Octave/MATLAB `load`, Python scipy.io.loadmat):
//   inputs, outputs       cell rows of names (the transfer matrix's columns and rows)
//   units                 struct: w "rad/s", f_hz "Hz", phase_deg "deg", delay_s "s", and one
//                         field per channel with its engineering unit (from engine.json)
//   frd.<E1>_<E2>         struct: pair, input, output, w [rad/s], f_hz [Hz], mag (|E2/E1|),
//                         phase_deg [deg], H (complex mag e^{j phase}), sigma (NaN unknown),
//                         coherence (NaN unknown), valid (1/0), units (text)
//   tf.<E1>_<E2>          struct: pair, text (report notation), gain, delay_s [s], num, den
//                         (polynomials in s, highest power first: G(s) = num/den e^(-s delay_s),
//                         Octave `tf(num, den)`), zeros, poles (complex columns, rad/s),
//                         fit_error, status
//   ss                    struct (when transfer_matrix.json holds the state model): A, B, C, D,
//                         delay_s (outputs x inputs), inputs, outputs, error
// CSV (a folder): frd/<E1>_<E2>.csv (w,f_hz,mag,mag_db,phase_deg,re,im,sigma,coherence,valid;
//   `fralab fit --frd` reads it back), tf.csv (one row per path: pair,input,output,gain,delay_s,
//   num,den,zeros,poles,fit_error,text; polynomial coefficients space separated), ss_A.csv ..
//   ss_D.csv and ss_delay_s.csv (row and column names in the first column and row), units.csv.
// JSON stays what `fralab measure` writes (docs/formats.md §1 and §4).
#pragma once

#include <map>
#include <string>

namespace fralab {

/// Each channel's engineering unit from a fralab-model/1 file (load_model; an input's unit also
/// for its command u_<input>); {} when the file does not exist, InputError when it does not read.
std::map<std::string, std::string> channel_units(const std::string& model_file);

struct ExportSummary {
  int frd = 0, tf = 0;
  bool state_model = false;
  std::string written;  // the file or folder
};

ExportSummary export_results_mat(const std::string& measure_dir, const std::string& out_file);
ExportSummary export_results_csv(const std::string& measure_dir, const std::string& out_dir);

}  // namespace fralab
