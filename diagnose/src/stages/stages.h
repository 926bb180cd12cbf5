// Internal to the diagnosis: the state diagnose() passes from stage to stage, and the stages, one
// file each in this folder, in the order docs/method/diagnosis.md ("The stages") describes them:
// prepare the pairs, fit the causes, scope, size together, regroup, the additive causes, the
// simpler alternatives, resolve, earn their place, level, summarise. Frequencies rad/s, s = jw.
#pragma once

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "../causes/cause.h"
#include "../pair_fit.h"
#include "fralab/diagnose/diagnose.h"

namespace fralab::diag {

/// A cause fitted on one pair (an index into DiagnosisRun::pairs), before scope groups it.
struct PairCause {
  size_t pair;
  Cause c;
};

/// Everything one diagnosis carries between its stages. It holds the multisines the pairs point
/// into, so it is neither copied nor moved.
struct DiagnosisRun {
  DiagnosisRun(const Model& sim, const std::vector<MeasuredPair>& data, const DiagnoseOptions& opt)
      : sim(sim), data(data), opt(opt) {}
  DiagnosisRun(const DiagnosisRun&) = delete;
  DiagnosisRun& operator=(const DiagnosisRun&) = delete;

  const Model& sim;
  const std::vector<MeasuredPair>& data;
  const DiagnoseOptions& opt;

  // prepare: per input excited by a multisine, its lines on the fitting (ms_fit) and the
  // validation (ms_val) measurement.
  std::map<std::string, MultisineExcitation> ms_fit, ms_val;
  // prepare: the same for each further level (MeasuredPair::levels[k]).
  std::vector<std::map<std::string, MultisineExcitation>> ms_levels;
  // prepare: the pairs the simulation can speak to (fit_causes extends their factor, and a
  // multisine actuator curve's sigma_eff), those it has no path for, and `pairs` as prepared
  // (fit_causes then copies the final sigma_eff into it; every later chi2 weighs by it).
  std::vector<PairFit> pairs, absent, original;

  // fit_causes: the causes found per pair, the findings fitted jointly over several pairs
  // (measurement coupling, then missing paths), and per pair the best candidate refused and why.
  std::vector<PairCause> raw;
  std::vector<Finding> coupling_findings, path_findings;
  // states: the state model's entries moved over every pair (a state model simulation only).
  std::vector<Finding> state_findings;
  // modes: the modes moved over every pair of their scope before any pair is diagnosed alone.
  std::vector<Finding> mode_findings;
  std::map<size_t, std::string> refused;

  // scope onward: the findings still standing.
  std::vector<Finding> findings;

