// The models/ folder compiled into the binaries, so that `fralab run` needs no file. Names are the
// file names ("j85_95.json", "j85_95_sim.json", ...).
#pragma once

#include <string>
#include <vector>

#include "fralab/plant/model.h"

namespace fralab {

struct EmbeddedModel {
  const char* name;
  const char* json;
};
const std::vector<EmbeddedModel>& embedded_models();

/// A model by file path, or, when `spec` names no file but an embedded model ("j85_95" or
/// "j85_95.json"), the embedded copy; "SET@X" / "SET@KEY=X" is the model of a set at an operating
/// point (plant/schedule.h). InputError listing the embedded names otherwise.
Model load_model_or_embedded(const std::string& spec);

}  // namespace fralab
