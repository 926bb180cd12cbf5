// Recording faults drawn at random for the self-checks (plant/faults.h), and how the checks'
// findings score against them: `fralab-bench-dataquality` (the checks alone, in-process) and
// `fralab-bench-diagnose --faults` (the lab end to end).
#pragma once

#include <random>
#include <string>
#include <vector>

#include "fralab/exchange/data_quality.h"
#include "fralab/plant/model.h"

namespace fralab::testing {

/// What was put into a channel and what the checks must name.
struct InjectedFault {
  std::string channel;
  DataFaultKind kind = DataFaultKind::kClipping;
  double size = 0;  // hum amplitude, drift rate, clock rate error (what is sized); else 0
  std::string text;
};

/// Adds one fault to an output of `m`, drawn from: clipped at 60-90 % of its swing on one side or
/// both, hum of 0.5-5 noise rms at 50 or 60 Hz (its 3rd harmonic half the time), drift of 0.5-3
/// response sd over the run, held or lost dropouts (0.2-3 a second, 1-20 samples), dead from
/// 30-80 % of the run, a clock 0.01-0.1 % fast; one of a kind per channel. Sized from `clean`,
/// a recording of `m` without faults.
InjectedFault add_random_fault(Model& m, const TimeSeries& clean, std::mt19937_64& g);

/// The checks' figures against what was put in: a fault is named when a fault of its channel and
/// kind is; sized when that one's size is within 10 %; a named fault nothing explains is false.
struct FaultScore {
  int put = 0, named = 0, to_size = 0, sized = 0, false_named = 0;
  std::vector<std::string> lines;  // what was missed, mis-sized or named falsely
  void add(const FaultScore& o);
};
FaultScore score_faults(const std::vector<InjectedFault>& put, const std::vector<DataFault>& named);

}  // namespace fralab::testing
