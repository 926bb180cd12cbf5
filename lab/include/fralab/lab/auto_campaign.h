// The campaign that decides itself (`--excitation auto`): multisine for what is linear,
// sine for what is not.
//   1. An orthogonal multisine (acquire/campaign.h: every selected input on every line, n_u
//      experiments of multisine_periods measured periods, at the sine test's power) over the
//      band: a measurement in DIR/multisine/ (its tape and curves; the campaign's runs fit
//      nothing, the merged curves are fitted once in 4).
//   2. Per input X, its actuator pair u_X:X from that run: the median nl_rel (the level of X's
//      position on the non-excited lines relative to the line, pair_analyzer.h) over the lines
//      measured to better than max_rel_sigma (sigma / |G|). X is nonlinear (a backlash, a deadband
//      at the multisine's level: its best linear approximation is not its describing function)
//      when that median exceeds nl_threshold.
//   3. The nonlinear inputs: a stepped sine at their test amplitude over the band at
//      sine_points_per_decade, sine_min_cycles cycles a point after a settle of
//      max(sine_settle_cycles cycles, 5 of their own actuators' slowest time constant) (only the
//      actuator pairs are taken from it, and a position measured to 1e-4 needs few cycles):
//      DIR/sine/.
//   4. DIR/frd: the multisine's curves, a nonlinear input's u_X:X replaced by the sine run's (the
//      describing function the diagnosis fits), its u_X:O left out (a multisine best linear
//      approximation through a backlash; kept in DIR/multisine/frd); X:O stays (the position is
//      measured after the nonlinearity, so Y / X is the linear path at every line).
//      DIR/tf and DIR/transfer_matrix.* fitted from them; DIR/run.json: "excitation" "auto",
//      engine_time_s the sum of both runs, each run's engine time, the nl figure and decision per
//      input, and the multisine run's measurement chain.
// Every number depends on the runs' tapes only (each run is deterministic in its seed).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/lab/measure.h"

namespace fralab {

struct AutoCampaignOptions {
  int multisine_periods = 2;    // measured periods per experiment (--min-cycles does not apply)
  double nl_threshold = 0.01;   // median nl_rel of u_X:X above which X is measured by sine
  double max_rel_sigma = 0.01;  // lines used for that median: sigma / |G| below this
  int sine_points_per_decade = 5;
  int sine_min_cycles = 2;  // cycles per sine point
  double sine_settle_cycles = 0.5;
  /// InputError naming the bad option.
  void validate() const;
};

struct AutoCampaignResult {
  MeasureResult measure;                 // pairs in DIR/frd, engine time of both runs
  std::map<std::string, double> nl;      // per input: the median nl_rel of u_X:X (-1: none)
  std::vector<std::string> sine_inputs;  // measured by sine
  double multisine_engine_s = 0, sine_engine_s = 0;
};

/// Runs the campaign into opt.out (opt.acquire's band, points per decade, amplitudes, seed; the
/// multisine's periods from --min-cycles). Throws InputError for --resume or a failed run; a fit
/// that fails after both runs measured leaves a partial campaign (result.measure.partial(),
/// DIR/run.json "state" "partial": measure.h).
AutoCampaignResult run_auto_campaign(const MeasureOptions& opt, const AutoCampaignOptions& a = {});

/// `fralab measure --resume DIR` on a partial auto campaign: DIR/frd fitted again (DIR/tf,
/// DIR/transfer_matrix.*), DIR/run.json "complete" or still "partial". InputError when DIR's
/// campaign is complete (nothing to resume) or not partial (an interrupted campaign resumes its
/// runs one by one: DIR/multisine, DIR/sine).
MeasureResult resume_auto_campaign(const std::string& dir);

/// Step 2 alone: the median nl_rel of an actuator curve over points with sigma / |G| <
/// max_rel_sigma (-1 when none qualifies).
double actuator_distortion(const Frd& actuator_curve, double max_rel_sigma);

}  // namespace fralab
