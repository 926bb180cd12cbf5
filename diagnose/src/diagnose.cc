#include "fralab/diagnose/diagnose.h"

#include <algorithm>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <functional>

#include "causes/cause.h"
#include "causes/measurement_coupling.h"
#include "causes/missing_path.h"
#include "causes/nonlinear.h"
#include "fralab/core/numerics.h"
#include "fralab/core/text.h"
#include "fralab/plant/nonlinearity.h"
#include "pair_fit.h"

namespace fralab {

using namespace diag;

namespace {

constexpr std::pair<CauseKind, const char*> kCauseNames[] = {
    {CauseKind::kTimeDelay, "time_delay"},
    {CauseKind::kMissingLag, "missing_lag"},
    {CauseKind::kMissingLead, "missing_lead"},
    {CauseKind::kMissingResonance, "missing_resonance"},
    {CauseKind::kPoleShift, "pole_shift"},
    {CauseKind::kGainMismatch, "gain_mismatch"},
    {CauseKind::kHysteresis, "hysteresis"},
    {CauseKind::kDeadband, "deadband"},
    {CauseKind::kMeasurementCoupling, "measurement_coupling"},
    {CauseKind::kDampingError, "damping_error"},
    {CauseKind::kSignError, "sign_error"},
    {CauseKind::kMissingPath, "missing_path"},
};
constexpr std::pair<Scope, const char*> kScopeNames[] = {{Scope::kPath, "path"},
                                                         {Scope::kOutput, "output"},
                                                         {Scope::kInput, "input"},
                                                         {Scope::kPlant, "plant"}};

bool is_actuator_pair(const std::string& e1, const std::string& e2) { return e1 == "u_" + e2; }

// The error metric for one pair under a response function (no response: the point is skipped).
double pair_error(const std::vector<double>& w, const std::vector<C>& meas,
                  const std::function<std::optional<C>(double, size_t)>& model) {
  std::vector<C> g;
  for (size_t i = 0; i < w.size(); ++i) g.push_back(model(w[i], i).value_or(0.0));
  return detail::rms_log_error(g, meas);
}

// Two fits on different pairs are one effect: the same cause and shape, the same parameters
// present, and the cause's own tolerance.
bool consistent(const Cause& a, const Cause& b, const DiagnoseOptions& opt) {
  if (a.cause != b.cause || a.detail != b.detail) return false;
  for (const auto& [k, v] : a.params)
    if (!b.params.count(k)) return false;
  const LinearCause* unit = linear_cause(a.cause);
  return unit && unit->consistent(a, b, opt);
}

// Extends a model by one finding: the coupling or nonlinearity of its input, the actuator's own tf
// (a finding of the actuator pair u_X:X), the output's sensor, or the paths its scope covers.
void apply_finding(Model& m, const Finding& f) {
  if (f.cause == CauseKind::kMeasurementCoupling) {
    m.inputs[m.input_index(f.input)].measurement_coupling.push_back(
        {f.text_parameters.at("coupled_to"), f.parameters.at("gain")});
    return;
  }
  if (f.cause == CauseKind::kMissingPath) {
    if (m.path(f.output, f.input) || !f.tf) return;
    Tf t = *f.tf;
    t.gain = f.parameters.at("gain");
    m.paths.push_back({f.output, f.input, t, Json::object()});
    return;
  }
  if (f.cause == CauseKind::kHysteresis || f.cause == CauseKind::kDeadband) {
    m.inputs[m.input_index(f.input)].nonlinearity.push_back(
        {to_string(f.cause), f.parameters.at("width")});
    return;
  }
  const LinearCause& unit = *linear_cause(f.cause);
  if (f.scope == Scope::kInput && f.output.empty() && f.pairs.size() == 1 &&
      split_pair(f.pairs[0]).first == "u_" + f.input) {
    ModelInput& in = m.inputs[m.input_index(f.input)];
    if (!in.actuator) in.actuator = Tf{};
    unit.extend(*in.actuator, f);
  } else if (f.scope == Scope::kOutput) {
    ModelOutput& out = m.outputs[m.output_index(f.output)];
    if (!out.sensor) out.sensor = Tf{};
    unit.extend(*out.sensor, f);
  } else {
    for (auto& p : m.paths) {
      if (f.scope == Scope::kPlant || (f.scope == Scope::kInput && p.input == f.input) ||
          (f.scope == Scope::kPath && p.input == f.input && p.output == f.output)) {
        unit.extend(p.tf, f);
      }
    }
  }
}

// The report's explanation of a linear finding: what the residual shows, and what its scope says.
std::string explain(const Finding& f) {
  std::string ex = linear_cause(f.cause)->explain(f);
  if (f.scope == Scope::kOutput) ex += "; common to every path into " + f.output + ": its sensor";
  const bool own = f.pairs.size() == 1 && split_pair(f.pairs[0]).first == "u_" + f.input;
  if (f.scope == Scope::kInput)
    ex += own ? "; in the actuator's own response " + f.pairs[0]
              : "; common to every path from " + f.input + ": its actuator or calibration";
  if (f.scope == Scope::kPlant) ex += "; common to every path: a plant state";
  return ex;
}

// A finding's primary parameter and its value in the simulation (nullopt: the simulation lacks
// what the finding adds, so "the simulation's value" is the finding's absence). "" for a sign
// error (no continuous parameter).
std::pair<std::string, std::optional<double>> primary_parameter(const Finding& f, const Model&) {
  switch (f.cause) {
    case CauseKind::kTimeDelay:
      return {"delay_s", 0.0};
    case CauseKind::kGainMismatch:
      return {"gain_db", 0.0};
    case CauseKind::kPoleShift:
      return {"to_rad_s", f.parameters.at("from_rad_s")};
    case CauseKind::kDampingError:
      return {"to_zeta", f.parameters.at("from_zeta")};
    case CauseKind::kMissingLag:
    case CauseKind::kMissingLead:
      return {"corner_rad_s", std::nullopt};
    case CauseKind::kMissingResonance:
      return {"wn_rad_s", std::nullopt};
    case CauseKind::kHysteresis:
    case CauseKind::kDeadband:
      return {"width", std::nullopt};
    case CauseKind::kMeasurementCoupling:
      return {"gain", 0.0};
    case CauseKind::kSignError:
    case CauseKind::kMissingPath:  // a whole path fitted by TFNS, no one parameter
      return {"", std::nullopt};
  }
  return {"", std::nullopt};
}

// The 1-sigma interval of a parameter: where g(v) = chi2(v) - (chi2_min + s) crosses zero on
// each side of the fitted value v0 (g(v0) < 0). The bracket starts 1e-3 |v0| (or a floor in the
// parameter's units) away and doubles, at most 60 times; the crossing is found by TOMS 748.
// Scale parameters (corners, frequencies, widths) stay positive. +-inf when g never turns
// positive.
std::array<double, 2> parameter_interval(const std::function<double(double)>& g, double v0,
                                         const std::string& key, const DiagnoseOptions&) {
  const bool positive =
      key == "corner_rad_s" || key == "wn_rad_s" || key == "to_rad_s" || key == "width";
  const double floor = key == "delay_s" ? 1e-5 : key == "gain_db" ? 1e-3 : 1e-6;
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

}  // namespace

const char* to_string(CauseKind c) { return enum_word(kCauseNames, c); }

const char* to_string(Scope s) { return enum_word(kScopeNames, s); }

CauseKind cause_from_string(const std::string& s) {
  if (const auto c = enum_from_word(kCauseNames, s)) return *c;
  throw InputError("unknown diagnosis cause '" + s + "'");
}

Scope scope_from_string(const std::string& s) {
  if (const auto k = enum_from_word(kScopeNames, s)) return *k;
  throw InputError("unknown diagnosis scope '" + s + "' (path, output, input or plant)");
}

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
  auto key = std::make_tuple(spec.type, spec.width, a);
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
  auto [e1, e2] = split_pair(pair);
  const bool cmd = e1.rfind("u_", 0) == 0;
  const std::string x = cmd ? e1.substr(2) : e1;
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
      if (nl.type == "hysteresis" || nl.type == "deadband") {
        const MultisineBla& b = ms->bla(nl, gain);
        act *= b.g[line];
        for (size_t j = 0; j < gain.size(); ++j) gain[j] *= std::abs(b.g[j]);
      }
  }
  for (const auto& nl : in.nonlinearity) {
    if (amplitude <= 0 || (ms && cmd)) break;
    if (nl.type == "hysteresis")
      act *= backlash_describing_function(amplitude * std::abs(act), nl.width);
    if (nl.type == "deadband")
      act *= deadband_describing_function(amplitude * std::abs(act), nl.width);
  }
  const C held = chain.pair_factor(e1, w);  // the lab's hold (measurement_chain.h)
  if (e2 == x) return cmd ? std::optional<C>(act * coupling * held) : std::nullopt;
  const int o = m.output_index(e2);
  if (o < 0 || !m.path(e2, x)) return std::nullopt;
  const C h = m.position_to_output(o, i, w);
  return (cmd ? act * h : h / coupling) * held;
}

