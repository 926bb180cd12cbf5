#include "fralab/identify/diagnose.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <set>
#include <sstream>

#include "fralab/plant/nonlinearity.h"
#include "line_search.h"

namespace fralab {
namespace {

using C = std::complex<double>;
constexpr double kPi = std::numbers::pi;

std::string fmt(double v, int prec = 3) {
  std::ostringstream s;
  s.precision(prec);
  s << v;
  return s.str();
}

bool is_actuator_pair(const std::string& e1, const std::string& e2) { return e1 == "u_" + e2; }

// A point says something about the model only when it is measured to better than max_rel_sigma
// (an actuator inside its backlash, or a response down in the noise, is not).
bool usable(const FrdPoint& p, const DiagnoseOptions& o) {
  return p.valid && p.sigma > 0 && p.mag > 0 && p.sigma <= o.max_rel_sigma * p.mag;
}

// One pair's data against the current model.
struct PairFit {
  std::string pair, e1, e2, input, output;  // output "" for actuator pairs
  std::vector<double> w, amp, h3;
  std::vector<C> meas, sim;  // sim: the simulation (unchanged by findings)
  std::vector<double> sig;   // sigma_eff
  std::vector<C> factor;     // product of accepted cause factors so far
};

double chi2(const PairFit& p, const std::vector<C>& F) {
  double c = 0;
  for (size_t i = 0; i < p.w.size(); ++i)
    c += std::norm(p.meas[i] - p.sim[i] * p.factor[i] * F[i]) / (p.sig[i] * p.sig[i]);
  return c;
}

using detail::golden;

// 1-D minimisation: a grid then golden section around the best grid point.
double minimise_1d(const std::function<double(double)>& f, double lo, double hi, int grid = 60) {
  double best = lo, fb = INFINITY;
  for (int k = 0; k <= grid; ++k) {
    double x = lo + (hi - lo) * k / grid, v = f(x);
    if (v < fb) fb = v, best = x;
  }
  const double step = (hi - lo) / grid;
  return golden(f, std::max(lo, best - step), std::min(hi, best + step));
}

struct Cause {
  std::string cause;
  std::map<std::string, double> params;
  std::vector<C> F;
  double chi2 = INFINITY;
  int k = 1;
  std::string detail;
};

std::vector<C> factor_of(const std::vector<double>& w, const std::function<C(C)>& f) {
  std::vector<C> F;
  for (double x : w) F.push_back(f(C(0, x)));
  return F;
}

// Backlash/deadband describing function at the input amplitude that produces the measured output
// amplitude y (solved by bisection: the output amplitude grows monotonically with A).
C nl_df(const std::string& type, double width, double y) {
  auto out_amp = [&](double a) {
    return type == "hysteresis" ? std::abs(backlash_describing_function(a, width)) * a
                                : deadband_describing_function(a, width) * a;
  };
  double lo = width / 2, hi = width / 2 + 2 * y + 1e-12;
  while (out_amp(hi) < y) hi *= 2;
  for (int i = 0; i < 80; ++i) {
    double m = (lo + hi) / 2;
    (out_amp(m) < y ? lo : hi) = m;
  }
  const double a = (lo + hi) / 2;
  return type == "hysteresis" ? backlash_describing_function(a, width)
                              : C(deadband_describing_function(a, width), 0);
}

// The simulated chain's poles for a pair (for pole_shift candidates).
std::vector<Root> chain_poles(const Model& m, const PairFit& p) {
  std::vector<Root> v;
  const int i = m.input_index(p.input);
  if (p.output.empty()) {
    if (m.inputs[i].actuator) v = m.inputs[i].actuator->poles;
    return v;
  }
  if (const ModelPath* mp = m.path(p.output, p.input)) v = mp->tf.poles;
  const int o = m.output_index(p.output);
  if (m.outputs[o].sensor)
    v.insert(v.end(), m.outputs[o].sensor->poles.begin(), m.outputs[o].sensor->poles.end());
  return v;
}

std::vector<Cause> candidates(const Model& m, const PairFit& p) {
  std::vector<Cause> out;
  const double wlo = p.w.front(), whi = p.w.back();
  auto add = [&](Cause c) {
    c.chi2 = chi2(p, c.F);
    out.push_back(std::move(c));
  };
  // gain_mismatch: closed form over real k.
  {
    double num = 0, den = 0;
    for (size_t i = 0; i < p.w.size(); ++i) {
      C s = p.sim[i] * p.factor[i];
      const double v = 1 / (p.sig[i] * p.sig[i]);
      num += v * (std::conj(s) * p.meas[i]).real();
      den += v * std::norm(s);
    }
    const double k = num / den;
    if (k > 0)
      add({"gain_mismatch",
           {{"gain_db", 20 * std::log10(k)}},
           std::vector<C>(p.w.size(), C(k, 0)),
           0,
           1,
           ""});
  }
  // time_delay
  {
    auto F = [&](double tau) { return factor_of(p.w, [&](C s) { return std::exp(-s * tau); }); };
    double tau = minimise_1d([&](double t) { return chi2(p, F(t)); }, -0.02, 0.05, 280);
    add({"time_delay", {{"delay_s", tau}}, F(tau), 0, 1, ""});
  }
  // missing_lag / missing_lead (log-spaced corner)
  for (int lead = 0; lead < 2; ++lead) {
    auto F = [&](double la) {
      const double a = std::exp(la);
      return factor_of(p.w, [&](C s) { return lead ? 1.0 + s / a : 1.0 / (1.0 + s / a); });
    };
    double la = minimise_1d([&](double x) { return chi2(p, F(x)); }, std::log(wlo / 10),
                            std::log(whi * 10), 80);
    add({lead ? "missing_lead" : "missing_lag", {{"corner_rad_s", std::exp(la)}}, F(la), 0, 1, ""});
  }
  // missing_resonance: a peak (pole pair) or a notch (zero pair); grid in wn and zeta, then
  // alternate golden searches.
  for (int notch = 0; notch < 2; ++notch) {
    auto F = [&](double lw, double z) {
      const double wn = std::exp(lw);
      return factor_of(p.w, [&](C s) {
        C d = s * s / (wn * wn) + 2 * z * s / wn + 1.0;
        return notch ? d : 1.0 / d;
      });
    };
    double blw = 0, bz = 0.1, bc = INFINITY;
    for (int k = 0; k <= 40; ++k) {
      double lw = std::log(wlo) + (std::log(whi) - std::log(wlo)) * k / 40;
      for (double z : {0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.7}) {
        double c = chi2(p, F(lw, z));
        if (c < bc) bc = c, blw = lw, bz = z;
      }
    }
    for (int it = 0; it < 4; ++it) {
      blw = golden([&](double x) { return chi2(p, F(x, bz)); }, blw - 0.1, blw + 0.1, 30);
      bz = golden([&](double z) { return chi2(p, F(blw, z)); }, std::max(0.002, bz * 0.5),
                  std::min(1.0, bz * 2), 30);
    }
    Cause c{"missing_resonance",     {{"wn_rad_s", std::exp(blw)}, {"zeta", bz}}, F(blw, bz), 0, 2,
            notch ? "notch" : "peak"};
    if (notch) c.params["notch"] = 1;
    add(c);
  }
  // pole_shift of each simulated pole
  for (const Root& r : chain_poles(m, p)) {
    const double from = r.pair ? r.wn : -r.real;
    auto F = [&](double lto) {
      const double to = std::exp(lto);
      Root q = r;
      if (q.pair)
        q.wn = to;
      else
        q.real = -to;
      return factor_of(p.w, [&](C s) { return r.factor(s) / q.factor(s); });
    };
    double lto = minimise_1d([&](double x) { return chi2(p, F(x)); }, std::log(from / 30),
                             std::log(from * 30), 120);
    Cause c{"pole_shift", {{"from_rad_s", from}, {"to_rad_s", std::exp(lto)}}, F(lto), 0, 1, ""};
    if (r.pair) c.params["zeta"] = r.zeta;
    add(c);
  }
  return out;
}

// The error metric for one pair under a response function (no response: the point is skipped).
double pair_error(const std::vector<double>& w, const std::vector<C>& meas,
                  const std::function<std::optional<C>(double, size_t)>& model) {
  std::vector<C> g;
  for (size_t i = 0; i < w.size(); ++i) g.push_back(model(w[i], i).value_or(0.0));
  return detail::rms_log_error(g, meas);
}

bool consistent(const Cause& a, const Cause& b) {
  if (a.cause != b.cause || a.detail != b.detail) return false;
  for (const auto& [k, v] : a.params) {
    auto it = b.params.find(k);
    if (it == b.params.end()) return false;
    const double u = it->second;
    if (k == "delay_s" && std::abs(v - u) > std::max(0.5e-3, 0.1 * std::abs(v))) return false;
    if (k == "gain_db" && std::abs(v - u) > 0.3) return false;
    if ((k == "corner_rad_s" || k == "wn_rad_s" || k == "to_rad_s" || k == "from_rad_s") &&
        std::abs(v - u) > 0.1 * std::abs(v))
      return false;
  }
  return true;
}

// Extends a tf by a finding's factor (delay, lag, lead, resonance, gain, moved pole).
void apply_tf(Tf& t, const Finding& f) {
  const auto& q = f.parameters;
  if (f.cause == "time_delay") t.delay_s = std::max(0.0, t.delay_s + q.at("delay_s"));
  if (f.cause == "missing_lag") t.poles.push_back(Root::Real(-q.at("corner_rad_s")));
  if (f.cause == "missing_lead") t.zeros.push_back(Root::Real(-q.at("corner_rad_s")));
  if (f.cause == "missing_resonance") {
    Root r = Root::Pair(q.at("wn_rad_s"), q.at("zeta"));
    (f.text_parameters.count("shape") ? t.zeros : t.poles).push_back(r);
  }
  if (f.cause == "gain_mismatch") t.gain *= std::pow(10.0, q.at("gain_db") / 20);
  if (f.cause == "pole_shift") {
    const double from = q.at("from_rad_s"), to = q.at("to_rad_s");
    Root* best = nullptr;
    for (Root& r : t.poles) {
      const double v = r.pair ? r.wn : -r.real;
      if (!best || std::abs(v - from) < std::abs((best->pair ? best->wn : -best->real) - from))
        best = &r;
    }
    if (best) {
      if (best->pair)
        best->wn = to;
      else
        best->real = -to;
    }
  }
}

// Extends a model by one finding: the coupling or nonlinearity of its input, the actuator's own tf
// (a finding of the actuator pair u_X:X), the output's sensor, or the paths its scope covers.
void apply_finding(Model& m, const Finding& f) {
  if (f.cause == "measurement_coupling") {
    m.inputs[m.input_index(f.input)].measurement_coupling.push_back(
        {f.text_parameters.at("coupled_to"), f.parameters.at("gain")});
  } else if (f.cause == "hysteresis" || f.cause == "deadband") {
    m.inputs[m.input_index(f.input)].nonlinearity.push_back({f.cause, f.parameters.at("width")});
  } else if (f.scope == "input" && f.output.empty() && f.pairs.size() == 1 &&
             split_pair(f.pairs[0]).first == "u_" + f.input) {
    ModelInput& in = m.inputs[m.input_index(f.input)];
    if (!in.actuator) in.actuator = Tf{};
    apply_tf(*in.actuator, f);
  } else if (f.scope == "output") {
    ModelOutput& out = m.outputs[m.output_index(f.output)];
    if (!out.sensor) out.sensor = Tf{};
    apply_tf(*out.sensor, f);
  } else {
    for (auto& p : m.paths) {
      if (f.scope == "plant" || (f.scope == "input" && p.input == f.input) ||
          (f.scope == "path" && p.input == f.input && p.output == f.output)) {
        apply_tf(p.tf, f);
      }
    }
  }
}

}  // namespace

void DiagnoseOptions::validate() const {
  if (!(sigma_floor >= 0)) throw InputError("diagnose: sigma_floor must be >= 0");
  if (!(min_improvement > 0 && min_improvement < 1))
    throw InputError("diagnose: min_improvement must be in (0, 1)");
  if (max_causes_per_path < 1) throw InputError("diagnose: max_causes_per_path must be >= 1");
  if (!(max_rel_sigma > 0)) throw InputError("diagnose: max_rel_sigma must be > 0");
}

std::optional<C> model_pair_response(const Model& m, const std::string& pair, double w,
                                     double amplitude) {
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
  // The actuator's describing function at the command amplitude (linear part first).
  C act = m.actuator_response(i, w);
  for (const auto& nl : in.nonlinearity) {
    if (amplitude <= 0) break;
    if (nl.type == "hysteresis")
      act *= backlash_describing_function(amplitude * std::abs(act), nl.width);
    if (nl.type == "deadband")
      act *= deadband_describing_function(amplitude * std::abs(act), nl.width);
  }
  if (e2 == x) return cmd ? std::optional<C>(act * coupling) : std::nullopt;
  const int o = m.output_index(e2);
  if (o < 0 || !m.path(e2, x)) return std::nullopt;
  const C h = m.position_to_output(o, i, w);
  return cmd ? act * h : h / coupling;
}

Diagnosis diagnose(const Model& sim, const std::vector<MeasuredPair>& data,
                   const DiagnoseOptions& opt) {
  opt.validate();
  Diagnosis d;
  d.extended = sim;
  // Prepare the pairs the simulation can speak to.
  std::vector<PairFit> pairs;
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
    for (const auto& pt : mp.frd.points) {
      if (!usable(pt, opt)) continue;
      auto s = model_pair_response(sim, mp.pair, pt.w, pt.amplitude);
      if (!s || std::abs(*s) == 0) continue;
      p.w.push_back(pt.w);
      p.meas.push_back(pt.value());
      p.sim.push_back(*s);
      p.amp.push_back(pt.amplitude);
      p.h3.push_back(pt.h3_rel);
      p.sig.push_back(std::hypot(pt.sigma, opt.sigma_floor * pt.mag));
      p.factor.push_back(1.0);
    }
    if (p.w.size() >= 3) pairs.push_back(std::move(p));
  }
  const std::vector<PairFit> original = pairs;

