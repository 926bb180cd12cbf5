// Stages 2-4, fit the causes (docs/method/diagnosis.md, "The stages"): the measurement coupling
// per input and the paths the simulation lacks (fitted jointly over several pairs), then pair by
// pair a nonlinear actuator (hysteresis or deadband, on an actuator curve that shows distortion)
// and up to max_causes_per_path linear causes of the catalogue, each accepted by BIC and by how
// much of chi2 it removes.
#include <algorithm>
#include <cmath>
#include <utility>

#include "../causes/measurement_coupling.h"
#include "../causes/missing_path.h"
#include "../causes/nonlinear.h"
#include "stages.h"

namespace fralab::diag {
namespace {

constexpr int kNlRounds = 8;  // width / linear-cause alternations (converges in 3-5 here)

// The product of the factors of `cs` at each of n points; a gain offset left out when asked.
std::vector<C> product_of(const std::vector<Cause>& cs, size_t n, bool without_gain) {
  std::vector<C> L(n, 1.0);
  for (const Cause& c : cs) {
    if (without_gain && c.cause == CauseKind::kGainMismatch) continue;
    for (size_t q = 0; q < n; ++q) L[q] *= c.F[q];
  }
  return L;
}

// The simulated pole pair a candidate moves or re-damps (its frequency in the simulation; 0: none).
// A pole_shift of a pair fits its damping too, so a pair claimed by one of pole_shift and
// damping_error is not offered to the other on the same measured pair.
double claimed_pair(const Cause& c) {
  if (c.cause == CauseKind::kPoleShift && c.params.count(Param::kFromZeta))
    return c.params.at(Param::kFromRadS);
  if (c.cause == CauseKind::kDampingError) return c.params.at(Param::kWnRadS);
  return 0;
}

// A nonlinear element of one width on a multisine curve, and the linear causes refitted on top.
struct ElementAtWidth {
  double chi2 = INFINITY;
  Cause nl;
  std::vector<Cause> lin;
  std::vector<C> L;  // the product of lin's factors: the actuator as this fit estimates it
};

// The causes of pair k: appended to r.raw, the pair's factor (and a multisine actuator curve's
// sigma_eff) extended by them; the best candidate refused goes to r.refused. An actuator curve
// that shows distortion gets its nonlinear element first, by the multisine's width profile or on
// the sine's low-frequency points, with the linear causes on top; a pair without one gets the
// linear causes alone.
class PairCauseFit {
 public:
  PairCauseFit(DiagnosisRun& r, size_t k)
      : r_(r),
        k_(k),
        p_(r.pairs[k]),
        n_(p_.w.size()),
        base_(p_.factor),
        ones_(n_, 1.0),
        by_multisine_(fits_by_multisine(p_)) {}

  // An actuator curve u_X:X: the only pair where an actuator's nonlinear element shows.
  bool actuator_curve() const { return p_.output.empty(); }
  // The low-frequency points: well below the simulated actuator's slowest corner.
  void find_low_points();
  // A multisine curve that shows distortion: its element by the width's profile, kept (with its
  // linear causes) when it removes enough of chi2. False otherwise, the pair as it was.
  bool multisine_element();
  // A sine curve that shows distortion: its element on the low-frequency points, then alternately
  // with the linear causes; kept (with them) when it removes enough of chi2. False otherwise.
  bool sine_element();
  // The linear causes alone.
  void linear_only() { record(linear_causes()); }

 private:
  // A chi2 beyond the pair's uncertainty: above N + 4 sqrt(N).
  bool beyond(double c) const { return c > n_ + 4 * std::sqrt(double(n_)); }
  std::vector<Cause> linear_causes();
  std::vector<Cause> linear_causes_on(const std::vector<C>& element);

  double median_nl() const;
  ElementAtWidth element_at(CauseKind kind, double width, const std::vector<C>& seed);
  ElementAtWidth width_profile(int pass, CauseKind kept, double before, const std::vector<C>& seed);
  void add_predicted_scatter(CauseKind kind, double width, const std::vector<C>& seed,
                             const std::vector<double>& sig0);

  bool sine_distorts() const;
  std::vector<Cause> alternate(Cause& nl);

  void record(const std::vector<Cause>& lin);
  void record(const Cause& nl, std::string detail, const std::vector<Cause>& lin);

