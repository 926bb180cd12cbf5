// A simulation made from measurements: a common-pole fit (identify/common_poles.h) written as a
// model file (fralab-model/1), so that `fralab diagnose`, `measure --engine` and `monitor` take
// it as they take a model a simulation's owner wrote (docs/formats.md §25).
//
// Each fitted curve becomes the path of its pair ("INPUT:OUTPUT", Frd::pair), its tf the curve's
// model in factored form (PoleSetFit::to_tf: every path holds the same poles, as a structure's
// modes are every path's). Inputs and outputs are named by the pairs, in their first appearance's
// order; no actuator, sensor or noise (full scale 1, in the data's own units).
#pragma once

#include <string>

#include "fralab/identify/common_poles.h"
#include "fralab/plant/model.h"

namespace fralab {

/// The model of fit r; `name` its name. InputError naming the curve when a curve's pair is not
/// "INPUT:OUTPUT", when two curves name one pair, or when a path's tf is unstable (a fit's poles
/// are stable; a rounding of to_tf's roots could not be).
Model fitted_simulation(const CommonPoleResult& r, const std::string& name);

}  // namespace fralab
