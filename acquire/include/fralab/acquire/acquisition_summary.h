// What an acquisition reports when its campaign ends (fralab-acquire --summary FILE:
// DIR/acquire.json, docs/formats.md §13), as a struct; JSON only where the file is written and
// read.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fralab/acquire/acquisition.h"
#include "fralab/core/json_util.h"

namespace fralab {

/// A step a free-running run played again because its samples were held ("repeated_steps").
struct RepeatedStep {
  int step = 0;
  double frequency_hz = 0;
  int round = 0;  // 1: the first round of repeats
  bool operator==(const RepeatedStep&) const = default;
};

struct AcquisitionSummary {
  std::string run_id;
  /// Engine (sample-clock) time of this run, s: a resumed run's from its first block on; a
  /// free-running run's every sample played, held and repeated ones too.
  double engine_time_s = 0;
  double wall_time_s = 0;   // s
  double speedup = 0;       // engine time over wall time
  int64_t blocks = 0;       // command blocks of the campaign
  int64_t first_block = 0;  // a resumed run's first
  int64_t samples = 0;      // the campaign's (an adaptive one's as it grew)
  Excitation excitation = Excitation::kStepped;
  int64_t retransmissions = 0;      // resend requests answered
  int64_t items_retransmitted = 0;  // blocks and events they resent
  bool free_running = false;        // "plant_clock": "free" or "lockstep"
  /// The adaptive stepped sine's steps, as adaptive_steps_json (acquire/adaptive_sine.h) writes
  /// them (run.json keeps the same JSON).
  std::optional<Json> adaptive;
  // Free-running only ("held_samples", "repeated_steps"):
  int64_t held_samples = 0;
  std::vector<RepeatedStep> repeated_steps;
  bool operator==(const AcquisitionSummary&) const = default;
};

/// The summary as acquire.json holds it (the free-running keys only for a free-running run).
Json acquisition_summary_to_json(const AcquisitionSummary& s);
/// Back; InputError naming `where` and the key for a missing run_id or samples, or a value of the
/// wrong kind. Keys written by later versions are ignored.
AcquisitionSummary acquisition_summary_from_json(const Json& j, const JsonWhere& where);

}  // namespace fralab
