#include "fralab/diagnose/extended_state_space.h"

#include <cmath>

#include "causes/cause.h"
#include "fralab/core/error.h"
#include "fralab/plant/realisation.h"

namespace fralab {
namespace {

constexpr double kSameRoot = 1e-9;  // relative: a pole of the extended model is a finding's

bool holds(const std::vector<Root>& roots, const Root& r) {
  for (const Root& x : roots)
    if (x.same_as(r, kSameRoot)) return true;
  return false;
}

// A pole a finding put in: where (a path, or an output's sensor: input ""), and the cause's word.
struct Added {
  std::string output, input;
  Root pole;
  std::string cause;
};

}  // namespace

StateSpace extended_state_space(const Model& sim, const Diagnosis& d) {
  std::vector<Added> added;
  for (const Finding& f : d.findings) {
    const diag::CauseUnit* unit = diag::cause_unit(f.cause);
    if (!unit) continue;
    Model alone = sim;
    try {
      unit->apply(alone, f);  // the finding alone on the simulation: the poles it puts in
    } catch (const InputError&) {
      continue;  // it needs another finding's root (a root two findings moved): no name
    }
    for (const ModelPath& p : alone.paths) {
      const ModelPath* was = sim.path(p.output, p.input);
      for (const Root& r : p.tf.poles)
        if (!was || !holds(was->tf.poles, r)) added.push_back({p.output, p.input, r, unit->name()});
    }
    for (size_t i = 0; i < alone.outputs.size(); ++i)
      if (const auto& s = alone.outputs[i].sensor)
        for (const Root& r : s->poles)
          if (!sim.outputs[i].sensor || !holds(sim.outputs[i].sensor->poles, r))
            added.push_back({alone.outputs[i].name, "", r, unit->name()});
  }
  const StateNamer namer = [&](const StatePlace& place, const Root& pole) {
    const std::string name = default_state_name(place, pole);
    for (const Added& a : added) {
      if (!a.pole.same_as(pole, kSameRoot)) continue;
      const bool here = place.kind == StatePlace::Kind::kPath
                            ? a.output == place.output && a.input == place.input
                        : place.kind == StatePlace::Kind::kInput ? a.input == place.input
                                                                 : a.output == place.output;
      if (here) return name + " (" + a.cause + ")";
    }
    return name;
  };
  return model_state_space(d.extended, namer);
}

}  // namespace fralab
