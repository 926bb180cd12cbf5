// Diagnosis (docs/formats.md §6, the method in docs/method/diagnosis.md): where a simulation is
// wrong, why, and what the extended model gains.
//
// For every measured pair, the residual R(w) = G_meas(jw) / G_sim(jw) with the uncertainty
// sigma_R = sigma_eff / |G_sim|, sigma_eff^2 = sigma^2 + ((sigma_floor + aliasing_floor (w h)^2)
// |G_meas|)^2 for a chain sampled at 1/h; points with sigma > max_rel_sigma |G| are left out. A
// pair is beyond its uncertainty when chi2 = sum |G_meas - G_sim|^2 / sigma_eff^2 > N + 4 sqrt(N).
// Error metric (summary.metric): rms over points of |ln(G_model / G_meas)|, nepers and radians.
//
// The catalogue, each a factor F(s; theta) on the simulated response (s = jw, w in rad/s; one unit
// per cause in diagnose/src/causes/, its search range in DiagnoseOptions; the parameters' keys in
// parameter.h):
//   time_delay          F = e^{-s tau}                           delay_s
//   missing_lag         F = 1 / (1 + s/a)                        corner_rad_s = a
//   missing_lead        F = 1 + s/a                              corner_rad_s = a
//   missing_resonance   F = 1 / (s^2/wn^2 + 2 zeta s/wn + 1)     wn_rad_s, zeta
//                       (a notch: the inverse)
//   pole_shift          F = D_from(s) / D_to(s), a simulated pole or pair moved
//                                                            from_rad_s, to_rad_s; a pair also
//                                                            from_zeta, to_zeta, zeta = to_zeta
//   damping_error       F = D_sim(s) / D(s; wn, to_zeta)         wn_rad_s, from_zeta, to_zeta
//   sign_error          F = -1                                   sign = -1
//   gain_mismatch       F = k                                    gain_db = 20 log10 k
//   hysteresis/deadband the actuator's describing function at the measured amplitude, or its best
//                       linear approximation under a multisine    width (input units)
//   missing_path        the path fitted where the simulation has none   gain, delay_s, poles, zeros
//   measurement_coupling  the position channel X records X + g O   channel, coupled_to, gain
// A finding is kept when its cause lowers chi2 by more than its BIC penalty and min_improvement,
// its primary parameter is resolved by the data (a 1-sigma interval, the simulation's value
// outside it), and it earns its place (on the validation data when there is some); scope, the
// stages and their figures: docs/method/diagnosis.md, "The stages".
#pragma once

#include <array>
#include <cmath>
#include <complex>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/core/measurement_chain.h"
#include "fralab/diagnose/parameter.h"
#include "fralab/plant/model.h"
#include "fralab/plant/nonlinearity.h"

