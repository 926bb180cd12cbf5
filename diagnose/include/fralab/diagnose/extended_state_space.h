// The extended model as a state model (docs/formats.md §2b, "The extended model as a state
// model"): the diagnosis' extended model realised by model_state_space (plant/realisation.h), each
// state a finding added named after it, so that the owner of the simulation reads where the
// model grew: "Wf:N pole -76.7 rad/s (missing_lag)". A simulation given as state space keeps its
// states and their names (a state entry a finding moved included) where the findings add factors
// before its inputs or after its outputs.
#pragma once

#include "fralab/diagnose/diagnose.h"
#include "fralab/plant/state_space.h"

namespace fralab {

/// d.extended as a state model: states model_state_space names, with " (<cause>)" appended to a
/// state whose pole a finding of that cause adds to, or moves within, the place it sits (a path,
/// or an input or output whose paths carry it). `sim` is the simulation d was diagnosed against.
/// InputError as model_state_space.
StateSpace extended_state_space(const Model& sim, const Diagnosis& d);

}  // namespace fralab
