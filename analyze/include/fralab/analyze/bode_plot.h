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

/// The picture format: PNG (pngcairo) for report.md, SVG for report.html (inlined).
enum class PlotFormat { kPng, kSvg };

/// Writes dir/STEM.dat for every plot and one gnuplot script dir/SCRIPT, and renders dir/STEM.png
/// (or .svg) with a single gnuplot run. Returns false (nothing rendered) when gnuplot is not
/// installed or fails; the .dat files and the script are written either way. Throws InputError
/// when a plot's arrays disagree in length or it has more than 4 model curves.
bool render_bode_plots(const std::vector<BodePlot>& plots, const std::string& dir,
                       const std::string& script = "plots.gp",
                       PlotFormat format = PlotFormat::kPng);

/// Runs gnuplot on a script file (the path quoted for the shell); false when gnuplot is not
/// installed or the script fails. Output and errors are discarded.
bool run_gnuplot(const std::string& script_path);

/// An SVG file a render wrote, from its <svg element on (its XML prolog and doctype dropped), to
/// be written inline into an HTML page; "" when the file is missing or holds no <svg.
std::string inline_svg(const std::string& svg_file);

/// The overview of a transfer matrix as one picture (the report's Figures 1-3 drawn): a grid of
/// small Bode plots, one column per input (`cols`), two rows per output (`rows`: gain in dB above,
/// phase in degrees below, over frequency in Hz), the measured points in black and each model's
/// curve in its colour as in render_bode_plots. grid[r][c] is the plot of output r / input c, or
/// null (an empty cell). Reads the .dat files render_bode_plots wrote in `dir` (call it first);
/// renders dir/STEM.png or .svg. false when gnuplot is missing or fails; InputError when the grid
/// is not rows x cols.
bool render_bode_overview(const std::vector<std::vector<const BodePlot*>>& grid,
                          const std::vector<std::string>& rows,
                          const std::vector<std::string>& cols, const std::string& title,
                          const std::string& dir, const std::string& stem, PlotFormat format);

}  // namespace fralab