namespace fralab {

/// The catalogue (docs/formats.md §6 names at the JSON edge: to_string / cause_from_string).
enum class CauseKind {
  kTimeDelay,
  kMissingLag,
  kMissingLead,
  kMissingResonance,
  kPoleShift,
  kGainMismatch,
  kHysteresis,
  kDeadband,
  kMeasurementCoupling,
  kDampingError,
  kSignError,
  kMissingPath,
  kStateParameter,
};
/// Where a finding sits: one path, every path into an output (its sensor), every path from an
/// input (its actuator or calibration), every path (the plant).
enum class Scope { kPath, kOutput, kInput, kPlant };

const char* to_string(CauseKind c);
const char* to_string(Scope s);
/// InputError naming the text when it is not a name of docs/formats.md §6.
CauseKind cause_from_string(const std::string& s);
Scope scope_from_string(const std::string& s);

struct DiagnoseOptions {
  double sigma_floor = 2e-3;  // relative accuracy floor of measurement and simulation
  // ... plus this times (w h)^2, h = 1 / chain.sample_rate_hz: the chain's first-order model
  // leaves out the hold's aliased images, whose share grows as (w h)^2 (the J85 emulator: 3-4 % in
  // IGV:P3 at w h = 0.6, stepped sine and multisine alike).
  double aliasing_floor = 0.1;
  double min_improvement = 0.25;  // a cause must remove at least this fraction of chi2
  int max_causes_per_path = 2;
  double max_rel_sigma = 0.3;  // points measured worse than this (sigma / |G|) are not used
  // Search ranges.
  double delay_min_s = -0.02;  // time_delay searched over [delay_min_s, delay_max_s], s
  double delay_max_s = 0.2;
  double corner_decades_beyond = 1;  // lag/lead corners: the band widened by this many decades
  double pole_shift_range = 30;      // a pole moves within [from / range, from * range]
  // Scope: the same cause on several paths is one effect when the parameters agree within these.
  double consistent_delay_s = 0.5e-3;  // delays: within max(consistent_delay_s, consistent_rel)
  double consistent_gain_db = 0.3;     // gains, dB
  double consistent_rel = 0.1;         // corners and frequencies (and delays, relative)
  // Nonlinear actuators: the width is fitted below this fraction of the simulated actuator's
  // slowest corner, when the mean 3rd harmonic there exceeds min_odd_harmonic.
  double low_corner_fraction = 0.3;
  double min_odd_harmonic = 0.01;
  // The lab's measurement chain (core/measurement_chain.h): the simulation is compared as the lab
  // would have measured it. Ideal (sample_rate_hz 0) unless the measurement recorded one.
  MeasurementChain chain;
  void validate() const;
};

/// How an input was excited by a multisine, from its measured actuator curve (or another curve of
/// the input): its lines w (rad/s, every valid point's, usable or not) and the command amplitude on
/// each (FrdPoint::line_amplitude); `k` the lines as harmonic numbers of one period. The best
/// linear approximations of the input's nonlinearities computed from it are kept (not thread-safe).
struct MultisineExcitation {
  std::vector<double> w, amplitude;
  std::vector<int> k;
  int realisations = 16;  // random-phase periods multisine_bla averages
  /// The element `spec` under this multisine with each line's amplitude scaled by gain[j] (the
  /// actuator before it): the BLA per line, and one realisation's scatter (var_nl).
  const MultisineBla& bla(const NonlinearitySpec& spec, const std::vector<double>& gain) const;
  mutable std::map<std::tuple<NonlinearityKind, double, std::vector<double>>, MultisineBla> cache;
};
/// From a curve's valid points with line_amplitude > 0 (k: w over the largest w0 / m, m <= 1000,
/// that makes every line a whole harmonic within 1e-6); nullopt for fewer than 2 such points, or
/// lines no such period holds within kMaxMultisineLine harmonics (such a curve is taken as sines').
std::optional<MultisineExcitation> multisine_excitation(const Frd& curve);

/// The pair measured at a further excitation level (`fralab diagnose --levels`), beside the
/// fitting and validation measurements: stage 7b refits each finding there. level: in the user's
/// unit (a force rms in N, an amplitude); 0: the points' median excitation amplitude (peak, input
/// units).
struct LevelCurve {
  double level = 0;
  Frd frd;  // may be empty (the pair not measured at that level)
};

struct MeasuredPair {
  std::string pair;  // "X:O" (position-relative) or "u_X:X" (actuator)
  Frd frd;           // the measurement used for fitting
  Frd validation;    // an independent measurement (other seed or amplitude); may be empty
  double level = 0;  // frd's level, as LevelCurve::level (0: from its points)
  /// levels[k] of every pair is the k-th further measurement (the same length for every pair).
  std::vector<LevelCurve> levels;
};

/// A finding whose parameter differs between excitation levels beyond its sigmas (the fitting
/// measurement, the validation one and any further levels, stage 7b): not one linear cause.
/// levels: each measurement's level (LevelCurve::level; 0 unknown), the fitting one first, then
/// the validation one, then the further levels in their order; values and 1-sigma intervals of the
/// parameter at each. slope: d value / d level, the two values' difference over the levels' for
/// two levels, the weighted least-squares line (weights 1 / sigma^2) for three or more; NaN when a
/// level is unknown. slope_sigma: the line's slope's 1-sigma (scaled by sqrt(chi2 / dof) when the
/// line misfits beyond the sigmas), NaN for two levels. apart: the values lie apart beyond
/// kApart (3) sigmas combined.
struct LevelDependence {
  Param parameter = Param::kToRadS;
  std::vector<double> levels, values;
  std::vector<std::array<double, 2>> intervals;
  double slope = 0;
  double slope_sigma = NAN;
  bool apart = true;
};

struct Finding {
  CauseKind cause = CauseKind::kGainMismatch;
  Scope scope = Scope::kPath;
  std::string output, input;  // "" = null
  Parameters parameters;
  std::map<std::string, std::string> text_parameters;  // measurement_coupling's channel names
  std::string explanation;
  double error_before = 0, error_after = 0;
  std::vector<std::string> pairs;  // the measured pairs it explains
  /// The primary parameter's 1-sigma interval from the data (see "resolved" in the file
  /// comment): {lo, hi}, +-inf where chi2 never rises enough within the search range.
  std::map<Param, std::array<double, 2>> intervals;
  /// missing_path: the path fitted (the extended model's new path; its gain follows
  /// parameters[Param::kGain]).
  std::optional<Tf> tf;
  /// Set when the primary parameter, or a fitted secondary one (a moved mode's damping), depends
  /// on the level (see LevelDependence): `level` is the primary's, `level_secondary` the fitted
  /// secondaries' at the same levels.
  std::optional<LevelDependence> level;
  std::vector<LevelDependence> level_secondary;