Diagnosis diagnose(const Model& sim, const std::vector<MeasuredPair>& data,
                   const DiagnoseOptions& opt) {
  opt.validate();
  opt.chain.validate();
  Diagnosis d;
  d.chain = opt.chain;
  d.extended = sim;
  // Inputs excited by a multisine, from their actuator curve (else another curve of theirs): the
  // fitting data's and the validation's (another amplitude).
  auto input_of = [](const std::string& pair) {
    const std::string e1 = split_pair(pair).first;
    return e1.rfind("u_", 0) == 0 ? e1.substr(2) : e1;
  };
  std::map<std::string, MultisineExcitation> ms_fit, ms_val;
  for (bool actuator : {true, false})
    for (const auto& mp : data) {
      auto [e1, e2] = split_pair(mp.pair);
      if (is_actuator_pair(e1, e2) != actuator) continue;
      const std::string in = input_of(mp.pair);
      if (!ms_fit.count(in))
        if (auto ms = multisine_excitation(mp.frd)) ms_fit.emplace(in, std::move(*ms));
      if (!ms_val.count(in))
        if (auto ms = multisine_excitation(mp.validation)) ms_val.emplace(in, std::move(*ms));
    }
  // The multisine a point of `pair` was measured by (nullptr: a sine).
  auto ms_of = [&](const std::string& pair, double line_amplitude,
                   bool validation) -> const MultisineExcitation* {
    if (!(line_amplitude > 0)) return nullptr;
    auto& set = validation ? ms_val : ms_fit;
    auto it = set.find(input_of(pair));
    return it == set.end() ? nullptr : &it->second;
  };
  // Prepare the pairs the simulation can speak to (and those it has no path for).
  std::vector<PairFit> pairs, absent;
  for (const auto& mp : data) {
    auto [e1, e2] = split_pair(mp.pair);
    PairFit p;
    p.pair = mp.pair;
    p.e1 = e1;
    p.e2 = e2;
    if (is_actuator_pair(e1, e2)) {
      p.input = e2;
    } else if (e1.rfind("u_", 0) != 0) {
      p.input = e1;
      p.output = e2;
    } else {
      continue;  // command-relative pairs repeat what X:O and u_X:X say
    }
    if (sim.input_index(p.input) < 0 || (!p.output.empty() && sim.output_index(p.output) < 0))
      continue;
    if (!p.output.empty() && !sim.path(p.output, p.input)) {  // a path the simulation lacks
      absent.push_back(absent_pair_points(mp, opt));
      continue;
    }
    for (const auto& pt : mp.frd.points) {
      if (!usable(pt, opt)) continue;
      const MultisineExcitation* ms = ms_of(mp.pair, pt.line_amplitude, false);
      auto s = model_pair_response(sim, mp.pair, pt.w, pt.amplitude, opt.chain, ms);
      if (!s || std::abs(*s) == 0) continue;
      add_point(p, pt, *s, opt);
      if (ms) p.ms = ms;
    }
    if (p.w.size() >= 3) pairs.push_back(std::move(p));
  }
  std::vector<PairFit> original = pairs;  // before the findings (sigma_eff: see step 2's end)

  struct Raw {
    size_t pair;
    Cause c;
  };
  std::vector<Raw> raw;
  std::vector<Finding> coupling_findings;
  std::map<size_t, std::string> refused;  // per pair: the best candidate left out, and why

  // 1. Measurement coupling, per input: joint over u_X:X and every X:O.
  for (const auto& in : sim.inputs) {
    if (auto f = fit_measurement_coupling(sim, in, pairs, opt)) coupling_findings.push_back(*f);
  }

  // 1b. Paths the simulation lacks, where the data respond.
  std::vector<Finding> path_findings;
  for (const PairFit& p : absent) {
    std::string why;
    if (auto f = fit_missing_path(sim, p, opt, &why)) path_findings.push_back(*f);
  }

  // 2. Per pair: nonlinear actuators first, then up to max_causes_per_path linear causes.
  constexpr int kNlRounds = 8;  // width / linear-cause alternations (converges in 3-5 here)
  for (size_t k = 0; k < pairs.size(); ++k) {
    PairFit& p = pairs[k];
    const size_t N = p.w.size();
    const std::vector<C> base = p.factor;  // the coupling found in step 1
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
            refused[k] =
                std::string("best candidate ") + to_string(best->cause) +
                " lowers chi2 only from " + fmt(c0) + " to " + fmt(best->chi2) + " (needs " +
                fmt(std::max(best->k * std::log(2.0 * N), opt.min_improvement * c0)) + " less)";
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
          continue;
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
        continue;
      }
    }
    for (const Cause& c : linear_causes()) raw.push_back({k, c});
  }

  // A multisine actuator curve's sigma_eff now holds its element's predicted scatter: every later
  // chi2 (intervals, resolution, the report) weighs it so.
  for (size_t k = 0; k < pairs.size(); ++k) original[k].sig = pairs[k].sig;

  // 3. Scope: group consistent findings of the same cause.
  std::vector<bool> used(raw.size(), false);
  std::vector<Finding> findings = coupling_findings;
  findings.insert(findings.end(), path_findings.begin(), path_findings.end());
  auto make = [&](const Cause& c, Scope scope, const std::string& in, const std::string& out,
                  const std::vector<size_t>& members) {
    Finding f;
    f.cause = c.cause;
    f.scope = scope;
    f.input = in;
    f.output = out;
    // Average the members' parameters.
    for (const auto& [key, v] : c.params) {
      double s = 0;
      for (size_t r : members) s += raw[r].c.params.at(key);
      f.parameters[key] = s / members.size();
    }
    f.parameters.erase("notch");
    if (c.detail == "notch") f.text_parameters["shape"] = "notch";
    for (size_t r : members) f.pairs.push_back(pairs[raw[r].pair].pair);
    return f;
  };
  // plant / output / input (position pairs); actuator pairs are the input's own.
  auto group = [&](const std::function<bool(const PairFit&)>& sel, Scope scope,
                   const std::string& in, const std::string& out, size_t min_pairs) {
    std::vector<size_t> members_pairs;
    for (size_t k = 0; k < pairs.size(); ++k)
      if (!pairs[k].output.empty() && sel(pairs[k])) members_pairs.push_back(k);
    if (members_pairs.size() < min_pairs) return;
    for (size_t a = 0; a < raw.size(); ++a) {
      if (used[a] || pairs[raw[a].pair].output.empty() || !sel(pairs[raw[a].pair])) continue;
      std::vector<size_t> m{a};
      for (size_t b = 0; b < raw.size(); ++b) {
        if (b == a || used[b] || pairs[raw[b].pair].output.empty() || !sel(pairs[raw[b].pair]))
          continue;
        if (!consistent(raw[a].c, raw[b].c, opt)) continue;
        bool dup = false;
        for (size_t x : m) dup |= raw[x].pair == raw[b].pair;
        if (!dup) m.push_back(b);
      }
      if (m.size() != members_pairs.size()) continue;
      for (size_t x : m) used[x] = true;
      findings.push_back(make(raw[a].c, scope, in, out, m));
    }
  };
  group([](const PairFit&) { return true; }, Scope::kPlant, "", "", 3);
  for (const auto& o : sim.outputs)
    group([&](const PairFit& p) { return p.output == o.name; }, Scope::kOutput, "", o.name, 2);
  for (const auto& i : sim.inputs)
    group([&](const PairFit& p) { return p.input == i.name; }, Scope::kInput, i.name, "", 2);
  for (size_t a = 0; a < raw.size(); ++a) {
    if (used[a]) continue;
    const PairFit& p = pairs[raw[a].pair];
    findings.push_back(
        make(raw[a].c, p.output.empty() ? Scope::kInput : Scope::kPath, p.input, p.output, {a}));
    if (!raw[a].c.detail.empty()) findings.back().explanation = raw[a].c.detail;
  }

  // 4. Errors: of a model over some pairs (all when `which` is empty), on the fitted or the
  // validation measurement.
  auto err_over = [&](const Model& m, const std::vector<std::string>& which, bool validation) {
    double s = 0;
    int n = 0;
    for (const auto& mp : data) {
      if (!which.empty() && std::find(which.begin(), which.end(), mp.pair) == which.end()) continue;
      const Frd& f = validation ? mp.validation : mp.frd;
      bool known = false;
      for (const auto& p : original) known |= p.pair == mp.pair;
      // A pair the simulation has no path for counts where a finding names it, never in a total
      // (the simulation's error there is unbounded).
      for (const auto& p : absent) known |= !which.empty() && p.pair == mp.pair;
      if (!known || f.points.empty()) continue;
      std::vector<double> w;
      std::vector<C> meas;
      std::vector<double> amp;
      std::vector<const MultisineExcitation*> ms;
      for (const auto& pt : f.points) {
        if (!usable(pt, opt)) continue;
        w.push_back(pt.w);
        meas.push_back(pt.value());
        amp.push_back(pt.amplitude);
        ms.push_back(ms_of(mp.pair, pt.line_amplitude, validation));
      }
      if (w.empty()) continue;
      // A model with no response on the pair (a path it lacks) errs by 1 there (100 %).
      const bool responds =
          model_pair_response(m, mp.pair, w[0], amp[0], opt.chain, ms[0]).has_value();
      double e = !responds ? 1.0 : pair_error(w, meas, [&](double x, size_t i) {
        return model_pair_response(m, mp.pair, x, amp[i], opt.chain, ms[i]);
      });
      s += e * e * w.size();
      n += int(w.size());
    }
    return n ? std::sqrt(s / n) : -1.0;
  };
  bool have_val = false;
  for (const auto& mp : data) have_val |= !mp.validation.points.empty();
  auto with = [&](const std::vector<Finding>& fs, size_t skip) {
    Model m = sim;
    for (size_t i = 0; i < fs.size(); ++i)
      if (i != skip) apply_finding(m, fs[i]);
    return m;
  };
  // 4b. Every finding is resolved by the data (file comment): its primary parameter's interval,
  // and its simulation value outside it.
  {
    std::vector<Finding> kept;
    for (size_t i = 0; i < findings.size(); ++i) {
      Finding& f = findings[i];
      // The finding's pairs (the fitting data, sigma_eff as fitted), and chi2 of a model there.
      std::vector<const PairFit*> mine;
      size_t n = 0;
      for (const std::vector<PairFit>* set : {static_cast<const std::vector<PairFit>*>(&original),
                                              static_cast<const std::vector<PairFit>*>(&absent)})
        for (const auto& p : *set)
          if (std::find(f.pairs.begin(), f.pairs.end(), p.pair) != f.pairs.end()) {
            mine.push_back(&p);
            n += p.w.size();
          }
      auto chi2_of_model = [&](const Model& m) {
        double c = 0;
        for (const PairFit* p : mine)
          for (size_t q = 0; q < p->w.size(); ++q) {
            const C g =
                model_pair_response(m, p->pair, p->w[q], p->amp[q], opt.chain, p->ms).value_or(0.0);
            c += std::norm(p->meas[q] - g) / (p->sig[q] * p->sig[q]);
          }
        return c;
      };
      const double c_min = chi2_of_model(with(findings, findings.size()));
      const double s = std::max(1.0, c_min / std::max<double>(1.0, double(n)));
      const auto [key, sim_value] = primary_parameter(f, sim);
      double c_sim = 0;
      if (sim_value) {
        std::vector<Finding> moved = findings;
        moved[i].parameters[key] = *sim_value;
        c_sim = chi2_of_model(with(moved, findings.size()));
      } else {
        c_sim = chi2_of_model(with(findings, i));  // the simulation lacks it: without it
      }
      if (!key.empty()) {
        auto chi2_at = [&](double v) {
          std::vector<Finding> moved = findings;
          moved[i].parameters[key] = v;
          return chi2_of_model(with(moved, findings.size())) - (c_min + s);
        };
        f.intervals[key] = parameter_interval(chi2_at, f.parameters.at(key), key, opt);
      }
      if (c_sim - c_min > s) {
        kept.push_back(f);
        continue;
      }
      std::string why = "not resolved by the data: chi2 over its pairs is " + fmt(c_min) +
                        " with it and " + fmt(c_sim) + " at the simulation's " +
                        (sim_value ? key + " = " + fmt(*sim_value) : std::string("(without it)")) +
                        ", less than " + fmt(s) + " apart";
      d.dropped.push_back({f, why});
    }
    findings = kept;
  }
  // 5. Every finding earns its place on the independent validation measurement: removed from the
  // extended model, its pairs' validation error must rise. The one that helps least is dropped
  // (and said why) until every remaining one does; then the extended model must beat the
  // simulation on the validation data as a whole, or the least useful finding goes too.
  if (have_val) {
    for (;;) {
      const Model full = with(findings, findings.size());
      const bool worse_overall = err_over(full, {}, true) > err_over(sim, {}, true);
      int worst = -1;
      double worst_gain = INFINITY, worst_with = 0, worst_without = 0;
      for (size_t i = 0; i < findings.size(); ++i) {
        const double e_with = err_over(full, findings[i].pairs, true);
        const double e_without = err_over(with(findings, i), findings[i].pairs, true);
        const double gain = e_without - e_with;
        if ((gain <= 0 || worse_overall) && gain < worst_gain) {
          worst = int(i), worst_gain = gain, worst_with = e_with, worst_without = e_without;
        }
      }
      if (worst < 0) break;
      d.dropped.push_back({findings[worst], "does not lower the validation error on its pairs (" +
                                                fmt(worst_without) + " without it, " +
                                                fmt(worst_with) + " with it)"});
      findings.erase(findings.begin() + worst);
    }
  }
  Model& ext = d.extended;
  ext = with(findings, findings.size());
  for (auto& f : findings) {
    Model one = sim;  // the simulation plus this finding alone
    apply_finding(one, f);
    f.error_before = err_over(sim, f.pairs, false);
    f.error_after = err_over(one, f.pairs, false);
    if (f.explanation.empty()) f.explanation = explain(f);
  }
  for (auto& x : d.dropped)
    if (x.finding.explanation.empty()) x.finding.explanation = explain(x.finding);
  std::sort(findings.begin(), findings.end(), [](const Finding& a, const Finding& b) {
    return a.error_before - a.error_after > b.error_before - b.error_after;
  });
  d.findings = findings;
  d.error_before = err_over(sim, {}, false);
  d.error_after = err_over(ext, {}, false);
  if (have_val) {
    d.validation_before = err_over(sim, {}, true);
    d.validation_after = err_over(ext, {}, true);
  }
  // Per-pair report data.
  for (const auto& p : original) {
    PairReport r;
    r.pair = p.pair;
    r.w = p.w;
    r.meas = p.meas;
    r.sim = p.sim;
    for (size_t q = 0; q < p.w.size(); ++q) {
      r.ext.push_back(
          model_pair_response(ext, p.pair, p.w[q], p.amp[q], opt.chain, p.ms).value_or(0.0));
      r.sigma.push_back(p.sig[q]);
      r.chi2_sim += std::norm(p.meas[q] - p.sim[q]) / (p.sig[q] * p.sig[q]);
      r.chi2_ext += std::norm(p.meas[q] - r.ext.back()) / (p.sig[q] * p.sig[q]);
    }
    r.beyond = r.chi2_sim > p.w.size() + 4 * std::sqrt(double(p.w.size()));
    r.error_sim =
        pair_error(p.w, p.meas, [&](double, size_t i) { return std::optional<C>(p.sim[i]); });
    r.error_ext =
        pair_error(p.w, p.meas, [&](double, size_t i) { return std::optional<C>(r.ext[i]); });
    // What the catalogue does not explain is said, not forced.
    const double n = double(p.w.size());
    if (r.chi2_ext > n + 4 * std::sqrt(n)) {
      Unexplained u;
      u.pair = p.pair;
      double lo = INFINITY, hi = 0;
      for (size_t q = 0; q < p.w.size(); ++q) {
        const double z = std::abs(p.meas[q] - r.ext[q]) / p.sig[q];
        if (z < 3) continue;
        lo = std::min(lo, p.w[q] / (2 * M_PI));
        hi = std::max(hi, p.w[q] / (2 * M_PI));
        u.residual = std::max(u.residual, std::abs(std::log(p.meas[q] / r.ext[q])));
      }
      u.band_hz = {std::isfinite(lo) ? lo : 0.0, hi};
      u.chi2 = r.chi2_ext;
      for (const auto& [k, why] : refused)
        if (pairs[k].pair == p.pair) u.explanation = why;
      if (u.explanation.empty())
        u.explanation = "no cause of the catalogue lowers chi2 enough to be accepted";
      d.unexplained.push_back(u);
    }
    d.pairs.push_back(r);
  }
  return d;
}

