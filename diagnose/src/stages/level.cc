// Stage 7b, level (docs/method/diagnosis.md, "The stages"): a finding whose parameters are not
// the same at every excitation level. Besides the fitting measurement there may be a validation
// measurement at another level (fralab's own is 1.5x the amplitude) and further levels
// (`fralab diagnose --levels`). On each, the findings' primary parameters and their fitted
// secondary ones (a moved mode's damping) are fitted again together on the points of their pairs
// (Levenberg-Marquardt, refine() of stage 5b), starting from the values at the nearest level
// already fitted (the fitting measurement's first), with their linearised 1-sigma (a finding the
// joint fit leaves stuck or without a sigma is fitted alone, the others held). When a value
// lies apart from the fitting measurement's by more than kApart times their sigmas combined, the
// finding is not one linear cause: it is marked level-dependent, with each parameter per level and
// its slope (Finding::level, Finding::level_secondary; a weighted straight line, the law, for three
// levels or more), and said so in its explanation. A level is the one the data give
// (MeasuredPair::level, LevelCurve::level), else the median excitation amplitude of the points
// (peak, input units); data that give neither compare as "fitting" and "validation", without a
// slope.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include "stages.h"

namespace fralab::diag {
namespace {

constexpr double kApart = 3.0;  // sigmas: a level dependence is named beyond this

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

// A measurement other than the fitting one: the validation one (k = -1) or further level k.
struct OtherMeasurement {
  int k = -1;
  const std::map<std::string, MultisineExcitation>* multisines = nullptr;
  const Frd& curve(const MeasuredPair& mp) const {
    return k < 0 ? mp.validation : mp.levels[k].frd;
  }
  double given_level(const MeasuredPair& mp) const { return k < 0 ? 0.0 : mp.levels[k].level; }
};

// A finding's points on one other measurement: its pairs there, with the levels of the fitting
// and the other measurement.
struct LevelPoints {
  std::vector<PairFit> pairs;
  double level_fit = 0, level_other = 0;
};

LevelPoints level_points(const DiagnosisRun& r, const Finding& f, const OtherMeasurement& m) {
  LevelPoints v;
  std::vector<double> amp_fit, amp_other;
  double given_fit = 0, given_other = 0;
  for (const MeasuredPair& mp : r.data) {
    if (std::find(f.pairs.begin(), f.pairs.end(), mp.pair) == f.pairs.end()) continue;
    if (m.k >= 0 && size_t(m.k) >= mp.levels.size()) continue;
    if (mp.level > 0) given_fit = mp.level;
    if (m.given_level(mp) > 0) given_other = m.given_level(mp);
    for (const auto& pt : mp.frd.points)
      if (usable(pt, r.opt)) amp_fit.push_back(pt.amplitude);
    PairFit p;
    p.pair = mp.pair;
    add_points(r, p, m.curve(mp), *m.multisines);
    amp_other.insert(amp_other.end(), p.amp.begin(), p.amp.end());
    if (p.w.size() >= 3) v.pairs.push_back(std::move(p));
  }
  v.level_fit = given_fit > 0 ? given_fit : median(amp_fit);
  v.level_other = given_other > 0 ? given_other : median(amp_other);
  return v;
}

// One parameter a finding is compared by: its key, whether it is fitted in its logarithm (as
// refine() takes it), its fitted value and 1-sigma.
struct Compared {
  Param key = Param::kToRadS;
  bool log = false;
  double v_fit = 0, s_fit = NAN;
};

// The slope of values against levels and its 1-sigma: the difference quotient for two, the
// weighted least-squares line for three or more (sigma scaled by sqrt(chi2 / dof) beyond 1).
void fit_slope(LevelDependence& ld, const std::vector<double>& sigmas) {
  const size_t n = ld.levels.size();
  ld.slope = NAN;
  ld.slope_sigma = NAN;
  if (std::any_of(ld.levels.begin(), ld.levels.end(), [](double l) { return !(l > 0); })) return;
  if (n == 2) {
    ld.slope = (ld.values[1] - ld.values[0]) / (ld.levels[1] - ld.levels[0]);
    return;
  }
  double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < n; ++k) {
    const double w = 1 / (sigmas[k] * sigmas[k]);
    sw += w;
    sx += w * ld.levels[k];
    sy += w * ld.values[k];
    sxx += w * ld.levels[k] * ld.levels[k];
    sxy += w * ld.levels[k] * ld.values[k];
  }
  const double det = sw * sxx - sx * sx;
  if (!(det > 0)) return;
  ld.slope = (sw * sxy - sx * sy) / det;
  const double intercept = (sy - ld.slope * sx) / sw;
  double chi2 = 0;
  for (size_t k = 0; k < n; ++k) {
    const double e = (ld.values[k] - intercept - ld.slope * ld.levels[k]) / sigmas[k];
    chi2 += e * e;
  }
  ld.slope_sigma = std::sqrt(sw / det) * std::sqrt(std::max(1.0, chi2 / double(n - 2)));
}

// Per finding and other measurement: the values of its parameters there and their intervals.
struct AtLevel {
  bool compared = false;
  double level_fit = 0, level_other = 0;
  std::vector<double> values;
  std::vector<std::array<double, 2>> intervals;
};

// The findings compared over the other measurements: per finding its compared parameters, per
// finding and measurement its points and values there.
class LevelComparison {
 public:
  explicit LevelComparison(DiagnosisRun& r) : r_(r), nf_(r.findings.size()) {
    if (std::any_of(r.data.begin(), r.data.end(),
                    [](const MeasuredPair& mp) { return !mp.validation.points.empty(); }))
      others_.push_back({-1, &r.ms_val});
    for (size_t k = 0; k < r.ms_levels.size(); ++k) others_.push_back({int(k), &r.ms_levels[k]});
    params_.resize(nf_);
    for (size_t i = 0; i < nf_; ++i) params_[i] = compared_parameters(r.findings[i]);
    at_.assign(nf_, std::vector<AtLevel>(others_.size()));
    pts_.assign(others_.size(), std::vector<LevelPoints>(nf_));
    for (size_t m = 0; m < others_.size(); ++m)
      for (size_t i = 0; i < nf_; ++i) {
        if (params_[i].empty()) continue;
        pts_[m][i] = level_points(r, r.findings[i], others_[m]);
        const LevelPoints& v = pts_[m][i];
        const bool levels_known = v.level_fit > 0 && v.level_other > 0;
        at_[i][m].compared =
            !v.pairs.empty() && !(levels_known && std::abs(v.level_other / v.level_fit - 1) < 0.05);
        at_[i][m].level_fit = v.level_fit;
        at_[i][m].level_other = v.level_other;
      }
  }

