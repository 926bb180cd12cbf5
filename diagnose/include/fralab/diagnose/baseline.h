// A diagnosis against a baseline (`fralab diagnose --baseline DIR`): the measurement the
// simulation was fitted to or last agreed with. What already differed there is the simulation's
// own misfit, not a finding; the findings are what changed between the baseline and the
// measurement, sized in the simulation's terms (docs/method/diagnosis.md, "Baseline").
//
// Per pair and point, B = G_base / G_sim (the simulation's response through the measurement
// chain, at the point's amplitude or multisine, as the diagnosis compares it) is the misfit the
// baseline shows; the measurement is diagnosed as G / B, with
//   sigma'^2 = (sigma^2 + |G|^2 (sigma_base / |G_base|)^2) / |B|^2,
// so a model that reproduces G / B reproduces G once the baseline's misfit is put back. The
// simulation is unchanged; the findings extend it as always. Frequencies rad/s; the baseline's
// point at a measured point is the one within 1e-6 of it (relative).
#pragma once

#include <string>
#include <vector>

#include "fralab/diagnose/diagnose.h"

namespace fralab {

struct BaselineSummary {
  int pairs = 0;     // pairs taken relative to the baseline
  int points = 0;    // their points so taken
  int left_out = 0;  // points made invalid: no usable baseline point at their frequency
  std::vector<std::string> without;  // measured pairs the baseline lacks (left as measured)
};

/// The data relative to `baseline` (the fitting curves, and the validation and further level
/// curves when present),
/// a pair the simulation has no response for left as measured. A point whose frequency the
/// baseline's curve lacks, or whose baseline point is invalid or without sigma, is kept as
/// invalid with a note saying so (nothing recorded is dropped). InputError naming the pair when
/// a baseline curve has no sigma at all.
std::vector<MeasuredPair> relative_to_baseline(const Model& sim,
                                               const std::vector<MeasuredPair>& data,
                                               const std::vector<MeasuredPair>& baseline,
                                               const DiagnoseOptions& opt,
                                               BaselineSummary* summary = nullptr);

}  // namespace fralab
