// Bode plots of measured frequency responses against models, rendered by gnuplot (PNG): the
// report's cross-plots (TFNS "crossplotted with the experimental frequency response data on a
// single Bode plot") and the diagnosis' measured / simulation / extended-model figures.
//
// Each figure has three panels over frequency in Hz (log axis): gain in dB (measured with its
// sigma as error bars, 20/ln10 sigma/|G|), phase in degrees (measured unwrapped along frequency,
// each model's phase taken within 180 degrees of the measurement so curves stay comparable; sigma
// in degrees = sigma/|G| rad), and the residual measured/model in dB and degrees per model.
// Sign convention: phase = arg G, a lag is negative.
#pragma once

#include <complex>
#include <string>
#include <vector>

namespace fralab {

struct BodeCurve {
  std::string title;                    // legend, e.g. "simulation", "fit"
  std::vector<std::complex<double>> g;  // at BodePlot::w
};

struct BodePlot {
  std::string title;                       // figure title
  std::string stem;                        // file name without extension (.dat, .png)
  std::vector<double> w;                   // rad/s, increasing
  std::vector<std::complex<double>> meas;  // measured ratio at w
  std::vector<double> sigma;               // its standard deviation (absolute); empty: no bars
  std::vector<BodeCurve> models;           // at most 4
};

/// Writes dir/STEM.dat for every plot and one gnuplot script dir/SCRIPT, and renders dir/STEM.png
/// with a single gnuplot run. Returns false (nothing rendered) when gnuplot is not installed or
/// fails; the .dat files and the script are written either way. Throws InputError when a plot's
/// arrays disagree in length or it has more than 4 model curves.
bool render_bode_plots(const std::vector<BodePlot>& plots, const std::string& dir,
                       const std::string& script = "plots.gp");

}  // namespace fralab
