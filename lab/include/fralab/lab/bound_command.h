// `fralab bound`: the engine time a best-designed experiment would need to size a diagnosis'
// findings as its measurement did (diagnose/engine_time_bound.h), against the measurement's own;
// a table on the terminal and, when asked, fralab-bound/1 JSON (docs/formats.md §29).
#pragma once

#include <string>

#include "fralab/diagnose/engine_time_bound.h"

namespace fralab {

struct BoundCommand {
  std::string simulation;  // the simulation the diagnosis was made against
  std::string diagnosis;   // a `fralab diagnose` (or `fralab run`) output folder
  std::string measured;    // its fitting measurement; "" = DIAGNOSIS/measure
  std::string json;        // write fralab-bound/1 here; "" none
};

struct BoundResult {
  EngineTimeBound bound;
  double validation_s = 0;  // the validation measurement's engine time (0: none)
  std::string table;        // the terminal's text
};

/// InputError naming the file: a folder without diagnosis.json, a measurement without run.json or
/// its engine time, a diagnosis relative to a baseline (its data are ratios, not measurements).
BoundResult run_bound(const BoundCommand& c);

}  // namespace fralab