  // What diagnose() returns: resolve and earn_place add what they drop, summarise the rest.
  Diagnosis d;
};

/// The multisine a point of `pair` was measured by (nullptr: a sine).
const MultisineExcitation* multisine_of(const DiagnosisRun& r, const std::string& pair,
                                        double line_amplitude, bool validation);

/// The simulation extended by every finding of `fs` but the one at `skip` (fs.size(): all).
Model extended_by(const DiagnosisRun& r, const std::vector<Finding>& fs, size_t skip);

/// The error metric of model m over the measured pairs `which` (all when empty), on the fitting or
/// the validation measurement; -1 when no point counts.
double error_over(const DiagnosisRun& r, const Model& m, const std::vector<std::string>& which,
                  bool validation);

/// The fitting data's pairs (r.original, then r.absent) named in `which`, in that order.
std::vector<const PairFit*> fitted_pairs(const DiagnosisRun& r,
                                         const std::vector<std::string>& which);

/// The points of `pairs`, N.
size_t points_of(const std::vector<const PairFit*>& pairs);
/// One parameter's BIC penalty over `pairs`: ln 2N (N at least 1).
double bic_penalty(const std::vector<const PairFit*>& pairs);
/// No pair of `which` has its chi2 raised by more than its own bic_penalty going from the findings
/// `before` to `after`.
bool quiet_over(const DiagnosisRun& r, const std::vector<Finding>& before,
                const std::vector<Finding>& after, const std::vector<std::string>& which);

/// The parameter naming the simulated root a cause moves or re-damps (rad/s): a pole shift's
/// from_rad_s, a damping error's wn_rad_s; nullopt for the other causes.
inline std::optional<Param> moved_root_key(CauseKind cause) {
  if (cause == CauseKind::kPoleShift) return Param::kFromRadS;
  if (cause == CauseKind::kDampingError) return Param::kWnRadS;
  return std::nullopt;
}

/// chi2 of model m over the points of `pairs`: the sum of |G_meas - G_m|^2 / sigma_eff^2, each
/// point at its own amplitude or multisine, through the lab's chain.
double chi2_of(const DiagnosisRun& r, const Model& m, const std::vector<const PairFit*>& pairs);

/// Appends to p the usable points of `curve` (its pair's fitting or validation measurement), each
/// with the simulation's response there and the multisine it was measured by; a point where the
/// simulation gives no response, or zero, is left out.
void add_points(const DiagnosisRun& r, PairFit& p, const Frd& curve, bool validation);
/// The same with the multisines of the measurement `curve` belongs to (ms_fit, ms_val or one of
/// ms_levels).
void add_points(const DiagnosisRun& r, PairFit& p, const Frd& curve,
                const std::map<std::string, MultisineExcitation>& multisines);

/// The error metric of one pair under a response function (no response: the point counts as 0).
double pair_error(const std::vector<double>& w, const std::vector<C>& meas,
                  const std::function<std::optional<C>(double, size_t)>& model);

/// The 1-sigma interval of a parameter: where g(v) = chi2(v) - (chi2_min + s) crosses zero on
/// each side of the fitted value v0 (g(v0) < 0). The bracket starts 1e-3 |v0| (or the domain's
/// floor, in the parameter's units) away and doubles, at most 60 times; the crossing is found by
/// TOMS 748. A positive domain (corners, frequencies, widths) stays positive. +-inf when g never
/// turns positive.
std::array<double, 2> parameter_interval(const std::function<double(double)>& g, double v0,
                                         const IntervalDomain& domain);

// The stages (docs/method/diagnosis.md, "The stages").
/// 1. The usable points of every pair against the simulation, and the multisines.
void prepare(DiagnosisRun& r);
/// The criterion of stages 3a and 3b: by how much the drop of chi2 from c0 to c, over n points,
/// exceeds k penalties ln 2n, in units of the misfit level s = max(1, c / n) (> 0: the move
/// earns its place).
double earned(double c0, double c, size_t n, int k);
/// 3a. Where the simulation is a state model, its entries (A, B, C) moved over every pair
/// (states.cc).
void states(DiagnosisRun& r);
/// 3b. A lightly damped pair every path of a scope holds is moved once over all those pairs, the
/// modes one after the other while each earns its place; each pair's factor then holds them
/// (modes.cc).
void modes(DiagnosisRun& r);
/// 2-4. The measurement coupling per input, the paths the simulation lacks, then per pair a
/// nonlinear actuator and up to max_causes_per_path linear causes.
void fit_causes(DiagnosisRun& r);
/// 5. Consistent fits of one cause over every path into an output, from an input, or everywhere
/// become one finding there; the rest stay with their path (scope.cc).
void scope(DiagnosisRun& r);
/// Whether two fits on different pairs are one effect: the same cause and shape, the same
/// parameters present, and the cause's own tolerance (scope.cc).
bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt);
/// 5b. Findings that share pairs get their primary parameters refined together, every finding in
/// place; the state model's entries (of_the_state_model) get their 1-sigma intervals there, the
/// others free (joint.cc).
void joint(DiagnosisRun& r);
/// Whether f is one of stage 3a's: an entry or named parameter of the state model, or a state or
/// delay it lacks (a missing_lag naming its `state`, a time_delay naming its `delay`).
bool of_the_state_model(const Finding& f);
/// The parameters of the findings fs[group] (each primary one, and those besides it the data
/// resolve) refined together by Levenberg-Marquardt on chi2 over `pairs`, every other finding of
/// fs in place; left as they were when that does not lower chi2 or there are fewer than
/// min_params (joint.cc). With `sigmas`: each parameter's linearised 1-sigma at the end, keyed
/// (finding, parameter key): where chi2 rises by max(1, chi2 per point) as in stage 6's
/// intervals, the others free: sqrt(diag((J^T J)^-1) max(1, chi2 per point)), J the weighted
/// residuals' Jacobian there; for a parameter fitted in its logarithm (a positive scale) the
/// sigma of its logarithm.
using ParameterSigmas = std::map<std::pair<size_t, Param>, double>;
void refine(DiagnosisRun& r, std::vector<Finding>& fs, const std::vector<size_t>& group,
            const std::vector<const PairFit*>& pairs, size_t min_params,
            ParameterSigmas* sigmas = nullptr);
/// 5c. After 5b, path findings of one cause now consistent over every pair of a scope (the plant,
/// an output, an input) become one finding there; true when any did (regroup.cc).
bool regroup(DiagnosisRun& r);
/// 5c's last steps: two delays or two gains at one place (scope, input, output, pairs) joined as
/// their sum; true when any were (one_per_place.cc).
bool one_per_place(std::vector<Finding>& fs);
/// 5c's last steps: a pole shift or damping error that moves a root another finding at its place
/// added or moved folded into that finding; true when any was (one_per_place.cc).
bool moved_roots_folded(DiagnosisRun& r);
/// 5d. A gain or a delay at an input and another at an output add up on the path between them:
/// the findings of each additive cause are explained by the fewest inputs' and outputs' values
/// (and paths' residuals) when that is fewer findings (as many, for delays that were all paths');
/// true when any were (calibration.cc).
bool decompose(DiagnosisRun& r);
/// 5e. A missing resonance that a delay, a lag, or a lag and a delay together fit over its pairs
/// with a lower BIC is replaced by that; true when any was (alternatives.cc).
bool simpler_alternatives(DiagnosisRun& r);
/// 6. Each finding's primary parameter gets its 1-sigma interval; the unresolved are dropped.
void resolve(DiagnosisRun& r);
/// 7. On the validation measurement, the findings that do not lower its error are dropped.
void earn_place(DiagnosisRun& r);
/// 7b. With a validation measurement at another level, the findings whose parameter differs
/// there beyond its sigmas are marked level-dependent (level.cc).
void level(DiagnosisRun& r);
/// 8-9. The extended model, the errors, each finding's explanation, and the per-pair report.
void summarise(DiagnosisRun& r);

}  // namespace fralab::diag