  struct Raw {
    size_t pair;
    Cause c;
  };
  std::vector<Raw> raw;
  std::vector<Finding> coupling_findings;

  // 1. Measurement coupling, per input: joint over u_X:X and every X:O.
  for (const auto& in : sim.inputs) {
    std::vector<size_t> idx;
    int act = -1;
    for (size_t k = 0; k < pairs.size(); ++k) {
      if (pairs[k].input != in.name) continue;
      idx.push_back(k);
      if (pairs[k].output.empty()) act = int(k);
    }
    if (act < 0 || idx.size() < 2) continue;
    const int i = sim.input_index(in.name);
    double base = 0;
    for (size_t k : idx) base += chi2(pairs[k], std::vector<C>(pairs[k].w.size(), 1.0));
    std::string best_o;
    double best_g = 0, best_c = base;
    for (const auto& out : sim.outputs) {
      const int o = sim.output_index(out.name);
      if (!sim.path(out.name, in.name)) continue;
      double hmax = 0;
      for (double w : pairs[act].w)
        hmax = std::max(hmax, std::abs(sim.position_to_output(o, i, w)));
      if (hmax == 0) continue;
      auto F = [&](const PairFit& p, double g) {
        return factor_of(p.w, [&](C s) {
          C h = 1.0 + g * sim.position_to_output(o, i, s.imag());
          return p.output.empty() ? h : 1.0 / h;
        });
      };
      auto total = [&](double g) {
        double c = 0;
        for (size_t k : idx) c += chi2(pairs[k], F(pairs[k], g));
        return c;
      };
      double g = minimise_1d(total, -0.9 / hmax, 0.9 / hmax, 200);
      double c = total(g);
      if (c < best_c) best_c = c, best_g = g, best_o = out.name;
    }
    double n = 0;
    for (size_t k : idx) n += pairs[k].w.size();
    // The signature must be in the channel's own actuator response (1 + g H): that pair has to be
    // beyond its uncertainty and be explained by the coupling (a path gain error is not a
    // coupling).
    bool act_signature = false;
    if (!best_o.empty()) {
      const PairFit& a = pairs[act];
      const double na = double(a.w.size());
      const double ca0 = chi2(a, std::vector<C>(a.w.size(), 1.0));
      const int o = sim.output_index(best_o);
      const double ca1 = chi2(a, factor_of(a.w, [&](C s) {
                                return 1.0 + best_g * sim.position_to_output(o, i, s.imag());
                              }));
      act_signature = ca0 > na + 4 * std::sqrt(na) && ca0 - ca1 > opt.min_improvement * ca0;
    }
    if (act_signature && base - best_c > std::max(std::log(2 * n), opt.min_improvement * base) &&
        base > n + 4 * std::sqrt(n)) {
      // Accept only if no single-path cause explains it as well (coupling touches every path).
      const int o = sim.output_index(best_o);
      Finding f;
      f.cause = "measurement_coupling";
      f.scope = "input";
      f.input = in.name;
      f.text_parameters = {{"channel", in.name}, {"coupled_to", best_o}};
      f.parameters = {{"gain", best_g}};
      f.explanation = "the " + in.name + " channel records " + in.name + " + " + fmt(best_g) +
                      " * " + best_o + ": its actuator response carries the " + best_o +
                      " response (1 + g H) and every " + in.name + " path divides by it; chi2 " +
                      fmt(base) + " -> " + fmt(best_c) + " over " + std::to_string(idx.size()) +
                      " pairs";
      for (size_t k : idx) {
        f.pairs.push_back(pairs[k].pair);
        for (size_t q = 0; q < pairs[k].w.size(); ++q) {
          C h = 1.0 + best_g * sim.position_to_output(o, i, pairs[k].w[q]);
          pairs[k].factor[q] *= pairs[k].output.empty() ? h : 1.0 / h;
        }
      }
      coupling_findings.push_back(f);
    }
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
        auto cs = candidates(sim, p);
        const Cause* best = nullptr;
        double best_bic = INFINITY;
        for (const auto& c : cs) {
          double bic = c.chi2 + c.k * std::log(2.0 * N);
          if (bic < best_bic) best_bic = bic, best = &c;
        }
        if (!best ||
            c0 - best->chi2 < std::max(best->k * std::log(2.0 * N), opt.min_improvement * c0))
          break;
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
      for (size_t q = 0; q < N; ++q) {
        if (p.w[q] < 0.3 * corner) {
          low.push_back(q);
          h3 += p.h3[q];
        }
      }
      // The describing function's width on the low points, against the simulation times `lin` (the
      // linear causes found so far); c0: the same points without it.
      auto fit_nl = [&](const std::vector<C>& lin, double* c0) {
        Cause best;
        auto low_chi2 = [&](const std::vector<C>& f) {
          double c = 0;
          for (size_t q : low)
            c += std::norm(p.meas[q] - p.sim[q] * base[q] * lin[q] * f[q]) / (p.sig[q] * p.sig[q]);
          return c;
        };
        for (const char* type : {"hysteresis", "deadband"}) {
          auto F = [&](double width) {
            std::vector<C> F(N, 1.0);
            for (size_t q = 0; q < N; ++q)
              F[q] = nl_df(type, width, p.amp[q] * std::abs(p.meas[q]));
            return F;
          };
          const double a = p.amp[low[0]];
          double width =
              minimise_1d([&](double x) { return low_chi2(F(x)); }, 1e-4 * a, 1.9 * a, 200);
          double c = low_chi2(F(width));
          if (c < best.chi2) best = Cause{type, {{"width", width}}, F(width), c, 1, ""};
        }
        *c0 = low_chi2(std::vector<C>(N, 1.0));
        return best;
      };
      double c0 = 0;
      Cause nl;
      if (low.size() >= 2 && h3 / low.size() > 0.01 && p.amp[low[0]] > 0)
        nl = fit_nl(std::vector<C>(N, 1.0), &c0);
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
            if (c.cause == "gain_mismatch") continue;
            for (size_t q = 0; q < N; ++q) L[q] *= c.F[q];
          }
          double c0_again = 0;
          Cause again = fit_nl(L, &c0_again);
          if (!std::isfinite(again.chi2) || again.cause != nl.cause) break;
          settled = std::abs(again.params["width"] / nl.params["width"] - 1) < 1e-3;
          nl = again;
        }
        std::ostringstream ex;
        const double mh3 = h3 / low.size();
        const C n0 = nl.F[low[0]];
        ex << "odd harmonics in the position (3rd at " << fmt(100 * mh3, 2)
           << " % of the fundamental); below " << fmt(0.3 * corner / (2 * kPi), 2)
           << " Hz the actuator lags " << fmt(-std::arg(n0) * 180 / kPi, 3) << " deg with gain "
           << fmt(std::abs(n0), 3) << " at +-" << fmt(p.amp[low[0]], 3)
           << " (describing function of a " << nl.cause << " of width "
           << fmt(nl.params["width"], 3) << ")";
        raw.push_back({k, nl});
        raw.back().c.detail = ex.str();
        for (const Cause& c : lin) raw.push_back({k, c});
        continue;
      }
    }
    for (const Cause& c : linear_causes()) raw.push_back({k, c});
  }

  // 3. Scope: group consistent findings of the same cause.
  std::vector<bool> used(raw.size(), false);
  std::vector<Finding> findings = coupling_findings;
  auto make = [&](const Cause& c, const std::string& scope, const std::string& in,
                  const std::string& out, const std::vector<size_t>& members) {
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
  auto group = [&](const std::function<bool(const PairFit&)>& sel, const std::string& scope,
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
        if (!consistent(raw[a].c, raw[b].c)) continue;
        bool dup = false;
        for (size_t x : m) dup |= raw[x].pair == raw[b].pair;
        if (!dup) m.push_back(b);
      }
      if (m.size() != members_pairs.size()) continue;
      for (size_t x : m) used[x] = true;
      findings.push_back(make(raw[a].c, scope, in, out, m));
    }
  };
  group([](const PairFit&) { return true; }, "plant", "", "", 3);
  for (const auto& o : sim.outputs)
    group([&](const PairFit& p) { return p.output == o.name; }, "output", "", o.name, 2);
  for (const auto& i : sim.inputs)
    group([&](const PairFit& p) { return p.input == i.name; }, "input", i.name, "", 2);
  for (size_t a = 0; a < raw.size(); ++a) {
    if (used[a]) continue;
    const PairFit& p = pairs[raw[a].pair];
    findings.push_back(make(raw[a].c, p.output.empty() ? "input" : "path", p.input, p.output, {a}));
    if (!raw[a].c.detail.empty()) findings.back().explanation = raw[a].c.detail;
  }

  // 4. The extended model: the simulation plus every finding.
  Model& ext = d.extended;
  for (const auto& f : findings) apply_finding(ext, f);

  // 5. Errors: per finding (its pairs, the simulation plus that finding alone) and in total.
  auto err_over = [&](const Model& m, const std::vector<std::string>& which, bool validation) {
    double s = 0;
    int n = 0;
    for (const auto& mp : data) {
      if (!which.empty() && std::find(which.begin(), which.end(), mp.pair) == which.end()) continue;
      const Frd& f = validation ? mp.validation : mp.frd;
      bool known = false;
      for (const auto& p : original) known |= p.pair == mp.pair;
      if (!known || f.points.empty()) continue;
      std::vector<double> w;
      std::vector<C> meas;
      std::vector<double> amp;
      for (const auto& pt : f.points) {
        if (!usable(pt, opt)) continue;
        w.push_back(pt.w);
        meas.push_back(pt.value());
        amp.push_back(pt.amplitude);
      }
      double e = pair_error(
          w, meas, [&](double x, size_t i) { return model_pair_response(m, mp.pair, x, amp[i]); });
      s += e * e * w.size();
      n += int(w.size());
    }
    return n ? std::sqrt(s / n) : -1.0;
  };
  for (auto& f : findings) {
    Model one = sim;  // the simulation plus this finding alone
    apply_finding(one, f);
    f.error_before = err_over(sim, f.pairs, false);
    f.error_after = err_over(one, f.pairs, false);
    if (f.explanation.empty()) {
      std::ostringstream ex;
      if (f.cause == "time_delay")
        ex << "phase residual linear in w (" << fmt(-f.parameters["delay_s"] * 1e3)
           << " ms slope), gain residual flat";
      if (f.cause == "missing_lag")
        ex << "a -20 dB/decade corner at " << fmt(f.parameters["corner_rad_s"])
           << " rad/s with its -90 deg phase, absent from the simulation";
      if (f.cause == "missing_lead")
        ex << "a +20 dB/decade corner at " << fmt(f.parameters["corner_rad_s"])
           << " rad/s with its +90 deg phase";
      if (f.cause == "missing_resonance")
        ex << "a resonance at " << fmt(f.parameters["wn_rad_s"]) << " rad/s, damping "
           << fmt(f.parameters["zeta"]);
      if (f.cause == "pole_shift")
        ex << "the simulated pole at " << fmt(f.parameters["from_rad_s"]) << " rad/s sits at "
           << fmt(f.parameters["to_rad_s"]) << " rad/s in the data";
      if (f.cause == "gain_mismatch")
        ex << "flat gain offset of " << fmt(f.parameters["gain_db"]) << " dB, no phase";
      if (f.scope == "output") ex << "; common to every path into " << f.output << ": its sensor";
      const bool own = f.pairs.size() == 1 && split_pair(f.pairs[0]).first == "u_" + f.input;
      if (f.scope == "input")
        ex << (own ? "; in the actuator's own response " + f.pairs[0]
                   : "; common to every path from " + f.input + ": its actuator or calibration");
      if (f.scope == "plant") ex << "; common to every path: a plant state";
      f.explanation = ex.str();
    }
  }
  std::sort(findings.begin(), findings.end(), [](const Finding& a, const Finding& b) {
    return a.error_before - a.error_after > b.error_before - b.error_after;
  });
  d.findings = findings;
  d.error_before = err_over(sim, {}, false);
  d.error_after = err_over(ext, {}, false);
  bool have_val = false;
  for (const auto& mp : data) have_val |= !mp.validation.points.empty();
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
      r.ext.push_back(model_pair_response(ext, p.pair, p.w[q], p.amp[q]).value_or(0.0));
      r.sigma.push_back(p.sig[q]);
      r.chi2_sim += std::norm(p.meas[q] - p.sim[q]) / (p.sig[q] * p.sig[q]);
      r.chi2_ext += std::norm(p.meas[q] - r.ext.back()) / (p.sig[q] * p.sig[q]);
    }
    r.beyond = r.chi2_sim > p.w.size() + 4 * std::sqrt(double(p.w.size()));
    r.error_sim =
        pair_error(p.w, p.meas, [&](double, size_t i) { return std::optional<C>(p.sim[i]); });
    r.error_ext =
        pair_error(p.w, p.meas, [&](double, size_t i) { return std::optional<C>(r.ext[i]); });
    d.pairs.push_back(r);
  }
  return d;
}

Json diagnosis_to_json(const Diagnosis& d) {
  Json j{{"format", "fralab-diagnosis/1"}, {"findings", Json::array()}};
  for (const auto& f : d.findings) {
    Json p = Json::object();
    for (const auto& [k, v] : f.parameters) p[k] = v;
    for (const auto& [k, v] : f.text_parameters) p[k] = v;
    j["findings"].push_back({{"cause", f.cause},
                             {"scope", f.scope},
                             {"output", f.output.empty() ? Json(nullptr) : Json(f.output)},
                             {"input", f.input.empty() ? Json(nullptr) : Json(f.input)},
                             {"parameters", p},
                             {"explanation", f.explanation},
                             {"error_before", f.error_before},
                             {"error_after", f.error_after},
                             {"pairs", f.pairs}});
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
