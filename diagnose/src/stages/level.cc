// Stage 7b, level (docs/method/diagnosis.md, "The stages"): a finding whose parameter is not the
// same at the validation measurement's level. With a validation measurement at another excitation
// level (fralab's own is 1.5x the amplitude), each finding's primary parameter is fitted again on
// the validation points of its pairs, every other finding in place (Brent's minimum of chi2 over
// the parameter, Boost.Math; the findings that share pairs refitted in turn, a few rounds), with
// its 1-sigma interval as stage 6 takes it. When the two values
// lie apart by more than kApart times their sigmas combined, the finding is not one linear
// cause: it is marked level-dependent, with the parameter per level and its slope
// (Finding::level), and said so in its explanation. A level is the median excitation amplitude
// of the points (peak, input units); data that do not give it compare as "fitting" and
// "validation", without a slope.
#include <algorithm>
#include <boost/math/tools/minima.hpp>
#include <cmath>

#include "stages.h"

namespace fralab::diag {
namespace {

constexpr double kApart = 3.0;  // sigmas: a level dependence is named beyond this
constexpr int kRounds = 4;      // rounds of the refit on the validation data

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double half_width(const std::array<double, 2>& iv, double v) {
  const double lo = std::isfinite(iv[0]) ? v - iv[0] : INFINITY;
  const double hi = std::isfinite(iv[1]) ? iv[1] - v : INFINITY;
  if (!std::isfinite(lo)) return hi;
  if (!std::isfinite(hi)) return lo;
  return 0.5 * (lo + hi);
}

// A finding's validation points: its pairs on the validation measurement, with the levels of the
// fitting and the validation points.
struct ValidationPoints {
  std::vector<PairFit> pairs;
  double level_fit = 0, level_val = 0;
  size_t n = 0;
};

ValidationPoints validation_points(const DiagnosisRun& r, const Finding& f) {
  ValidationPoints v;
  std::vector<double> amp_fit, amp_val;
  for (const MeasuredPair& mp : r.data) {
    if (std::find(f.pairs.begin(), f.pairs.end(), mp.pair) == f.pairs.end()) continue;
    for (const auto& pt : mp.frd.points)
      if (usable(pt, r.opt)) amp_fit.push_back(pt.amplitude);
    PairFit p;
    p.pair = mp.pair;
    add_points(r, p, mp.validation, true);
    amp_val.insert(amp_val.end(), p.amp.begin(), p.amp.end());
    if (p.w.size() >= 3) {
      v.n += p.w.size();
      v.pairs.push_back(std::move(p));
    }
  }
  v.level_fit = median(amp_fit);
  v.level_val = median(amp_val);
  return v;
}

}  // namespace

void level(DiagnosisRun& r) {
  const size_t nf = r.findings.size();
  // Per finding: its primary parameter, its validation points, whether it is compared.
  std::vector<std::string> keys(nf);
  std::vector<ValidationPoints> val(nf);
  std::vector<bool> compared(nf, false);
  for (size_t i = 0; i < nf; ++i) {
    const Finding& f = r.findings[i];
    keys[i] = cause_unit(f.cause)->primary_parameter(f).key;
    if (keys[i].empty() || !f.intervals.count(keys[i]) || !f.parameters.count(keys[i])) continue;
    val[i] = validation_points(r, f);
    const bool levels_known = val[i].level_fit > 0 && val[i].level_val > 0;
    compared[i] = !val[i].pairs.empty() &&
                  !(levels_known && std::abs(val[i].level_val / val[i].level_fit - 1) < 0.05);
  }
  std::vector<std::vector<const PairFit*>> val_pairs(nf);
  for (size_t i = 0; i < nf; ++i)
    for (const PairFit& p : val[i].pairs) val_pairs[i].push_back(&p);
  // chi2 of finding i's validation points with the findings `fs`, i's parameter at v.
  auto chi2_at = [&](std::vector<Finding> fs, size_t i, double v) {
    fs[i].parameters[keys[i]] = v;
    return chi2_of(r, extended_by(r, fs, fs.size()), val_pairs[i]);
  };
  // Every compared finding's parameter refitted on the validation data together (findings that
  // share pairs, as a pair's frequency and its gain, move together): rounds of Brent's minimum
  // over each in turn. The search: a factor of 2 either way for a positive parameter, else 20
  // sigmas (at least half the value) either way.
  std::vector<Finding> at_val = r.findings;
  for (int round = 0; round < kRounds; ++round)
    for (size_t i = 0; i < nf; ++i) {
      if (!compared[i]) continue;
      const Finding& f = r.findings[i];
      const IntervalDomain domain = cause_unit(f.cause)->interval_domain();
      const double v_fit = f.parameters.at(keys[i]);
      const double s_fit = half_width(f.intervals.at(keys[i]), v_fit);
      const double reach =
          std::max(20 * (std::isfinite(s_fit) ? s_fit : 0.0), 0.5 * std::abs(v_fit));
      const double lo = domain.positive ? v_fit / 2 : v_fit - std::max(reach, domain.floor);
      const double hi = domain.positive ? v_fit * 2 : v_fit + std::max(reach, domain.floor);
      boost::uintmax_t iters = 200;
      at_val[i].parameters[keys[i]] =
          boost::math::tools::brent_find_minima([&](double v) { return chi2_at(at_val, i, v); }, lo,
                                                hi, 40, iters)
              .first;
    }
  for (size_t i = 0; i < nf; ++i) {
    if (!compared[i]) continue;
    Finding& f = r.findings[i];
    const double v_fit = f.parameters.at(keys[i]), v_val = at_val[i].parameters.at(keys[i]);
    const double c_min = chi2_at(at_val, i, v_val);
    const double s = std::max(1.0, c_min / double(val[i].n));
    const auto iv_val =
        parameter_interval([&](double v) { return chi2_at(at_val, i, v) - (c_min + s); }, v_val,
                           cause_unit(f.cause)->interval_domain());
    const double s_fit = half_width(f.intervals.at(keys[i]), v_fit);
    const double s_val = half_width(iv_val, v_val);
    if (!std::isfinite(s_fit) || !std::isfinite(s_val)) continue;
    if (std::abs(v_val - v_fit) <= kApart * std::hypot(s_fit, s_val)) continue;
    const bool levels_known = val[i].level_fit > 0 && val[i].level_val > 0;
    LevelDependence ld;
    ld.parameter = keys[i];
    ld.levels = {val[i].level_fit, val[i].level_val};
    ld.values = {v_fit, v_val};
    ld.intervals = {f.intervals.at(keys[i]), iv_val};
    ld.slope = levels_known ? (v_val - v_fit) / (val[i].level_val - val[i].level_fit) : NAN;
    f.level = ld;
  }
}

}  // namespace fralab::diag
