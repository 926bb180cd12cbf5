// The engine time a best-designed experiment would need to size a diagnosis' findings as well as
// the campaign did (the method: docs/method/engine-time-bound.md).
//
// For each fitted parameter p of each finding (those with an interval), the others held at their
// values: the campaign's information I_p = sum over its points of |dH/dp|^2 / sigma^2 (H the
// extended model's response at the point's own excitation, sigma the point's noise part:
// sigma_noise when separated, else sigma; the pairs and points the diagnosis uses), so its 1-sigma
// is 1 / sqrt(I_p). The noise of each point, made independent of how it was excited,
// v = sigma^2 A^2 T (A the command amplitude on the point's line, T the seconds of data its
// estimate averages), is interpolated in log w between a pair's points. A sine of amplitude A_i on
// input i for T seconds at w then gives T A_i^2 sum_pairs |dH/dp|^2 / v(w), summed over the pairs
// input i drives; the best sine is the input and w (each pair's measured band) that maximise that
// rate r_p, and bound_p = I_p / r_p seconds reach the campaign's 1-sigma. A_i: the sine of the
// power the campaign gave input i (a sine's A^2 / 2; a multisine's sum of line amplitudes^2 / 2).
// With the other parameters known the information can only be larger than with them fitted, and a
// set of parameters needs at least its hardest one's time: max_p bound_p is a lower bound on the
// engine time of any experiment of the campaign's power reaching the campaign's intervals.
//
// T per point: a sine's n_cycles cycles at w; a multisine's n_cycles periods (the period whose
// harmonics the lines are, as multisine_excitation takes it) times the experiments of its design
// (the inputs whose lines share the point's frequency: the orthogonal design's n_u, a zippered
// one's 1) times its random-phase realisations; a point without a line amplitude whose
// frequency is one of its input's multisine's lines and whose amplitude is that multisine's peak
// (a one-input multisine's X:O) is that line.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fralab/core/measurement_chain.h"
#include "fralab/diagnose/diagnose.h"

namespace fralab {

struct EngineTimeBoundOptions {
  int grid_per_decade = 100;   // frequencies tried for the best sine, per decade of each band
  double step_rel = 1e-5;      // a parameter's central-difference step, relative to its value
  double step_abs = 1e-9;      // ... and at least this (a value of 0)
  double max_rel_sigma = 0.3;  // points measured worse than this (sigma / |G|) are not used
  void validate() const;
};

/// One fitted parameter: the campaign's information and the best sine's.
struct ParameterBound {
  size_t finding = 0;  // index into the findings
  Param parameter = Param::kDelayS;
  double value = 0;
  double information = 0;   // I_p, 1 / parameter unit^2
  double sigma_data = 0;    // 1 / sqrt(I_p), the parameter's unit
  std::string best_input;   // the best sine's input, its frequency (rad/s) and amplitude (input
  double best_w_rad_s = 0;  // units, peak)
  double best_amplitude = 0;
  double rate = 0;     // r_p, information per second of that sine
  double bound_s = 0;  // I_p / r_p
};

struct EngineTimeBound {
  enum class Status { kOk, kNoParameter };
  Status status = Status::kNoParameter;
  std::string message;
  double campaign_s = 0;  // the campaign's engine time, as given
  double bound_s = 0;     // max over the parameters of bound_s
  double ratio = 0;       // campaign_s / bound_s (0 without a parameter)
  std::vector<ParameterBound> parameters;
  std::map<std::string, double> input_amplitude;  // A_i per input
};

/// The bound for `findings` of a diagnosis of `data` against `sim` (the fitting measurement;
/// `chain` the lab's measurement chain), the campaign having taken `campaign_s` seconds of engine
/// time. InputError naming the pair and point when a point the diagnosis uses does not say its
/// excitation (amplitude, cycles), or when no pair has a usable point.
EngineTimeBound engine_time_bound(const Model& sim, const std::vector<Finding>& findings,
                                  const std::vector<MeasuredPair>& data,
                                  const MeasurementChain& chain, double campaign_s,
                                  const EngineTimeBoundOptions& opt = {});

}  // namespace fralab
