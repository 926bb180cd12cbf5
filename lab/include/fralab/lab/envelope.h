// `fralab envelope`, the campaign: each operating point measured, identified and diagnosed into
// DIR/<point>/ exactly as `fralab run` does, then the points joined (fralab/envelope/envelope.h:
// the states, findings and slow states across the points, the scheduled model), each inner point
// left out once, and the report written.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fralab/envelope/envelope.h"
#include "fralab/lab/measure.h"

namespace fralab {

// The campaign.
struct EnvelopeCommand {
  std::string engine;      // SET: an embedded family (j85), a comma list of files, or a folder
  std::string simulation;  // SET, paired with the engines by the scheduling variable
  std::string out;
  EnvelopeOptions options;
  MeasureOptions measure;  // every measure flag (engine and out are set per point)
  bool plots = true;
  // Each point's validation measurement (DiagnoseCommand::validation): off by default, each point
  // measured once (the J85 envelope in 21.9 min of engine time, 43.9 with it; every point's
  // findings the same either way, docs/validation.md §1).
  bool validation = false;
};

/// Leave-one-out over the points' folders under `dir` (each with its extended_model.json and
/// measure/ folder; EnvelopePoint::simulation set): one entry per inner point, in x order.
std::vector<LeaveOneOut> leave_one_out(const std::string& dir,
                                       const std::vector<EnvelopePoint>& points,
                                       const EnvelopeOptions& o = {});

/// Runs the campaign: each point whose DIR/<point>/diagnosis.json is missing is diagnosed (a
/// folder left by an interrupted point is first renamed DIR/<point>.interrupted, or
/// .interrupted-2, ...: its tapes are kept), in x order; then the report is joined, the scheduled
/// extended model is written to DIR/scheduled_model.json, leave-one-out is run, and the report is
/// written to DIR/envelope.json and DIR/envelope.md. `log` receives one line per step.
EnvelopeReport run_envelope(const EnvelopeCommand& c,
                            const std::function<void(const std::string&)>& log = {});

}  // namespace fralab