namespace {
// {"delay_s": [lo, hi]}, null for an unbounded side.
Json intervals_json(const Finding& f) {
  Json j = Json::object();
  for (const auto& [k, v] : f.intervals)
    j[k] = {std::isfinite(v[0]) ? Json(v[0]) : Json(nullptr),
            std::isfinite(v[1]) ? Json(v[1]) : Json(nullptr)};
  return j;
}
}  // namespace

Json diagnosis_to_json(const Diagnosis& d) {
  Json j{{"format", "fralab-diagnosis/1"}, {"findings", Json::array()}};
  for (const auto& f : d.findings) {
    Json p = Json::object();
    for (const auto& [k, v] : f.parameters) p[k] = v;
    for (const auto& [k, v] : f.text_parameters) p[k] = v;
    j["findings"].push_back({{"cause", to_string(f.cause)},
                             {"scope", to_string(f.scope)},
                             {"output", f.output.empty() ? Json(nullptr) : Json(f.output)},
                             {"input", f.input.empty() ? Json(nullptr) : Json(f.input)},
                             {"parameters", p},
                             {"explanation", f.explanation},
                             {"error_before", f.error_before},
                             {"error_after", f.error_after},
                             {"pairs", f.pairs},
                             {"intervals", intervals_json(f)}});
    if (f.tf) j["findings"].back()["tf"] = tf_to_json(*f.tf);
  }
  j["measurement_chain"] = chain_to_json(d.chain);
  j["dropped"] = Json::array();
  for (const auto& x : d.dropped) {
    Json p = Json::object();
    for (const auto& [k, v] : x.finding.parameters) p[k] = v;
    j["dropped"].push_back(
        {{"cause", to_string(x.finding.cause)},
         {"scope", to_string(x.finding.scope)},
         {"output", x.finding.output.empty() ? Json(nullptr) : Json(x.finding.output)},
         {"input", x.finding.input.empty() ? Json(nullptr) : Json(x.finding.input)},
         {"parameters", p},
         {"pairs", x.finding.pairs},
         {"intervals", intervals_json(x.finding)},
         {"reason", x.reason}});
  }
  j["unexplained"] = Json::array();
  for (const auto& u : d.unexplained) {
    j["unexplained"].push_back({{"pair", u.pair},
                                {"band_hz", {u.band_hz[0], u.band_hz[1]}},
                                {"residual", u.residual},
                                {"chi2", u.chi2},
                                {"explanation", u.explanation}});
  }
  j["summary"] = {
      {"metric", d.metric}, {"error_before", d.error_before}, {"error_after", d.error_after}};
  if (d.validation_before >= 0) {
    j["summary"]["validation_error_before"] = d.validation_before;
    j["summary"]["validation_error_after"] = d.validation_after;
  }
  j["pairs"] = Json::array();
  for (const auto& p : d.pairs) {
    j["pairs"].push_back({{"pair", p.pair},
                          {"beyond_uncertainty", p.beyond},
                          {"chi2_simulation", p.chi2_sim},
                          {"chi2_extended", p.chi2_ext},
                          {"n_points", p.w.size()},
                          {"error_before", p.error_sim},
                          {"error_after", p.error_ext}});
  }
  return j;
}

}  // namespace fralab
