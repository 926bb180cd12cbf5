// Stage 6, resolved by the data (docs/method/diagnosis.md, "The stages"): each finding's primary
// parameter (its cause's unit names it) gets a 1-sigma interval, where chi2 over the finding's
// pairs, every other finding in place and this parameter alone moved, rises by
// s = max(1, chi2_min / N) above its minimum (and so each other parameter its cause reports, as a
// moved pair's damping; the state model's entries keep the intervals stage 5b gave them, the set's
// other entries free); a finding whose simulated value (or absence) does
// not raise chi2 by more than 4s (that value within two sigma) is dropped, said why; so are a lag
// and a lead at one place that cancel each other.
#include <algorithm>
#include <array>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <functional>

#include "stages.h"

namespace fralab::diag {

std::array<double, 2> parameter_interval(const std::function<double(double)>& g, double v0,
                                         const IntervalDomain& domain) {
  const bool positive = domain.positive;
  const double floor = domain.floor;
  std::array<double, 2> out{-INFINITY, INFINITY};
  for (int side = 0; side < 2; ++side) {
    const double dir = side ? 1.0 : -1.0;
    double step = std::max(1e-3 * std::abs(v0), floor);
    double inner = v0, outer = v0;
    bool found = false;
    for (int k = 0; k < 60; ++k) {
      outer = v0 + dir * step;
      if (positive && outer <= 0) outer = v0 * std::pow(0.5, k + 1);  // toward 0, never at it
      if (g(outer) > 0) {
        found = true;
        break;
      }
      inner = outer;
      step *= 2;
    }
    if (!found) continue;
    boost::uintmax_t iters = 60;
    try {
      const auto r =
          boost::math::tools::toms748_solve(g, std::min(inner, outer), std::max(inner, outer),
                                            boost::math::tools::eps_tolerance<double>(30), iters);
      out[size_t(side)] = 0.5 * (r.first + r.second);
    } catch (const std::exception&) {  // a profile too flat to bracket cleanly: the bracket's edge
      out[size_t(side)] = outer;
    }
  }
  return out;
}

// The chi2 step that counts over n points whose minimum is c_min: s = max(1, c_min / n), the
// minimum's chi2 per point where the model leaves more than the noise.
static double chi2_scale(double c_min, size_t n) {
  return std::max(1.0, c_min / std::max<double>(1.0, double(n)));
}

// A lag and a lead at one place (the same scope, input and output) whose corners are within
// consistent_rel of each other cancel: each alone is resolved (removing one leaves the other),
// but the two together are 1 to within the tolerance. Both are dropped, said why, when removing
// both raises chi2 over their pairs by no more than 2 s (two parameters).
static void drop_cancelling(DiagnosisRun& r) {
  std::vector<Finding>& fs = r.findings;
  for (size_t i = 0; i < fs.size(); ++i)
    for (size_t j = 0; j < fs.size(); ++j) {
      const Finding &lag = fs[i], &lead = fs[j];
      if (lag.cause != CauseKind::kMissingLag || lead.cause != CauseKind::kMissingLead ||
          lag.scope != lead.scope || lag.input != lead.input || lag.output != lead.output)
        continue;
      const double a = lag.parameters.at(Param::kCornerRadS),
                   b = lead.parameters.at(Param::kCornerRadS);
      if (std::abs(a - b) > r.opt.consistent_rel * a) continue;
      const std::vector<const PairFit*> mine = fitted_pairs(r, lag.pairs);
      std::vector<Finding> without;
      for (size_t x = 0; x < fs.size(); ++x)
        if (x != i && x != j) without.push_back(fs[x]);
      const double c_min = chi2_of(r, extended_by(r, fs, fs.size()), mine);
      const double s = chi2_scale(c_min, points_of(mine));
      const double c_without = chi2_of(r, extended_by(r, without, without.size()), mine);
      if (c_without - c_min > 2 * s) continue;
      const std::string why = " beside it (corners " + fmt(a) + " and " + fmt(b) +
                              " rad/s): chi2 over their pairs is " + fmt(c_min) +
                              " with both and " + fmt(c_without) + " without, less than " +
                              fmt(2 * s) + " apart";
      r.d.dropped.push_back({lag, "cancels the missing_lead" + why});
      r.d.dropped.push_back({lead, "cancels the missing_lag" + why});
      fs = std::move(without);
      i = size_t(-1);
      break;
    }
}

// A change is resolved when the simulation's value lies this many sigmas from the finding's.
constexpr double kResolvedSigmas = 2.0;

void resolve(DiagnosisRun& r) {
  drop_cancelling(r);
  std::vector<Finding>& findings = r.findings;
  std::vector<Finding> kept;
  for (size_t i = 0; i < findings.size(); ++i) {
    Finding& f = findings[i];
    // The finding's pairs (the fitting data, sigma_eff as fitted), and chi2 of a model there.
    const std::vector<const PairFit*> mine = fitted_pairs(r, f.pairs);
    auto chi2_of_model = [&](const Model& m) { return chi2_of(r, m, mine); };
    const double c_min = chi2_of_model(extended_by(r, findings, findings.size()));
    const double s = chi2_scale(c_min, points_of(mine));
    const CauseUnit& unit = *cause_unit(f.cause);
    const auto [key, sim_value] = unit.primary_parameter(f);
    double c_sim = 0;
    if (sim_value) {
      std::vector<Finding> moved = findings;
      moved[i].parameters[*key] = *sim_value;
      c_sim = chi2_of_model(extended_by(r, moved, findings.size()));
    } else {
      c_sim = chi2_of_model(extended_by(r, findings, i));  // the simulation lacks it: without it
    }
    // An interval the joint stage gave (the state model's entries, fitted as a set) stands.
    if (key && !f.intervals.count(*key)) {
      auto chi2_at = [&](double v) {
        std::vector<Finding> moved = findings;
        moved[i].parameters[*key] = v;
        return chi2_of_model(extended_by(r, moved, findings.size())) - (c_min + s);
      };
      f.intervals[*key] =
          parameter_interval(chi2_at, f.parameters.at(*key), unit.interval_domain());
    }
    // The other parameters the cause reports an interval for (a moved pair's damping), each moved
    // alone the same way; scales, so positive.
    for (const SecondaryParameter& sp : unit.secondary_parameters(f)) {
      if (!f.parameters.count(sp.key) || f.intervals.count(sp.key)) continue;
      auto chi2_at = [&](double v) {
        std::vector<Finding> moved = findings;
        moved[i].parameters[sp.key] = v;
        return chi2_of_model(extended_by(r, moved, findings.size())) - (c_min + s);
      };
      f.intervals[sp.key] = parameter_interval(chi2_at, f.parameters.at(sp.key), {true, 1e-6});
    }
    // Resolved: the simulation's value lies beyond kResolvedSigmas of the finding's.
    const double apart = kResolvedSigmas * kResolvedSigmas * s;
    if (c_sim - c_min > apart) {
      kept.push_back(f);
      continue;
    }
    // A moved pair whose frequency the data do not resolve but whose damping they do is the
    // pair's damping_error (a joint refit can take a damping change's small frequency move back
    // to the simulated one): judged again as that.
    if (f.cause == CauseKind::kPoleShift && f.parameters.count(Param::kFromZeta) &&
        f.parameters.count(Param::kToZeta)) {
      Finding d = f;
      d.cause = CauseKind::kDampingError;
      d.parameters = {{Param::kWnRadS, f.parameters.at(Param::kFromRadS)},
                      {Param::kFromZeta, f.parameters.at(Param::kFromZeta)},
                      {Param::kToZeta, f.parameters.at(Param::kToZeta)}};
      d.intervals.clear();
      d.explanation.clear();  // said again as a damping_error by summarise
      std::vector<Finding> as_damping = findings;
      as_damping[i] = d;
      const double c_d = chi2_of_model(extended_by(r, as_damping, as_damping.size()));
      as_damping[i].parameters[Param::kToZeta] = f.parameters.at(Param::kFromZeta);
      const double c_none = chi2_of_model(extended_by(r, as_damping, as_damping.size()));
      if (c_d - c_min <= apart && c_none - c_d > apart) {
        f = std::move(d);
        --i;  // this finding again, as a damping_error (unsigned wrap-around at 0 is defined)
        continue;
      }
    }
    std::string why = "not resolved by the data: chi2 over its pairs is " + fmt(c_min) +
                      " with it and " + fmt(c_sim) + " at the simulation's " +
                      (sim_value ? std::string(to_string(*key)) + " = " + fmt(*sim_value)
                                 : std::string("(without it)")) +
                      ", less than " + fmt(apart) + " apart";
    r.d.dropped.push_back({f, why});
  }
  findings = kept;
}

}  // namespace fralab::diag
