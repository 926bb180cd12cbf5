// The launcher's process plan: which processes a plain `fralab measure` run starts, with which
// arguments, in which order, on which host. A pure function of the run's model, options, id, URL
// and resume point, so what the lab starts can be read and tested without starting anything
// (docs/lcm-protocol.md, "Processes").
//
// In start order: the recorder (inside the flow control, so a busy machine slows the run instead
// of losing tape blocks), the plant, on a fresh run the live analysers (at lower priority,
// grouped as MeasureOptions::analysers says: by default one process per position-relative pair
// and one for the command-relative pairs of each input)
// and the identifier (not essential: its failure leaves the measurement whole), and the
// acquisition last, once every consumer it waits for listens. A resumed run replays the tape into
// the plant, appends to the tape, and analyses the whole tape at its end instead of live.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fralab/lab/measure.h"
#include "fralab/lab/resume.h"
#include "fralab/lab/supervisor.h"
#include "fralab/plant/model.h"

namespace fralab {

struct ProcessPlan {
  /// The processes in start order, the acquisition last; none when a resumed run's tape is
  /// already complete.
  std::vector<ProcessSpec> processes;
  /// The acquisition's --consumers (the processes it waits for, flow control): the plant, the
  /// recorder and every analyser.
  std::vector<std::string> consumers;
  /// The processes whose exit ends the measurement: the plant, every analyser and the
  /// acquisition (the recorder is stopped after the tape is verified, the identifier waited for
  /// on its own).
  std::vector<std::string> awaited;
};

/// The path of a module executable from its name (module_path in production; a test passes its
/// own to make the plan independent of where the binary runs).
using ModuleResolver = std::function<std::string(const std::string&)>;

/// The pairs a run on `inputs` (indices into m.inputs) measures, input by input
/// (pairs_for_input).
std::vector<std::string> measured_pairs(const Model& m, const std::vector<int>& inputs);

/// One live analyser: its process name and pairs.
struct AnalyserGroup {
  std::string name;  // "analyze-<stem>": the first pair's file stem (-cmd: a command group), the
                     // input (by input), or the group's number (N pairs an instance)
  std::vector<std::string> pairs;
};

/// The analysers of a run measuring `inputs` (names) on outputs `outs`, grouped as `g` says:
/// every measured pair (measured_pairs' order) in exactly one group.
std::vector<AnalyserGroup> analyser_groups(const std::vector<std::string>& inputs,
                                           const std::vector<std::string>& outs,
                                           const AnalyserGrouping& g);

/// The plan of a run of `model` with options `o` (o.out the run's folder, its files named by
/// MeasureDir; o.acquire the acquisition's options, with the adaptive decisions already taken on a
/// resume: plan_adaptive_resume), run id `run_id`, on LCM URL `lcm_url`, starting at `from` (a
/// fresh run: the default ResumePoint; o.resume says whether the run is resumed). The acquisition
/// gets the selected inputs by name (all the model's when o.acquire.inputs is empty). No side
/// effects: nothing is read, written or started.
ProcessPlan plan_processes(const Model& model, const MeasureOptions& o, const std::string& run_id,
                           const std::string& lcm_url, const ResumePoint& from,
                           const ModuleResolver& program = module_path);

}  // namespace fralab
