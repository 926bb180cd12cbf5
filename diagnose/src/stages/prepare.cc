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

bool is_actuator_pair(const std::string& e1, const std::string& e2) { return e1 == "u_" + e2; }

// The input a pair's excitation drives: X of u_X:X, u_X:O or X:O.
std::string input_of(const std::string& pair) { return PairId::parse(pair).input; }

}  // namespace

namespace {

const MultisineExcitation* multisine_in(const std::map<std::string, MultisineExcitation>& set,
                                        const std::string& pair, double line_amplitude) {
  if (!(line_amplitude > 0)) return nullptr;
  auto it = set.find(input_of(pair));
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
  // Inputs excited by a multisine, from their actuator curve (else another curve of theirs): the
  // fitting data's and the validation's (another amplitude).
  for (bool actuator : {true, false})
    for (const auto& mp : r.data) {
      auto [e1, e2] = split_pair(mp.pair);
      if (is_actuator_pair(e1, e2) != actuator) continue;
      const std::string in = input_of(mp.pair);
      if (!r.ms_fit.count(in))
        if (auto ms = multisine_excitation(mp.frd)) r.ms_fit.emplace(in, std::move(*ms));
      if (!r.ms_val.count(in))
        if (auto ms = multisine_excitation(mp.validation)) r.ms_val.emplace(in, std::move(*ms));
      if (r.ms_levels.size() < mp.levels.size()) r.ms_levels.resize(mp.levels.size());
      for (size_t k = 0; k < mp.levels.size(); ++k)
        if (!r.ms_levels[k].count(in))
          if (auto ms = multisine_excitation(mp.levels[k].frd))
            r.ms_levels[k].emplace(in, std::move(*ms));
    }
  // The pairs the simulation can speak to (and those it has no path for).
  for (const auto& mp : r.data) {
    auto [e1, e2] = split_pair(mp.pair);
    PairFit p;
    p.pair = mp.pair;
    p.e1 = e1;
    p.e2 = e2;
    if (is_actuator_pair(e1, e2)) {
      p.input = e2;
    } else if (e1.rfind("u_", 0) != 0) {
      p.input = e1;
      p.output = e2;
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