  /// Whether the finding is its numeric parameters alone: no whole path (tf) and no text
  /// parameter (a mode shape's form, a state model's entry, a coupled channel). Only such
  /// findings of one cause add, group and fold by value.
  bool by_value() const { return !tf && text_parameters.empty(); }
};

/// "cause [scope input output]" (the empty ones left out): a finding's kind and place as the
/// terminal's lines name it.
std::string finding_label(const Finding& f);

struct PairReport {  // per pair, for the report
  std::string pair;
  std::vector<double> w;
  std::vector<std::complex<double>> meas, sim, ext;
  std::vector<double> sigma;
  double chi2_sim = 0, chi2_ext = 0;
  bool beyond = false;
  double error_sim = 0, error_ext = 0;
};

/// A finding fitted but not reported: not resolved by the data, or it did not earn its place (on
/// the validation measurement, or without one on the data fitted).
struct DroppedFinding {
  Finding finding;
  std::string reason;
};

/// A pair still beyond its uncertainty under the extended model: the band where its points lie
/// beyond 3 sigma, the largest |ln(measured/model)| there, and why no cause was accepted.
struct Unexplained {
  std::string pair;
  std::array<double, 2> band_hz{0, 0};
  double residual = 0;
  double chi2 = 0;
  std::string explanation;
};

/// Another set of a state model simulation's entries that fits the data as well as the set stage
/// 3a names: as many entries, its chi2 above the named set's by no more than one parameter's
/// ln 2N in units of the misfit level (the stage's criterion cannot tell the two apart).
struct StateAlternative {
  std::vector<Finding> findings;  // each entry as stage 3a names it, value as fitted there
  double chi2_above = 0;          // its chi2 minus the named set's, in units of the misfit level
};

struct Diagnosis {
  MeasurementChain chain;  // what the comparison used
  std::vector<DroppedFinding> dropped;
  std::vector<Unexplained> unexplained;
  std::vector<Finding> findings;
  std::vector<StateAlternative> state_alternatives;  // stage 3a's, when its findings are kept
  Model extended;
  std::vector<PairReport> pairs;
  double error_before = 0, error_after = 0;
  double validation_before = -1, validation_after = -1;
  std::string metric = "rms over points of |ln(G_model/G_measured)| (nepers and radians combined)";
};

/// The diagnosis of `data` against `simulation` (docs/method/diagnosis.md, "The stages"). Where
/// the simulation is a state model and stage 3a names entries of it, the diagnosis by the paths
/// alone (stage 3a left out) is made too, and kept instead only when its chi2 plus ln 2N per
/// fitted parameter is lower by more than one parameter's ln 2N.
Diagnosis diagnose(const Model& simulation, const std::vector<MeasuredPair>& data,
                   const DiagnoseOptions& opt = {});

/// The diagnosis' error metric (Diagnosis::metric) of model `m` on the fitting measurement of
/// `data`, over the pairs the simulation `sim` has a path for (those diagnosis.json's
/// error_before counts), restricted to `which` when not empty; through opt.chain, each point at its
/// own amplitude or multisine. diagnose(sim, data, opt).error_before equals model_error(sim, sim,
/// data, opt) and its error_after model_error(d.extended, sim, data, opt). A pair `m` has no
/// response for errs by 1 there; -1 when no point counts.
double model_error(const Model& m, const Model& sim, const std::vector<MeasuredPair>& data,
                   const DiagnoseOptions& opt = {}, const std::vector<std::string>& which = {});

/// A finding as diagnosis.json writes it (docs/formats.md §6: cause, scope, input, output,
/// parameters, pairs, a missing path's tf, and the 1-sigma intervals when present, null an
/// unbounded side); InputError naming `where` and the key.
Finding finding_from_json(const Json& j, const JsonWhere& where);
/// Every finding of a diagnosis.json read from `file` (its "findings", each as finding_from_json).
std::vector<Finding> findings_from_json(const Json& diagnosis, const std::string& file);

/// The simulation extended by the findings, each as its cause extends a model (the diagnosis'
/// own extended model is extend_model(sim, d.findings)).
Model extend_model(const Model& sim, const std::vector<Finding>& findings);

/// fralab-diagnosis/1 JSON (docs/formats.md §6).
Json diagnosis_to_json(const Diagnosis& d);

/// The model's response for a measured pair ("X:O" position -> output, "u_X:X" the actuator's
/// linear response, "u_X:O" command -> output); nullopt when the model has no such path.
/// Measured through `chain`: times chain.pair_factor(E1, w). An actuator nonlinearity enters as
/// measured: its describing function at the command `amplitude` (a sine), or, given the input's
/// multisine `ms` (w one of its lines), its best linear approximation under that multisine.
std::optional<std::complex<double>> model_pair_response(const Model& m, const std::string& pair,
                                                        double w, double amplitude = 0.0,
                                                        const MeasurementChain& chain = {},
                                                        const MultisineExcitation* ms = nullptr);

}  // namespace fralab
