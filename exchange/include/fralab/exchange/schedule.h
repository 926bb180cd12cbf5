// The excitation schedule, `fralab-schedule/1`: the test signal's status events (core/block.h,
// StatusEvent) as JSON, so that a time series recorded elsewhere can be analysed as a tape
// (`fralab import --schedule`), and a tape's schedule written out (`fralab export --tape`).
//
// { "format": "fralab-schedule/1", "sample_rate_hz": 1000, "run_id": "imported",
//   "events": [ { "seq": 0, "sample": 2000, "excitation": "stepped_sine", "state": "integrate",
//                 "step": 0, "n_steps": 31, "frequency_hz": 0.1, "ref_phase_rad": 0.0,
//                 "n_cycles": 3, "n_samples": 30000, "inputs": ["Wf"], "amplitudes": [30.0] } ] }
//
// Event keys are the StatusEvent fields: sample indices on the series' clock (t = sample /
// sample_rate_hz), frequency_hz in Hz, ref_phase_rad in radians (the reference at sample n is
// ref_phase_rad + 2 pi frequency_hz (n - sample) / sample_rate_hz), amplitudes peak in input
// units per input of `inputs`; "excitation" "stepped_sine" | "sweep" | "multisine", "state"
// "start" | "settle" | "integrate" | "done" | "abort"; multisine events add period_samples, lines
// and line_input. Optional keys default as in StatusEvent; seq defaults to the event's index
// (the start event: -1). Numbers are written losslessly.
#pragma once

#include <string>
#include <vector>

#include "fralab/core/block.h"
#include "fralab/core/json_util.h"

namespace fralab {

inline constexpr const char* kScheduleFormat = "fralab-schedule/1";

struct Schedule {
  double sample_rate_hz = 0.0;
  std::string run_id;
  std::vector<StatusEvent> events;
};

Json schedule_to_json(const Schedule& s);
/// Errors name the file and JSON path (a missing key, a word that is not a state, amplitudes not
/// one per input, a sample rate <= 0, events out of sample order).
Schedule schedule_from_json(const Json& j, const std::string& source);
Schedule load_schedule(const std::string& file);

/// A stepped-sine schedule found from a recorded reference alone (`fralab import --reference`):
/// the generator's frequency (Hz) and phase (radians) channels, as fralab's own tape records them.
/// A step is a maximal run of samples at one frequency > 0 (relative 1e-9); its integration is its
/// last N whole cycles, N = max(min_cycles, ceil(min_integrate_s f)) as the campaign chooses them
/// (acquire/campaign.h), L = round(N fs / f) samples (refused when N cycles are not within 1e-6 of
/// a whole number of samples: not a fralab stepped sine), the rest its settle; the reference phase
/// is the recorded one at the window's first sample. The excited input is the command channel
/// u_<input> that varies over the step (the largest rms about its mean relative to the mean's
/// size; every other u_ channel's input gets amplitude 0); its amplitude is sqrt(2) x that rms
/// over the window (a sine's peak). InputError naming the channel or the step otherwise.
struct ReferenceScheduleOptions {
  std::string freq_channel = "ref_freq_hz";
  std::string phase_channel = "ref_phase";
  int min_cycles = 8;
  double min_integrate_s = 4.0;
  std::string run_id = "imported";
  void validate() const;
};
struct TimeSeries;
Schedule schedule_from_reference(const TimeSeries& s, const ReferenceScheduleOptions& o);

}  // namespace fralab
