// The diagnosis's driver and its public helpers (diagnose.h): the options' checks, the multisine
// of a curve, the model's response on a measured pair, and a model extended by findings.
// diagnose() runs the stages (stages/stages.h, one file each; the method:
// docs/method/diagnosis.md); what is particular to a cause lives in its unit (causes/cause.h).
// The words at the edges are in names.cc, diagnosis.json in diagnosis_json.cc.
#include "fralab/diagnose/diagnose.h"

#include <algorithm>
#include <cmath>

#include "causes/cause.h"
#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"
#include "fralab/plant/nonlinearity.h"
#include "stages/stages.h"

namespace fralab {

using namespace diag;

void DiagnoseOptions::validate() const {
  if (!(sigma_floor >= 0)) throw InputError("diagnose: sigma_floor must be >= 0");
  if (!(aliasing_floor >= 0)) throw InputError("diagnose: aliasing_floor must be >= 0");
  if (!(min_improvement > 0 && min_improvement < 1))
    throw InputError("diagnose: min_improvement must be in (0, 1)");
  if (max_causes_per_path < 1) throw InputError("diagnose: max_causes_per_path must be >= 1");
  if (!(max_rel_sigma > 0)) throw InputError("diagnose: max_rel_sigma must be > 0");
  if (!(delay_min_s < delay_max_s))
    throw InputError("diagnose: delay_min_s must be below delay_max_s");
  if (!(corner_decades_beyond >= 0))
    throw InputError("diagnose: corner_decades_beyond must be >= 0");
  if (!(pole_shift_range > 1)) throw InputError("diagnose: pole_shift_range must be > 1");
  if (!(consistent_delay_s >= 0 && consistent_gain_db >= 0 && consistent_rel >= 0))
    throw InputError("diagnose: consistency tolerances must be >= 0");
  if (!(low_corner_fraction > 0 && low_corner_fraction <= 1))
    throw InputError("diagnose: low_corner_fraction must be in (0, 1]");
  if (!(min_odd_harmonic >= 0)) throw InputError("diagnose: min_odd_harmonic must be >= 0");
}

const MultisineBla& MultisineExcitation::bla(const NonlinearitySpec& spec,
                                             const std::vector<double>& gain) const {
  std::vector<double> a(amplitude.size());
  for (size_t j = 0; j < a.size(); ++j) a[j] = amplitude[j] * (j < gain.size() ? gain[j] : 1.0);
  auto key = std::make_tuple(spec.kind, spec.width, a);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, multisine_bla(spec, k, a, realisations)).first;
  return it->second;
}

std::optional<MultisineExcitation> multisine_excitation(const Frd& curve) {
  std::map<double, double> lines;  // w -> amplitude, ascending, one per line
  for (const FrdPoint& p : curve.points)
    if (p.valid && p.line_amplitude > 0) lines.emplace(p.w, p.line_amplitude);
  if (lines.size() < 2) return std::nullopt;
  MultisineExcitation ms;
  for (const auto& [w, a] : lines) ms.w.push_back(w), ms.amplitude.push_back(a);
  const double w0 = ms.w.front();
  for (int m = 1; m <= 1000; ++m) {
    const double base = w0 / m;
    bool whole = true;
    for (double x : ms.w)
      whole = whole && std::abs(x / base - std::round(x / base)) < 1e-6 * x / base;
    if (!whole) continue;
    if (ms.w.back() / base > kMaxMultisineLine) return std::nullopt;  // beyond what is simulated
    for (double x : ms.w) ms.k.push_back(int(std::lround(x / base)));
    return ms;
  }
  return std::nullopt;
}

std::optional<C> model_pair_response(const Model& m, const std::string& pair, double w,
                                     double amplitude, const MeasurementChain& chain,
                                     const MultisineExcitation* ms) {
  const PairId id = PairId::parse(pair);
  const bool cmd = id.command;
  const std::string& x = id.input;
  const int i = m.input_index(x);
  if (i < 0) return std::nullopt;
  const ModelInput& in = m.inputs[i];
  // The recorded position channel sees its couplings: pos (1 + sum g H_O).
  C coupling = 1.0;
  for (const auto& c : in.measurement_coupling)
    coupling += c.gain * m.position_to_output(m.output_index(c.output), i, w);
  // The actuator's describing function at the command amplitude (linear part first), or its best
  // linear approximation under the multisine.
  C act = m.actuator_response(i, w);
  if (ms && cmd && !in.nonlinearity.empty()) {
    const size_t line = size_t(
        std::min_element(ms->w.begin(), ms->w.end(),
                         [&](double a, double b) { return std::abs(a - w) < std::abs(b - w); }) -
        ms->w.begin());
    std::vector<double> gain;
    for (double x : ms->w) gain.push_back(std::abs(m.actuator_response(i, x)));
    for (const auto& nl : in.nonlinearity)
      if (has_width(nl.kind)) {
        const MultisineBla& b = ms->bla(nl, gain);
        act *= b.g[line];
        for (size_t j = 0; j < gain.size(); ++j) gain[j] *= std::abs(b.g[j]);
      }
  }
  for (const auto& nl : in.nonlinearity) {
    if (amplitude <= 0 || (ms && cmd)) break;
    if (nl.kind == NonlinearityKind::kHysteresis)
      act *= backlash_describing_function(amplitude * std::abs(act), nl.width);
    if (nl.kind == NonlinearityKind::kDeadband)
      act *= deadband_describing_function(amplitude * std::abs(act), nl.width);
  }
  const C held = chain.pair_factor(id, w);  // the lab's hold (measurement_chain.h)
  if (id.output == x) return cmd ? std::optional<C>(act * coupling * held) : std::nullopt;
  const int o = m.output_index(id.output);
  if (o < 0 || !m.path(id.output, x)) return std::nullopt;
  const C h = m.position_to_output(o, i, w);
  return (cmd ? act * h : h / coupling) * held;
}