  DiagnosisRun& r_;
  const size_t k_;
  PairFit& p_;
  const size_t n_;             // the pair's points
  const std::vector<C> base_;  // the factor as fit_pair found it: the measurement coupling
  const std::vector<C> ones_;  // no candidate factor
  const bool by_multisine_;    // a multisine curve its multisine's lines describe
  double corner_ = INFINITY;   // the simulated actuator's slowest corner, rad/s
  std::vector<size_t> low_;    // the points below low_corner_fraction of it
  double h3_ = 0;              // the sum of their 3rd harmonics
};

// Up to max_causes_per_path linear causes on top of p.factor (which each one found extends): the
// lowest BIC of the catalogue's fits, accepted when it lowers chi2 enough; the best refused is
// remembered for the report.
std::vector<Cause> PairCauseFit::linear_causes() {
  const DiagnoseOptions& opt = r_.opt;
  std::vector<Cause> found;
  for (int n = 0; n < opt.max_causes_per_path; ++n) {
    const double c0 = chi2(p_, ones_);
    if (!beyond(c0)) break;
    std::vector<Cause> cs;
    for (const LinearCause* unit : linear_catalogue()) unit->fit(r_.sim, p_, opt, &cs);
    const Cause* best = nullptr;
    double best_bic = INFINITY;
    for (const auto& c : cs) {
      bool claimed = false;
      for (const Cause& f : found)
        claimed |= claimed_pair(c) > 0 && claimed_pair(c) == claimed_pair(f);
      if (claimed) continue;
      double bic = c.chi2 + c.k * std::log(2.0 * n_);
      if (bic < best_bic) best_bic = bic, best = &c;
    }
    if (!best) break;
    const double needed = std::max(best->k * std::log(2.0 * n_), opt.min_improvement * c0);
    if (c0 - best->chi2 < needed) {
      r_.refused[k_] = std::string("best candidate ") + to_string(best->cause) +
                       " lowers chi2 only from " + fmt(c0) + " to " + fmt(best->chi2) + " (needs " +
                       fmt(needed) + " less)";
      break;
    }
    found.push_back(*best);
    for (size_t q = 0; q < n_; ++q) p_.factor[q] *= best->F[q];
  }
  return found;
}

// The linear causes on top of a nonlinear element's factor.
std::vector<Cause> PairCauseFit::linear_causes_on(const std::vector<C>& element) {
  for (size_t q = 0; q < n_; ++q) p_.factor[q] = base_[q] * element[q];
  return linear_causes();
}

void PairCauseFit::find_low_points() {
  const Model& sim = r_.sim;
  const int i = sim.input_index(p_.input);
  if (sim.inputs[i].actuator) {
    for (const Root& root : sim.inputs[i].actuator->poles)
      corner_ = std::min(corner_, root.pair ? root.wn : -root.real);
  }
  for (size_t q = 0; q < n_; ++q) {
    if (p_.w[q] < r_.opt.low_corner_fraction * corner_) {
      low_.push_back(q);
      h3_ += p_.h3[q];
    }
  }
}

// A multisine's trigger: the median level on the non-excited lines (nl_rel).
double PairCauseFit::median_nl() const {
  std::vector<double> v = p_.nl;
  std::nth_element(v.begin(), v.begin() + n_ / 2, v.end());
  return v[n_ / 2];
}

// A multisine: the element's BLA depends on every line through the actuator, which the simulation
// may have wrong (the J85's A8: ten times too slow), and a width fitted on the low lines alone is
// not resolved (they pass whole). The width by its profile: at each candidate, the BLA with the
// element's input through the actuator as last estimated (`seed`: the linear causes of the
// previous pass; none at first), then the linear causes refitted on top. Passes repeat with the
// new estimate until the width settles (< 0.5 %).
bool PairCauseFit::multisine_element() {
  if (!by_multisine_) return false;
  const double nl_median = median_nl();
  if (!(nl_median > r_.opt.min_odd_harmonic && p_.amp[0] > 0)) return false;
  std::vector<C> seed(n_, 1.0);
  const std::vector<double> sig0 = p_.sig;
  double c_lin = 0;
  ElementAtWidth best;
  for (int pass = 0; pass < 3 * kNlRounds; ++pass) {
    if (pass > 0) {
      seed = best.L;
      add_predicted_scatter(best.nl.cause, best.nl.params[Param::kWidth], seed, sig0);
    }
    p_.factor = base_;
    linear_causes();
    c_lin = chi2(p_, ones_);  // the linear causes alone
    const double before = pass > 0 ? best.nl.params[Param::kWidth] : 0.0;
    best = width_profile(pass, best.nl.cause, before, seed);
    if (pass > 0 && std::abs(best.nl.params[Param::kWidth] / before - 1) < 5e-3) break;
  }
  if (c_lin - best.chi2 > r_.opt.min_improvement * c_lin) {
    // Refitted at the width found: p.factor as this fit left it.
    best = element_at(best.nl.cause, best.nl.params[Param::kWidth], seed);
    record(best.nl,
           explain_nonlinearity(p_, best.nl, {0}, nl_median, corner_, r_.opt.low_corner_fraction),
           best.lin);
    return true;
  }
  p_.factor = base_;
  p_.sig = sig0;
  return false;
}

// The element of `kind` and `width` through the actuator estimate `seed`, the linear causes
// refitted on top; chi2 with both.
ElementAtWidth PairCauseFit::element_at(CauseKind kind, double width, const std::vector<C>& seed) {
  ElementAtWidth f;
  f.nl = Cause{kind, {{Param::kWidth, width}}, nonlinear_factor(p_, kind, width, seed), 0, 1, ""};
  f.lin = linear_causes_on(f.nl.F);
  f.L = product_of(f.lin, n_, false);
  f.chi2 = f.nl.chi2 = chi2(p_, ones_);
  return f;
}

// One pass of the profile. The first pass searches both elements over the whole range; later ones
// the element found (`kept`), near its width (`before`: it rises pass by pass as the actuator
// estimate speeds up).
ElementAtWidth PairCauseFit::width_profile(int pass, CauseKind kept, double before,
                                           const std::vector<C>& seed) {
  ElementAtWidth best;
  for (CauseKind kind : {CauseKind::kHysteresis, CauseKind::kDeadband}) {
    if (pass > 0 && kind != kept) continue;
    const double a = p_.amp[0];
    const double lo = pass > 0 ? 0.8 * before : 1e-3 * a;
    const double hi = pass > 0 ? std::min(1.9 * a, 3 * before) : 1.9 * a;
    const double width = minimise_1d([&](double x) { return element_at(kind, x, seed).chi2; }, lo,
                                     hi, pass > 0 ? 12 : 24);
    ElementAtWidth f = element_at(kind, width, seed);
    if (f.chi2 < best.chi2) best = f;
  }
  return best;
}

// One realisation's distortion is not noise its periods show: once a width is found, its predicted
// scatter joins sigma_eff on this curve (the linear causes otherwise chase it), and stays for every
// later chi2.
void PairCauseFit::add_predicted_scatter(CauseKind kind, double width, const std::vector<C>& seed,
                                         const std::vector<double>& sig0) {
  std::vector<double> var_nl;
  nonlinear_factor(p_, kind, width, seed, &var_nl);
  for (size_t q = 0; q < n_; ++q)
    if (p_.realisations[q] <= 1)
      p_.sig[q] = std::hypot(sig0[q], std::abs(p_.sim[q] * seed[q]) * std::sqrt(var_nl[q]));
}

// A sine's trigger: the mean 3rd harmonic over the low-frequency points.
bool PairCauseFit::sine_distorts() const {
  return !by_multisine_ && low_.size() >= 2 && h3_ / low_.size() > r_.opt.min_odd_harmonic &&
         p_.amp[low_[0]] > 0;
}

bool PairCauseFit::sine_element() {
  if (!sine_distorts()) return false;
  double c0 = 0;
  Cause nl = fit_nonlinearity(p_, low_, base_, ones_, &c0);
  if (!(std::isfinite(nl.chi2) && c0 - nl.chi2 > r_.opt.min_improvement * c0)) return false;
  const std::vector<Cause> lin = alternate(nl);
  record(nl,
         explain_nonlinearity(p_, nl, low_, h3_ / low_.size(), corner_, r_.opt.low_corner_fraction),
         lin);
  return true;
}

// The simulation's own actuator, still wrong, lags at 0.3 of its corner and biases a width fitted
// against it alone (the J85's A8: 8.3 instead of 9.2, and a spurious -0.4 dB gain): alternate, the
// width with the linear causes in place, then the linear causes again. Each round fits the linear
// causes on the current width; the last one follows a width that moved by less than 0.1 %, or is
// the kNlRounds-th. nl ends as the last width; returns the linear causes on it.
std::vector<Cause> PairCauseFit::alternate(Cause& nl) {
  std::vector<Cause> lin;
  bool settled = false;
  for (int round = 0;; ++round) {
    lin = linear_causes_on(nl.F);
    if (settled || round == kNlRounds - 1) break;
    // A gain offset is left out: at low frequency it trades against the width's gain and would
    // keep itself alive; it must earn its place again against the new width.
    double c0_again = 0;
    Cause again = fit_nonlinearity(p_, low_, base_, product_of(lin, n_, true), &c0_again);
    if (!std::isfinite(again.chi2) || again.cause != nl.cause) break;
    settled = std::abs(again.params[Param::kWidth] / nl.params[Param::kWidth] - 1) < 1e-3;
    nl = again;
  }
  return lin;
}

void PairCauseFit::record(const std::vector<Cause>& lin) {
  for (const Cause& c : lin) r_.raw.push_back({k_, c});
}

// The element with its explanation for the report, then the linear causes on top of it.
void PairCauseFit::record(const Cause& nl, std::string detail, const std::vector<Cause>& lin) {
  r_.raw.push_back({k_, nl});
  r_.raw.back().c.detail = std::move(detail);
  record(lin);
}

// The causes of pair k: an actuator curve's nonlinear element (by a multisine's width profile, or
// on a sine's low-frequency points) with the linear causes on top; failing that, or on any other
// pair, the linear causes alone.
void fit_pair(DiagnosisRun& r, size_t k) {
  PairCauseFit fit(r, k);
  if (fit.actuator_curve()) {
    fit.find_low_points();
    if (fit.multisine_element() || fit.sine_element()) return;
  }
  fit.linear_only();
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
