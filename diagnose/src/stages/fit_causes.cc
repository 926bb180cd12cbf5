// Stages 2-4, fit the causes (docs/method/diagnosis.md, "The stages"): the measurement coupling
// per input and the paths the simulation lacks (fitted jointly over several pairs), then pair by
// pair a nonlinear actuator (hysteresis or deadband, on an actuator curve that shows distortion)
// and up to max_causes_per_path linear causes of the catalogue, each accepted by BIC and by how
// much of chi2 it removes.
#include <algorithm>
#include <cmath>

#include "../causes/measurement_coupling.h"
#include "../causes/missing_path.h"
#include "../causes/nonlinear.h"
#include "stages.h"

namespace fralab::diag {
namespace {

constexpr int kNlRounds = 8;  // width / linear-cause alternations (converges in 3-5 here)

// The causes of pair k: appended to r.raw, the pair's factor (and a multisine actuator curve's
// sigma_eff) extended by them; the best candidate refused goes to r.refused.
void fit_pair(DiagnosisRun& r, size_t k) {
  const Model& sim = r.sim;
  const DiagnoseOptions& opt = r.opt;
  std::vector<PairCause>& raw = r.raw;
  std::map<size_t, std::string>& refused = r.refused;
  PairFit& p = r.pairs[k];
  const size_t N = p.w.size();
  const std::vector<C> base = p.factor;  // the measurement coupling found first
  auto beyond = [&](double c) { return c > N + 4 * std::sqrt(double(N)); };
  // Up to max_causes_per_path linear causes on top of p.factor (which each one found extends).
  auto linear_causes = [&] {
    std::vector<Cause> found;
    for (int n = 0; n < opt.max_causes_per_path; ++n) {
      const double c0 = chi2(p, std::vector<C>(N, 1.0));
      if (!beyond(c0)) break;
      std::vector<Cause> cs;
      for (const LinearCause* unit : linear_catalogue()) unit->fit(sim, p, opt, &cs);
      const Cause* best = nullptr;
      double best_bic = INFINITY;
      for (const auto& c : cs) {
        double bic = c.chi2 + c.k * std::log(2.0 * N);
        if (bic < best_bic) best_bic = bic, best = &c;
      }
      if (!best ||
          c0 - best->chi2 < std::max(best->k * std::log(2.0 * N), opt.min_improvement * c0)) {
        if (best)
          refused[k] = std::string("best candidate ") + to_string(best->cause) +
                       " lowers chi2 only from " + fmt(c0) + " to " + fmt(best->chi2) + " (needs " +
                       fmt(std::max(best->k * std::log(2.0 * N), opt.min_improvement * c0)) +
                       " less)";
        break;
      }
      found.push_back(*best);
      for (size_t q = 0; q < N; ++q) p.factor[q] *= best->F[q];
    }
    return found;
  };
  if (p.output.empty()) {
    // Low-frequency points: well below the simulated actuator's slowest corner.
    const int i = sim.input_index(p.input);
    double corner = INFINITY;
    if (sim.inputs[i].actuator) {
      for (const Root& r : sim.inputs[i].actuator->poles)
        corner = std::min(corner, r.pair ? r.wn : -r.real);
    }
    std::vector<size_t> low;
    double h3 = 0;
    const bool by_multisine = fits_by_multisine(p);
    for (size_t q = 0; q < N; ++q) {
      if (p.w[q] < opt.low_corner_fraction * corner) {
        low.push_back(q);
        h3 += p.h3[q];
      }
    }
    // A multisine's trigger: the median level on the non-excited lines (nl_rel).
    const double nl_median = [&] {
      if (!by_multisine) return 0.0;
      std::vector<double> v = p.nl;
      std::nth_element(v.begin(), v.begin() + N / 2, v.end());
      return v[N / 2];
    }();
    if (by_multisine && nl_median > opt.min_odd_harmonic && p.amp[0] > 0) {
      // A multisine: the element's BLA depends on every line through the actuator, which the
      // simulation may have wrong (the J85's A8: ten times too slow), and a width fitted on the
      // low lines alone is not resolved (they pass whole). The width by its profile: at each
      // candidate, the BLA with the element's input through the actuator as last estimated
      // (`seed`: the linear causes of the previous pass; none at first), then the linear causes
      // refitted on top. Passes repeat with the new estimate until the width settles (< 0.5 %).
      struct Fit {
        double chi2 = INFINITY;
        Cause nl;
        std::vector<Cause> lin;
        std::vector<C> L;
      };
      std::vector<C> seed(N, 1.0);
      auto at = [&](CauseKind kind, double width) {
        Fit f;
        f.nl = Cause{kind, {{"width", width}}, nonlinear_factor(p, kind, width, seed), 0, 1, ""};
        for (size_t q = 0; q < N; ++q) p.factor[q] = base[q] * f.nl.F[q];
        f.lin = linear_causes();
        f.L.assign(N, 1.0);
        for (const Cause& c : f.lin)
          for (size_t q = 0; q < N; ++q) f.L[q] *= c.F[q];
        f.chi2 = f.nl.chi2 = chi2(p, std::vector<C>(N, 1.0));
        return f;
      };
      // One realisation's distortion is not noise its periods show: once a width is found, its
      // predicted scatter joins sigma_eff on this curve (the linear causes otherwise chase it).
      const std::vector<double> sig0 = p.sig;
      double c_lin = 0;
      Fit best;
      for (int pass = 0; pass < 3 * kNlRounds; ++pass) {
        if (pass > 0) {
          seed = best.L;
          std::vector<double> var_nl;
          nonlinear_factor(p, best.nl.cause, best.nl.params["width"], seed, &var_nl);
          for (size_t q = 0; q < N; ++q)
            if (p.realisations[q] <= 1)
              p.sig[q] = std::hypot(sig0[q], std::abs(p.sim[q] * seed[q]) * std::sqrt(var_nl[q]));
        }
        p.factor = base;
        linear_causes();
        c_lin = chi2(p, std::vector<C>(N, 1.0));  // the linear causes alone
        const double before = pass > 0 ? best.nl.params["width"] : 0.0;
        const CauseKind kept = best.nl.cause;
        best = Fit{};
        // The first pass searches both elements over the whole range; later ones the element
        // found, near its width (it rises pass by pass as the actuator estimate speeds up).
        for (CauseKind kind : {CauseKind::kHysteresis, CauseKind::kDeadband}) {
          if (pass > 0 && kind != kept) continue;
          const double a = p.amp[0];
          const double lo = pass > 0 ? 0.8 * before : 1e-3 * a;
          const double hi = pass > 0 ? std::min(1.9 * a, 3 * before) : 1.9 * a;
          const double width =
              minimise_1d([&](double x) { return at(kind, x).chi2; }, lo, hi, pass > 0 ? 12 : 24);
          Fit f = at(kind, width);
          if (f.chi2 < best.chi2) best = f;
        }
        if (pass > 0 && std::abs(best.nl.params["width"] / before - 1) < 5e-3) break;
      }
      if (c_lin - best.chi2 > opt.min_improvement * c_lin) {
        best = at(best.nl.cause, best.nl.params["width"]);  // p.factor as this fit left it
        raw.push_back({k, best.nl});
        raw.back().c.detail =
            explain_nonlinearity(p, best.nl, {0}, nl_median, corner, opt.low_corner_fraction);
        for (const Cause& c : best.lin) raw.push_back({k, c});
        return;
      }
      p.factor = base;
      p.sig = sig0;
    }
    double c0 = 0;
    Cause nl;
    if (!by_multisine && low.size() >= 2 && h3 / low.size() > opt.min_odd_harmonic &&
        p.amp[low[0]] > 0)
      nl = fit_nonlinearity(p, low, base, std::vector<C>(N, 1.0), &c0);
    if (std::isfinite(nl.chi2) && c0 - nl.chi2 > opt.min_improvement * c0) {
      // The simulation's own actuator, still wrong, lags at 0.3 of its corner and biases a width
      // fitted against it alone (the J85's A8: 8.3 instead of 9.2, and a spurious -0.4 dB gain):
      // alternate, the width with the linear causes in place, then the linear causes again.
      // Each round fits the linear causes on the current width; the last one follows a width that
      // moved by less than 0.1 %, or is the kNlRounds-th.
      std::vector<Cause> lin;
      bool settled = false;
      for (int round = 0;; ++round) {
        for (size_t q = 0; q < N; ++q) p.factor[q] = base[q] * nl.F[q];
        lin = linear_causes();
        if (settled || round == kNlRounds - 1) break;
        std::vector<C> L(N, 1.0);
        // A gain offset is left out: at low frequency it trades against the width's gain and
        // would keep itself alive; it must earn its place again against the new width.
        for (const Cause& c : lin) {
          if (c.cause == CauseKind::kGainMismatch) continue;
          for (size_t q = 0; q < N; ++q) L[q] *= c.F[q];
        }
        double c0_again = 0;
        Cause again = fit_nonlinearity(p, low, base, L, &c0_again);
        if (!std::isfinite(again.chi2) || again.cause != nl.cause) break;
        settled = std::abs(again.params["width"] / nl.params["width"] - 1) < 1e-3;
        nl = again;
      }
      raw.push_back({k, nl});
      raw.back().c.detail =
          explain_nonlinearity(p, nl, low, h3 / low.size(), corner, opt.low_corner_fraction);
      for (const Cause& c : lin) raw.push_back({k, c});
      return;
    }
  }
  for (const Cause& c : linear_causes()) raw.push_back({k, c});
}

}  // namespace

void fit_causes(DiagnosisRun& r) {
  // Measurement coupling, per input: joint over u_X:X and every X:O.
  for (const auto& in : r.sim.inputs) {
    if (auto f = fit_measurement_coupling(r.sim, in, r.pairs, r.opt))
      r.coupling_findings.push_back(*f);
  }
  // Paths the simulation lacks, where the data respond.
  for (const PairFit& p : r.absent) {
    std::string why;
    if (auto f = fit_missing_path(r.sim, p, r.opt, &why)) r.path_findings.push_back(*f);
  }
  // Per pair: nonlinear actuators first, then up to max_causes_per_path linear causes.
  for (size_t k = 0; k < r.pairs.size(); ++k) fit_pair(r, k);
  // A multisine actuator curve's sigma_eff now holds its element's predicted scatter: every later
  // chi2 (intervals, resolution, the report) weighs it so.
  for (size_t k = 0; k < r.pairs.size(); ++k) r.original[k].sig = r.pairs[k].sig;
}

}  // namespace fralab::diag
