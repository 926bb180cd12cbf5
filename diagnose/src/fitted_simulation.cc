#include "fralab/diagnose/fitted_simulation.h"

#include "fralab/core/error.h"
#include "fralab/core/pair_id.h"

namespace fralab {

Model fitted_simulation(const CommonPoleResult& r, const std::string& name) {
  Model m;
  m.name = name;
  m.source = name;
  for (size_t c = 0; c < r.curves.size(); ++c) {
    const CommonPoleCurve& k = r.curves[c];
    PairId id;
    try {
      id = PairId::parse(k.pair);
    } catch (const InputError& e) {
      throw InputError(k.source + ": " + e.what());
    }
    if (!id.path())
      throw InputError(k.source + ": pair '" + k.pair +
                       "' is not INPUT:OUTPUT (a position-to-output pair names the path)");
    const std::string &in = id.input, &out = id.output;
    if (m.path(out, in))
      throw InputError(k.source + ": pair " + k.pair + " is named by two curves");
    if (m.input_index(in) < 0) {
      ModelInput mi;
      mi.name = in;
      mi.full_scale = 1.0;
      m.inputs.push_back(mi);
    }
    if (m.output_index(out) < 0) {
      ModelOutput mo;
      mo.name = out;
      m.outputs.push_back(mo);
    }
    m.paths.push_back({out, in, r.fit.to_tf(c), Json::object()});
  }
  // The file's own reader checks what a model must be (stable poles, names): the model returned
  // is the one a later `load_model` of the saved file gives.
  return parse_model(model_to_json(m), name);
}

}  // namespace fralab
