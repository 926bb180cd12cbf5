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

}  // namespace fralab
