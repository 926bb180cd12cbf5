// Stage 1, prepare (docs/method/diagnosis.md, "The stages"): the multisines that excited each
// input, and every pair's usable points with the simulation's response through the lab's chain
// there. Pairs of a path the simulation lacks are set aside for the missing-path fit.
#include <algorithm>
#include <cmath>

#include "../causes/missing_path.h"
#include "fralab/core/error.h"
#include "fralab/core/pair_id.h"
#include "stages.h"

namespace fralab::diag {
namespace {

const MultisineExcitation* multisine_in(const std::map<std::string, MultisineExcitation>& set,
                                        const std::string& pair, double line_amplitude) {
  if (!(line_amplitude > 0)) return nullptr;
  auto it = set.find(PairId::parse(pair).input);  // the input its excitation drives
  return it == set.end() ? nullptr : &it->second;
}

}  // namespace

const MultisineExcitation* multisine_of(const DiagnosisRun& r, const std::string& pair,
                                        double line_amplitude, bool validation) {
  return multisine_in(validation ? r.ms_val : r.ms_fit, pair, line_amplitude);
}

void add_points(const DiagnosisRun& r, PairFit& p, const Frd& curve, bool validation) {
  add_points(r, p, curve, validation ? r.ms_val : r.ms_fit);
}

void add_points(const DiagnosisRun& r, PairFit& p, const Frd& curve,
                const std::map<std::string, MultisineExcitation>& multisines) {
  for (const auto& pt : curve.points) {
    if (!usable(pt, r.opt)) continue;
    const MultisineExcitation* ms = multisine_in(multisines, p.pair, pt.line_amplitude);
    const auto s = model_pair_response(r.sim, p.pair, pt.w, pt.amplitude, r.opt.chain, ms);
    if (!s || std::abs(*s) == 0) continue;
    add_point(p, pt, *s, r.opt);
    if (ms) p.ms = ms;
  }
}

void prepare(DiagnosisRun& r) {
  const Model& sim = r.sim;
  const DiagnoseOptions& opt = r.opt;
  // Inputs excited by a multisine: the fitting data's, the validation's (another amplitude) and
  // each further level's.
  r.ms_fit = input_multisines(r.data, [](const MeasuredPair& mp) { return &mp.frd; });
  r.ms_val = input_multisines(r.data, [](const MeasuredPair& mp) { return &mp.validation; });
  size_t levels = 0;
  for (const auto& mp : r.data) levels = std::max(levels, mp.levels.size());
  r.ms_levels.resize(levels);
  for (size_t k = 0; k < levels; ++k)
    r.ms_levels[k] = input_multisines(r.data, [k](const MeasuredPair& mp) {
      return k < mp.levels.size() ? &mp.levels[k].frd : nullptr;
    });
  // The pairs the simulation can speak to (and those it has no path for).
  for (const auto& mp : r.data) {
    const PairId id = PairId::parse(mp.pair);
    PairFit p;
    p.pair = mp.pair;
    if (id.actuator()) {
      p.input = id.input;
    } else if (id.path()) {
      p.input = id.input;
      p.output = id.output;
    } else {
      continue;  // command-relative pairs repeat what X:O and u_X:X say
    }
    if (sim.input_index(p.input) < 0 || (!p.output.empty() && sim.output_index(p.output) < 0))
      continue;
    // Every point is weighed by 1/sigma^2: a curve whose valid points carry none would be left
    // out whole, and the report would read as if it agreed.
    size_t valid = 0, with_sigma = 0;
    for (const FrdPoint& pt : mp.frd.points) {
      valid += pt.valid && pt.mag > 0;
      with_sigma += pt.valid && pt.mag > 0 && pt.sigma > 0;
    }
    if (valid > 0 && with_sigma == 0)
      throw InputError(mp.pair + ": none of its " + std::to_string(valid) +
                       " valid points carries a sigma, and the diagnosis weighs each point by "
                       "1/sigma^2 (give each point's sigma, as fralab's analyser writes it)");
    if (!p.output.empty() && !sim.path(p.output, p.input)) {  // a path the simulation lacks
      r.absent.push_back(absent_pair_points(mp, opt));
      continue;
    }
    add_points(r, p, mp.frd, false);
    if (p.w.size() >= 3) r.pairs.push_back(std::move(p));
  }
  r.original = r.pairs;  // before the findings (sigma_eff: fit_causes copies its own back)
}

}  // namespace fralab::diag
