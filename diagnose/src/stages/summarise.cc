// Stages 8-9, summarise (docs/method/diagnosis.md, "The stages"): the extended model (the
// simulation with every finding kept), each finding's errors alone and its explanation, the
// findings ordered by what they gain, the errors of simulation and extended model on the fitting
// and validation data, and per pair its chi2 and errors, with what the catalogue leaves
// unexplained said, not forced onto a cause.
#include <algorithm>
#include <cmath>

#include "fralab/core/pair_id.h"
#include "fralab/plant/state_space.h"
#include "stages.h"

namespace fralab::diag {
namespace {

// The report's explanation of a finding: what the residual shows, and what its scope says.
// A moved root of a state model simulation: the mode of A it is and the states that take part
// in it (those with a participation of 5 % or more), "" otherwise.
std::string state_mode(const Model& sim, const Finding& f) {
  if (!sim.state_space) return "";
  const std::optional<Param> key = moved_root_key(f.cause);
  if (!key || !f.parameters.count(*key)) return "";
  const double wn = f.parameters.at(*key);
  const auto z = f.parameters.find(Param::kFromZeta);
  const C s = z == f.parameters.end() || z->second >= 1
                  ? C(-wn, 0)
                  : wn * C(-z->second, std::sqrt(1 - z->second * z->second));
  const auto mp = mode_participation(*sim.state_space, s);
  if (!mp) return "";
  std::string text =
      "; the state model's mode at " + fmt(mp->eigenvalue.real()) +
      (std::abs(mp->eigenvalue.imag()) > 0 ? " +- " + fmt(std::abs(mp->eigenvalue.imag())) + "j"
                                           : std::string()) +
      " rad/s, its states";
  for (const auto& [name, share] : mp->states)
    if (share >= 0.05) text += " " + name + " " + fmt(share);
  return text;
}

std::string explain(const Finding& f) {
  std::string ex = cause_unit(f.cause)->explain(f);
  if (f.scope == Scope::kOutput) ex += "; common to every path into " + f.output + ": its sensor";
  const bool own = f.pairs.size() == 1 && PairId::parse(f.pairs[0]).command &&
                   PairId::parse(f.pairs[0]).input == f.input;
  if (f.scope == Scope::kInput)
    ex += own ? "; in the actuator's own response " + f.pairs[0]
              : "; common to every path from " + f.input + ": its actuator or calibration";
  if (f.scope == Scope::kPlant) ex += "; common to every path: a plant state";
  if (f.level) {
    // Each parameter whose values lie apart: its value per level and its slope (with three levels
    // or more, the line's, with its sigma and as a share of the value per 10 units of level).
    auto said = [&](const LevelDependence& l) {
      auto at = [&](size_t k) {
        return fmt(l.values[k]) + (l.levels[k] > 0 ? " at level " + fmt(l.levels[k])
                                                   : std::string(k ? " on the validation data"
                                                                   : " on the data fitted"));
      };
      std::string s = to_string(l.parameter) + (" " + at(0));
      for (size_t k = 1; k < l.values.size(); ++k) s += ", " + at(k);
      if (std::isfinite(l.slope_sigma))
        s += " (slope " + fmt(l.slope) + " +- " + fmt(l.slope_sigma) + " per unit of level, " +
             fmt(100 * 10 * l.slope / l.values[0]) + " % per 10 units)";
      else if (std::isfinite(l.slope))
        s += " (slope " + fmt(l.slope) + " per unit of level)";
      return s;
    };
    std::string parts = f.level->apart ? said(*f.level) : "";
    for (const LevelDependence& l : f.level_secondary)
      if (l.apart) parts += (parts.empty() ? "" : "; ") + said(l);
    ex += "; level-dependent, not one linear value: " + parts;
  }
  return ex;
}

// The pair's report: the measured, simulated and extended responses, chi2 and the errors of both
// models; an `unexplained` entry when it stays beyond its uncertainty under the extended model.
PairReport pair_report(DiagnosisRun& r, const PairFit& p) {
  const Model& ext = r.d.extended;
  PairReport pr;
  pr.pair = p.pair;
  pr.w = p.w;
  pr.meas = p.meas;
  pr.sim = p.sim;
  for (size_t q = 0; q < p.w.size(); ++q) {
    pr.ext.push_back(
        model_pair_response(ext, p.pair, p.w[q], p.amp[q], r.opt.chain, p.ms).value_or(0.0));
    pr.sigma.push_back(p.sig[q]);
    pr.chi2_sim += std::norm(p.meas[q] - p.sim[q]) / (p.sig[q] * p.sig[q]);
    pr.chi2_ext += std::norm(p.meas[q] - pr.ext.back()) / (p.sig[q] * p.sig[q]);
  }
  pr.beyond = pr.chi2_sim > p.w.size() + 4 * std::sqrt(double(p.w.size()));
  pr.error_sim =
      pair_error(p.w, p.meas, [&](double, size_t i) { return std::optional<C>(p.sim[i]); });
  pr.error_ext =
      pair_error(p.w, p.meas, [&](double, size_t i) { return std::optional<C>(pr.ext[i]); });
  // What the catalogue does not explain is said, not forced.
  const double n = double(p.w.size());
  if (pr.chi2_ext > n + 4 * std::sqrt(n)) {
    Unexplained u;
    u.pair = p.pair;
    double lo = INFINITY, hi = 0;
    for (size_t q = 0; q < p.w.size(); ++q) {
      const double z = std::abs(p.meas[q] - pr.ext[q]) / p.sig[q];
      if (z < 3) continue;
      lo = std::min(lo, p.w[q] / (2 * M_PI));
      hi = std::max(hi, p.w[q] / (2 * M_PI));
      u.residual = std::max(u.residual, std::abs(std::log(p.meas[q] / pr.ext[q])));
    }
    u.band_hz = {std::isfinite(lo) ? lo : 0.0, hi};
    u.chi2 = pr.chi2_ext;
    for (const auto& [k, why] : r.refused)
      if (r.pairs[k].pair == p.pair) u.explanation = why;
    if (u.explanation.empty())
      u.explanation = "no cause of the catalogue lowers chi2 enough to be accepted";
    r.d.unexplained.push_back(u);
  }
  return pr;
}

}  // namespace

void summarise(DiagnosisRun& r) {
  Diagnosis& d = r.d;
  std::vector<Finding>& findings = r.findings;
  bool have_val = false;
  for (const auto& mp : r.data) have_val |= !mp.validation.points.empty();
  for (auto& f : findings) cause_unit(f.cause)->settle(f);
  for (auto& x : d.dropped) cause_unit(x.finding.cause)->settle(x.finding);
  d.extended = extended_by(r, findings, findings.size());
  for (auto& f : findings) {
    Model one = r.sim;  // the simulation plus this finding alone
    cause_unit(f.cause)->apply(one, f);
    f.error_before = error_over(r, r.sim, f.pairs, false);
    f.error_after = error_over(r, one, f.pairs, false);
    if (f.explanation.empty()) f.explanation = explain(f) + state_mode(r.sim, f);
  }
  for (auto& x : d.dropped)
    if (x.finding.explanation.empty()) x.finding.explanation = explain(x.finding);
  std::sort(findings.begin(), findings.end(), [](const Finding& a, const Finding& b) {
    return a.error_before - a.error_after > b.error_before - b.error_after;
  });
  d.findings = findings;
  d.error_before = error_over(r, r.sim, {}, false);
  d.error_after = error_over(r, d.extended, {}, false);
  if (have_val) {
    d.validation_before = error_over(r, r.sim, {}, true);
    d.validation_after = error_over(r, d.extended, {}, true);
  }
  for (const auto& p : r.original) d.pairs.push_back(pair_report(r, p));
}

}  // namespace fralab::diag
