#include "fralab/diagnose/baseline.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>

#include "fralab/core/error.h"
#include "fralab/core/pair_id.h"

namespace fralab {

namespace {

using C = std::complex<double>;

constexpr double kSameFrequency = 1e-6;  // relative

// Per input, its multisine on the fitting curves of `data` (the actuator curve's, else another
// curve of the input's), as prepare finds it.
std::map<std::string, MultisineExcitation> multisines(const std::vector<MeasuredPair>& data) {
  std::map<std::string, MultisineExcitation> out;
  for (bool actuator : {true, false}) {
    for (const MeasuredPair& mp : data) {
      const PairId id = PairId::parse(mp.pair);
      if (id.actuator() != actuator) continue;
      const std::string& in = id.input;
      if (out.count(in)) continue;
      if (auto ms = multisine_excitation(mp.frd)) out.emplace(in, std::move(*ms));
    }
  }
  return out;
}

// The simulation's response at a point of `pair` as the diagnosis compares it.
std::optional<C> sim_at(const Model& sim, const std::string& pair, const FrdPoint& pt,
                        const std::map<std::string, MultisineExcitation>& ms,
                        const DiagnoseOptions& opt) {
  const MultisineExcitation* m = nullptr;
  if (pt.line_amplitude > 0)
    if (auto it = ms.find(PairId::parse(pair).input); it != ms.end()) m = &it->second;
  return model_pair_response(sim, pair, pt.w, pt.amplitude, opt.chain, m);
}

// The baseline's point at w (nullptr: none within kSameFrequency).
const FrdPoint* point_at(const Frd& base, double w) {
  auto it = std::lower_bound(base.points.begin(), base.points.end(), w * (1 - kSameFrequency),
                             [](const FrdPoint& p, double x) { return p.w < x; });
  return it != base.points.end() && std::abs(it->w - w) <= kSameFrequency * w ? &*it : nullptr;
}

// curve relative to base (baseline.h); counts into s.
Frd relative(const Model& sim, const std::string& pair, const Frd& curve, const Frd& base,
             const std::map<std::string, MultisineExcitation>& ms_base, const DiagnoseOptions& opt,
             BaselineSummary& s) {
  Frd out = curve;
  for (FrdPoint& p : out.points) {
    if (!p.valid) continue;
    const FrdPoint* b = point_at(base, p.w);
    const std::optional<C> gs = b ? sim_at(sim, pair, *b, ms_base, opt) : std::nullopt;
    if (!b || !b->valid || !(b->sigma > 0) || !(b->mag > 0) || !gs || std::abs(*gs) == 0) {
      p.valid = false;
      p.note = "no usable baseline point at this frequency";
      ++s.left_out;
      continue;
    }
    const C B = b->value() / *gs, g = p.value() / B;
    const double rel_b = b->sigma / b->mag;
    if (p.sigma > 0)
      p.sigma = std::sqrt(p.sigma * p.sigma + p.mag * p.mag * rel_b * rel_b) / std::abs(B);
    p.mag = std::abs(g);
    p.phase_deg = std::arg(g) * 180 / std::numbers::pi;
    ++s.points;
  }
  return out;
}

}  // namespace

std::vector<MeasuredPair> relative_to_baseline(const Model& sim,
                                               const std::vector<MeasuredPair>& data,
                                               const std::vector<MeasuredPair>& baseline,
                                               const DiagnoseOptions& opt,
                                               BaselineSummary* summary) {
  BaselineSummary s;
  const auto ms_base = multisines(baseline);
  std::vector<MeasuredPair> out = data;
  for (MeasuredPair& mp : out) {
    const auto b = std::find_if(baseline.begin(), baseline.end(),
                                [&](const MeasuredPair& x) { return x.pair == mp.pair; });
    if (b == baseline.end() || !model_pair_response(sim, mp.pair, 1.0, 0.0, opt.chain)) {
      s.without.push_back(mp.pair);
      continue;
    }
    if (std::none_of(b->frd.points.begin(), b->frd.points.end(),
                     [](const FrdPoint& p) { return p.valid && p.sigma > 0; }))
      throw InputError("baseline " + mp.pair +
                       ": no point carries sigma (its misfit's uncertainty is unknown)");
    mp.frd = relative(sim, mp.pair, mp.frd, b->frd, ms_base, opt, s);
    if (!mp.validation.points.empty())
      mp.validation = relative(sim, mp.pair, mp.validation, b->frd, ms_base, opt, s);
    for (LevelCurve& lc : mp.levels)
      if (!lc.frd.points.empty()) lc.frd = relative(sim, mp.pair, lc.frd, b->frd, ms_base, opt, s);
    ++s.pairs;
  }
  if (summary) *summary = s;
  return out;
}

}  // namespace fralab
