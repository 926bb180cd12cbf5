// Findings a fault of the recording would explain as well (docs/method/data-quality.md): what the
// data alone cannot tell from a model difference is reported beside the finding as an
// alternative the user must check, never silently as either.
//   wiring_sign  a sign_error at an output (its sensor) or an input: the channel wired with the
//                wrong sign gives the same curves.
//   units        a gain_mismatch at an output or input whose factor |k| (or 1/|k|) is within 1 %
//                of a units factor (psi/kPa 6.894757, bar/psi 14.50377, degF/degC 1.8, in/mm
//                25.4, lb/kg 2.204623, lbf/N 4.448222, rpm/(rad/s) 9.549297, deg/rad 57.29578,
//                %/fraction 100, ...): the channel recorded in one unit and read as the other.
//   clipping     any finding at a clipped channel (its output, or its input's position), given
//                the share of its samples the recordings' checks found at its range: the
//                clipped samples are filled from those the range kept, but what the fill
//                cannot know (the plant's own distortion at those peaks, samples outside the
//                integration windows) stays, and unfilled clipping lowers the channel's gain
//                and distorts its curves as a model difference would.
//   dead_channel an output whose every measured pair holds only noise (at most 20 % of the
//                points above 3 sigma) while the simulation expects far more (at least half the
//                points and five of them above 10 sigma): a sensor dead from before the run's
//                first period, which the recording's own checks have nothing to compare with.
//                Over two or more inputs' paths a dead sensor is the likelier reading (every
//                path into one output gone at once is not a model difference) and the lab sets
//                its pairs aside (silent_outputs); over one, a missing path reads the same, and
//                the finding there names the dead channel beside it.
//   clock        a time_delay (delay tau) or missing_lag (corner wc: at low frequency a delay of
//                1 / wc) at an output whose recorder's clock estimate over the campaign's runs
//                (pooled, ClockEvidence) stands 2 sigma or more from zero but below what the
//                recordings' checks name: a clock eps fast delays the samples by eps t, so at
//                the measured periods' mean time t_mid by eps t_mid; the alternative is named
//                when tau (or 1 / wc) lies within (|eps| +- 2 sigma) t_mid.
//   swap         two outputs A, B whose measured curves match the simulation's with the two
//                exchanged: with e(A, B) = rms |ln(measured A / simulated B)| over every
//                input's points, e(A,B) + e(B,A) < 0.35 (e(A,A) + e(B,B)) and each exchanged
//                error below half the smaller straight one (the simulation's own misfit stays
//                in both): the two channels swapped in the wiring or the channel list.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"
#include "fralab/diagnose/diagnose.h"

namespace fralab {

struct DataAlternative {
  enum class Kind { kWiringSign, kUnits, kSwap, kClipping, kDeadChannel, kClock };
  Kind kind = Kind::kWiringSign;
  std::string channel;  // the channel to check
  std::string other;    // swap: the channel it looks exchanged with
  int finding = -1;     // the finding (index in Diagnosis::findings) it is the alternative of
  double factor = 0;    // units: the units factor matched
  std::string text;     // one sentence, what to check
};
/// "wiring_sign", "units", "swap", "clipping", "dead_channel", "clock".
const char* to_string(DataAlternative::Kind k);

/// An output's clock rate error as the campaign's recordings estimate it and do not name: eps
/// (> 0: its samples lag more and more) and its sigma, pooled over the runs, and the mean time
/// of the measured periods since the run's start, s.
struct ClockEvidence {
  double eps = 0, sigma = 0, t_mid_s = 0;
};

/// An output of the simulation whose measured pairs hold only noise where the simulation expects
/// a response well above it (dead_channel above).
struct SilentOutput {
  std::string output;
  std::vector<std::string> pairs;   // its measured pairs (X:O, position-relative)
  std::vector<std::string> inputs;  // their inputs
  int points = 0;                   // valid points with a sigma over those pairs
  int above_noise = 0;              // of them, |H| > 3 sigma
  int expected = 0;                 // of them, |G_sim| > 10 sigma
  std::string text;                 // what was seen, one sentence
};
/// The silent outputs of `data` against `sim` (its chain in opt), in the simulation's order.
std::vector<SilentOutput> silent_outputs(const Model& sim, const std::vector<MeasuredPair>& data,
                                         const DiagnoseOptions& opt = {});

/// The alternatives of diagnosis `d` of `data` against `sim` (its chain in opt); `clipped`: per
/// channel the largest share of its samples a recording of the measurement held at its range;
/// `silent`: the silent outputs left in the data (a finding at one names the dead channel);
/// `clocks`: per output, its clock evidence (clock above).
std::vector<DataAlternative> data_alternatives(
    const Diagnosis& d, const Model& sim, const std::vector<MeasuredPair>& data,
    const DiagnoseOptions& opt = {}, const std::map<std::string, double>& clipped = {},
    const std::vector<SilentOutput>& silent = {},
    const std::map<std::string, ClockEvidence>& clocks = {});

/// [{"kind", "channel", "other", "finding", "factor", "text"}], "finding" null when none.
Json data_alternatives_to_json(const std::vector<DataAlternative>& a);

}  // namespace fralab