namespace {

// The stages in order (docs/method/diagnosis.md, "The stages"); stage 3a only with_states.
void run_stages(DiagnosisRun& r, bool with_states) {
  r.d.chain = r.opt.chain;
  r.d.extended = r.sim;
  prepare(r);
  if (with_states) states(r);
  modes(r);
  fit_causes(r);
  scope(r);
  joint(r);
  bool moved = regroup(r);
  moved |= decompose(r);
  moved |= simpler_alternatives(r);
  if (moved) {
    joint(r);
    // What 5d and 5e replaced was fitted pair by pair; sized together, the same cause on every
    // pair of a scope is one finding there, and gains or delays that add up on the paths are
    // their inputs' and outputs'.
    bool again = regroup(r);
    again |= decompose(r);
    if (again) joint(r);
  }
  resolve(r);
  earn_place(r);
  level(r);
  summarise(r);
}

// The fitted parameters of a diagnosis: each finding's primary one and those besides it fitted.
int fitted_parameters(const std::vector<Finding>& fs) {
  int k = 0;
  for (const Finding& f : fs) {
    k += 1;
    for (const SecondaryParameter& sp : cause_unit(f.cause)->secondary_parameters(f))
      k += sp.fitted ? 1 : 0;
  }
  return k;
}

// chi2 of the extended model over every fitted pair and the diagnosis's parameters.
std::pair<double, int> criterion_of(const DiagnosisRun& r) {
  std::vector<const PairFit*> all;
  for (const std::vector<PairFit>* set : {&r.original, &r.absent})
    for (const PairFit& p : *set) all.push_back(&p);
  return {chi2_of(r, r.d.extended, all), fitted_parameters(r.d.findings)};
}

}  // namespace

Diagnosis diagnose(const Model& sim, const std::vector<MeasuredPair>& data,
                   const DiagnoseOptions& opt) {
  opt.validate();
  opt.chain.validate();
  DiagnosisRun r(sim, data, opt);
  run_stages(r, true);
  if (r.state_findings.empty()) return std::move(r.d);
  // The state model's entries against the diagnosis the paths alone give: what a set of entries
  // explains only in part (a change no entry makes, as a pole moved on one path) is better said
  // by the paths' causes. Each is scored by its chi2 plus ln 2N per fitted parameter, in units of
  // the misfit level of the better fit (the states stage's criterion); the paths' diagnosis is
  // kept only when it scores better by more than one parameter's ln 2N, since where both say the
  // same the state model's terms are the owner's.
  DiagnosisRun paths(sim, data, opt);
  run_stages(paths, false);
  const auto [c_states, k_states] = criterion_of(r);
  const auto [c_paths, k_paths] = criterion_of(paths);
  size_t n = 0;
  for (const PairFit& p : r.original) n += p.w.size();
  const double penalty = std::log(2.0 * double(std::max<size_t>(n, 1)));
  const double s = std::max(1.0, std::min(c_states, c_paths) / double(std::max<size_t>(n, 1)));
  const bool states_better =
      c_states / s + k_states * penalty <= c_paths / s + (k_paths + 1) * penalty;
  return std::move(states_better ? r.d : paths.d);
}

Model extend_model(const Model& sim, const std::vector<Finding>& findings) {
  Model m = sim;
  for (const Finding& f : findings) {
    if ((!f.input.empty() && m.input_index(f.input) < 0) ||
        (!f.output.empty() && m.output_index(f.output) < 0))
      throw InputError(std::string(to_string(f.cause)) + " at " + f.input +
                       (f.output.empty() ? "" : " -> " + f.output) + ": " + m.name +
                       " has no such channel");
    diag::cause_unit(f.cause)->apply(m, f);
  }
  return m;
}

}  // namespace fralab