  // Every other measurement fitted, nearest the fitting measurement's level first (as given where
  // a level is unknown), each started from the values at the nearest level already fitted.
  void fit_all() {
    std::vector<size_t> order(others_.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
      return distance(level_of(a, true), level_of(a, false)) <
             distance(level_of(b, true), level_of(b, false));
    });
    std::vector<std::vector<Finding>> fitted(others_.size());
    std::vector<size_t> done;
    for (size_t m : order) {
      std::vector<Finding> fs = r_.findings;
      double nearest = distance(level_of(m, true), level_of(m, false));
      for (size_t d : done)
        if (const double x = distance(level_of(m, true), level_of(d, true)); x < nearest) {
          nearest = x;
          fs = fitted[d];
        }
      if (!fit_level(m, fs)) continue;
      fitted[m] = std::move(fs);
      done.push_back(m);
    }
  }

  // Per finding: each parameter's values by level; marked level-dependent when one lies apart.
  void mark_dependent() {
    for (size_t i = 0; i < nf_; ++i) {
      std::vector<LevelDependence> lds;
      bool any_apart = false;
      for (size_t q = 0; q < params_[i].size(); ++q) {
        std::optional<LevelDependence> ld = dependence(i, q);
        if (!ld) break;  // the primary (or this one) not compared
        any_apart = any_apart || ld->apart;
        lds.push_back(std::move(*ld));
      }
      if (!any_apart) continue;
      r_.findings[i].level = lds[0];
      r_.findings[i].level_secondary.assign(lds.begin() + 1, lds.end());
    }
  }

 private:
  // The parameters f is compared by (the primary first), as refine() fits them.
  static std::vector<Compared> compared_parameters(const Finding& f) {
    std::vector<Compared> out;
    const CauseUnit& unit = *cause_unit(f.cause);
    const std::optional<Param> key = unit.primary_parameter(f).key;
    if (!key || !f.intervals.count(*key) || !f.parameters.count(*key)) return out;
    auto compared = [&](Param k, bool log) {
      const double v = f.parameters.at(k);
      return Compared{k, log, v, half_width(f.intervals.at(k), v)};
    };
    out.push_back(compared(*key, unit.interval_domain().positive && f.parameters.at(*key) > 0));
    for (const SecondaryParameter& sp : unit.secondary_parameters(f))
      if (sp.fitted && f.intervals.count(sp.key) && f.parameters.count(sp.key) &&
          f.parameters.at(sp.key) > 0)
        out.push_back(compared(sp.key, true));
    return out;
  }

  static double distance(double a, double b) {
    return a > 0 && b > 0 ? std::abs(std::log(a / b)) : INFINITY;
  }

  // A measurement's level (the first compared finding's view of it; 0 unknown).
  double level_of(size_t m, bool other) const {
    for (size_t i = 0; i < nf_; ++i)
      if (at_[i][m].compared) return other ? at_[i][m].level_other : at_[i][m].level_fit;
    return 0.0;
  }

  // The compared findings refitted together on measurement m's points of their pairs, starting
  // from fs, their values and intervals kept; false when no finding is compared there.
  bool fit_level(size_t m, std::vector<Finding>& fs) {
    std::vector<size_t> group;
    std::vector<std::string> pair_names;
    for (size_t i = 0; i < nf_; ++i) {
      if (!at_[i][m].compared) continue;
      group.push_back(i);
      for (const PairFit& p : pts_[m][i].pairs)
        if (std::find(pair_names.begin(), pair_names.end(), p.pair) == pair_names.end())
          pair_names.push_back(p.pair);
    }
    if (group.empty()) return false;
    // The points of every pair a compared finding explains, once each.
    std::vector<const PairFit*> pairs;
    for (const std::string& name : pair_names)
      for (size_t i : group) {
        const auto it = std::find_if(pts_[m][i].pairs.begin(), pts_[m][i].pairs.end(),
                                     [&](const PairFit& p) { return p.pair == name; });
        if (it == pts_[m][i].pairs.end()) continue;
        pairs.push_back(&*it);
        break;
      }
    const std::vector<Finding> start = fs;
    ParameterSigmas sigmas;
    refine(r_, fs, group, pairs, 1, &sigmas);
    for (size_t i : group) refit_if_stuck(m, i, start, fs, sigmas);
    for (size_t i : group)
      for (const Compared& c : params_[i]) {
        const double v = fs[i].parameters.at(c.key);
        const auto s = sigmas.find({i, c.key});
        const double sg = s == sigmas.end() ? INFINITY : s->second;
        at_[i][m].values.push_back(v);
        at_[i][m].intervals.push_back(
            c.log ? std::array<double, 2>{v * std::exp(-sg), v * std::exp(sg)}
                  : std::array<double, 2>{v - sg, v + sg});
      }
    return true;
  }

  // A finding the group's fit left where it started or without a sigma (two findings the data
  // cannot tell apart there make the group's normal equations singular) is fitted alone, the
  // others held, so that one such pair does not cost every finding its comparison.
  void refit_if_stuck(size_t m, size_t i, const std::vector<Finding>& start,
                      std::vector<Finding>& fs, ParameterSigmas& sigmas) {
    const bool stuck = std::any_of(params_[i].begin(), params_[i].end(), [&](const Compared& c) {
      const auto it = sigmas.find({i, c.key});
      return it == sigmas.end() || !std::isfinite(it->second) ||
             fs[i].parameters.at(c.key) == start[i].parameters.at(c.key);
    });
    if (!stuck) return;
    std::vector<Finding> alone = fs;
    std::vector<const PairFit*> own;
    for (const PairFit& p : pts_[m][i].pairs) own.push_back(&p);
    ParameterSigmas s;
    refine(r_, alone, {i}, own, 1, &s);
    fs[i] = alone[i];
    for (const Compared& c : params_[i])
      if (const auto it = s.find({i, c.key}); it != s.end()) sigmas[{i, c.key}] = it->second;
  }

  // Finding i's parameter q by level, apart when a level's value lies beyond kApart sigmas of the
  // fitting measurement's; nullopt when it is not compared at two levels.
  std::optional<LevelDependence> dependence(size_t i, size_t q) const {
    const Compared& c = params_[i][q];
    if (!std::isfinite(c.s_fit)) return std::nullopt;
    LevelDependence ld;
    ld.parameter = c.key;
    ld.apart = false;
    std::vector<double> sigmas = {c.s_fit};
    bool first = true;
    for (size_t m = 0; m < others_.size(); ++m) {
      const AtLevel& a = at_[i][m];
      if (!a.compared) continue;
      const double s_other = half_width(a.intervals[q], a.values[q]);
      if (!std::isfinite(s_other)) continue;
      if (first) {
        ld.levels.push_back(a.level_fit);
        ld.values.push_back(c.v_fit);
        ld.intervals.push_back(r_.findings[i].intervals.at(c.key));
        first = false;
      }
      ld.levels.push_back(a.level_other);
      ld.values.push_back(a.values[q]);
      ld.intervals.push_back(a.intervals[q]);
      sigmas.push_back(s_other);
      if (std::abs(a.values[q] - c.v_fit) > kApart * std::hypot(c.s_fit, s_other)) ld.apart = true;
    }
    if (ld.values.size() < 2) return std::nullopt;
    fit_slope(ld, sigmas);
    return ld;
  }

  DiagnosisRun& r_;
  const size_t nf_;
  std::vector<OtherMeasurement> others_;  // the validation one, then each further level
  std::vector<std::vector<Compared>> params_;
  std::vector<std::vector<AtLevel>> at_;
  std::vector<std::vector<LevelPoints>> pts_;
};

}  // namespace

void level(DiagnosisRun& r) {
  LevelComparison c(r);
  c.fit_all();
  c.mark_dependent();
}

}  // namespace fralab::diag
