#include "fralab/diagnose/engine_time_bound.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <set>

#include "fralab/core/error.h"
#include "fralab/core/pair_id.h"
#include "pair_fit.h"

namespace fralab {

void EngineTimeBoundOptions::validate() const {
  if (grid_per_decade < 1) throw InputError("engine time bound: grid_per_decade must be >= 1");
  if (!(step_rel > 0 && step_rel < 0.1))
    throw InputError("engine time bound: step_rel must be in (0, 0.1)");
  if (!(step_abs > 0)) throw InputError("engine time bound: step_abs must be > 0");
  if (!(max_rel_sigma > 0)) throw InputError("engine time bound: max_rel_sigma must be > 0");
}

namespace {

using C = std::complex<double>;

// A point the diagnosis uses, with its noise made independent of its excitation.
struct NoisePoint {
  double w = 0;
  double amplitude = 0;  // the point's excitation: a sine's peak (model_pair_response's amplitude)
  const MultisineExcitation* ms = nullptr;  // its input's multisine, for a multisine's line
  double sigma = 0;                         // the noise part of the point's sigma
  double v = 0;                             // sigma^2 A^2 T
};

struct NoisePair {
  std::string pair, input;
  std::vector<NoisePoint> points;  // ascending w
  // v at w, log-log interpolated between the points; nullopt outside their band.
  std::optional<double> v_at(double w) const {
    if (points.empty() || w < points.front().w || w > points.back().w) return std::nullopt;
    auto hi = std::lower_bound(points.begin(), points.end(), w,
                               [](const NoisePoint& p, double x) { return p.w < x; });
    if (hi->w == w || hi == points.begin()) return hi->v;
    auto lo = hi - 1;
    const double t = std::log(w / lo->w) / std::log(hi->w / lo->w);
    return std::exp((1 - t) * std::log(lo->v) + t * std::log(hi->v));
  }
};

bool same_w(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(a, b); }

// The inputs' multisines as the diagnosis takes them (prepare.cc: the actuator curve's, else
// another curve of the input's) and, per input, its multisine lines.
struct Excitations {
  std::map<std::string, MultisineExcitation> ms;
  std::map<std::string, double> peak;  // the multisine's peak (its points' `amplitude`)
  std::map<std::string, std::vector<double>> lines;  // every curve's multisine lines, ascending
  // The experiments a multisine's line at w took: the inputs whose lines include w.
  int experiments(double w) const {
    int n = 0;
    for (const auto& [x, ws] : lines) {
      auto it = std::lower_bound(ws.begin(), ws.end(), w * (1 - 1e-9));
      n += it != ws.end() && same_w(*it, w);
    }
    return std::max(n, 1);
  }
};

Excitations excitations(const std::vector<MeasuredPair>& data) {
  Excitations e;
  e.ms = diag::input_multisines(data, [](const MeasuredPair& mp) { return &mp.frd; });
  for (bool actuator : {true, false})
    for (const MeasuredPair& mp : data) {
      const PairId id = PairId::parse(mp.pair);
      if (id.actuator() != actuator) continue;
      std::vector<double>& ws = e.lines[id.input];
      for (const FrdPoint& p : mp.frd.points)
        if (p.valid && p.line_amplitude > 0) {
          ws.push_back(p.w);
          e.peak.emplace(id.input, p.amplitude);  // one peak an input: its multisine's
        }
    }
  for (auto& [x, ws] : e.lines) {
    std::sort(ws.begin(), ws.end());
    ws.erase(std::unique(ws.begin(), ws.end(), same_w), ws.end());
  }
  return e;
}

std::string where(const MeasuredPair& mp, size_t i) {
  return mp.pair + " point " + std::to_string(i) + " (w " + std::to_string(mp.frd.points[i].w) +
         " rad/s)";
}

// The line of multisine `ms` at w, or ms.w.size().
size_t line_at(const MultisineExcitation& ms, double w) {
  size_t j = 0;
  while (j < ms.w.size() && !same_w(ms.w[j], w)) ++j;
  return j;
}

// The multisine of input x whose line a point without a line amplitude is: its frequency one of
// that multisine's lines and its amplitude that multisine's peak (a one-input multisine's
// position-relative pairs X:O, whose analyser sees the position, not the command); else null.
const MultisineExcitation* line_of(const FrdPoint& p, const std::string& x, const Excitations& e) {
  const auto it = e.ms.find(x);
  if (it == e.ms.end() || !(p.amplitude > 0) || !same_w(e.peak.at(x), p.amplitude) ||
      line_at(it->second, p.w) >= it->second.w.size())
    return nullptr;
  return &it->second;
}

// A point's command amplitude A on its line and the seconds T its estimate averages; `own_curve`
// the multisine of the point's curve (multisine_excitation of it).
std::pair<double, double> excitation_of(const MeasuredPair& mp, size_t i,
                                        const std::optional<MultisineExcitation>& own_curve,
                                        const Excitations& e) {
  const FrdPoint& p = mp.frd.points[i];
  if (p.n_cycles <= 0)
    throw InputError(where(mp, i) +
                     ": no n_cycles, so the seconds it was measured are unknown (the bound "
                     "needs curves as fralab's analyser writes them)");
  const MultisineExcitation* own = nullptr;
  double line_amplitude = p.line_amplitude;
  if (line_amplitude > 0) {
    if (!own_curve)
      throw InputError(where(mp, i) +
                       ": a multisine's line, but the curve's lines are no one period's harmonics");
    own = &*own_curve;
  } else if ((own = line_of(p, PairId::parse(mp.pair).input, e))) {
    line_amplitude = own->amplitude[line_at(*own, p.w)];
  } else {
    if (!(p.amplitude > 0))
      throw InputError(where(mp, i) + ": no excitation amplitude (the bound needs it)");
    return {p.amplitude, p.n_cycles * 2 * std::numbers::pi / p.w};
  }
  const double period_s = 2 * std::numbers::pi * own->k.at(line_at(*own, p.w)) / p.w;
  const double T = period_s * p.n_cycles * e.experiments(p.w) * std::max(p.realisations, 1);
  return {line_amplitude, T};
}

std::vector<NoisePair> noise_pairs(const Model& sim, const std::vector<MeasuredPair>& data,
                                   const Excitations& e, const EngineTimeBoundOptions& opt) {
  DiagnoseOptions usable_opt;
  usable_opt.max_rel_sigma = opt.max_rel_sigma;
  std::vector<NoisePair> out;
  for (const MeasuredPair& mp : data) {
    const PairId id = PairId::parse(mp.pair);
    if (!id.actuator() && !id.path()) continue;  // command pairs repeat X:O and u_X:X
    if (sim.input_index(id.input) < 0) continue;
    if (id.path() && (sim.output_index(id.output) < 0 || !sim.path(id.output, id.input))) continue;
    NoisePair np{mp.pair, id.input, {}};
    const std::optional<MultisineExcitation> own = multisine_excitation(mp.frd);
    for (size_t i = 0; i < mp.frd.points.size(); ++i) {
      const FrdPoint& p = mp.frd.points[i];
      if (!diag::usable(p, usable_opt)) continue;
      const auto [A, T] = excitation_of(mp, i, own, e);
      NoisePoint q;
      q.w = p.w;
      q.amplitude = p.amplitude;
      if (p.line_amplitude > 0)
        if (auto it = e.ms.find(id.input); it != e.ms.end()) q.ms = &it->second;
      q.sigma = p.sigma_noise > 0 ? p.sigma_noise : p.sigma;
      q.v = q.sigma * q.sigma * A * A * T;
      np.points.push_back(q);
    }
    std::sort(np.points.begin(), np.points.end(),
              [](const NoisePoint& a, const NoisePoint& b) { return a.w < b.w; });
    if (!np.points.empty()) out.push_back(std::move(np));
  }
  if (out.empty())
    throw InputError("no measured pair has a point the diagnosis uses (valid, with a sigma)");
  return out;
}

// A_i: the sine of the power the campaign gave each input (a sine's largest peak; a multisine's
// sqrt of its lines' summed squares).
std::map<std::string, double> input_amplitudes(const std::vector<MeasuredPair>& data,
                                               const Excitations& e) {
  std::map<std::string, double> a;
  for (const MeasuredPair& mp : data) {
    const std::string x = PairId::parse(mp.pair).input;
    for (const FrdPoint& p : mp.frd.points)
      if (p.valid && !(p.line_amplitude > 0) && p.amplitude > 0 && !line_of(p, x, e))
        a[x] = std::max(a[x], p.amplitude);
  }
  for (const auto& [x, ms] : e.ms) {
    double s = 0;
    for (double l : ms.amplitude) s += l * l;
    a[x] = std::max(a[x], std::sqrt(s));
  }
  return a;
}

// The extended model with parameter q of finding f moved by d (a moved pair's zeta with its
// to_zeta: the two are one value).
Model moved(const Model& sim, std::vector<Finding> findings, size_t f, Param q, double d) {
  Parameters& p = findings[f].parameters;
  p[q] += d;
  if (q == Param::kToZeta && p.count(Param::kZeta)) p[Param::kZeta] = p[q];
  return extend_model(sim, findings);
}

struct Derivative {
  Model plus, minus;
  double h = 0;
  const MeasurementChain* chain = nullptr;
  C at(const std::string& pair, double w, double amplitude, const MultisineExcitation* ms) const {
    const C a = model_pair_response(plus, pair, w, amplitude, *chain, ms).value_or(0.0);
    const C b = model_pair_response(minus, pair, w, amplitude, *chain, ms).value_or(0.0);
    return (a - b) / (2 * h);
  }
};

// The frequencies tried for the best sine on one input: its pairs' points and a log grid over
// their bands.
std::vector<double> grid(const std::vector<const NoisePair*>& pairs, int per_decade) {
  std::vector<double> ws;
  double lo = INFINITY, hi = 0;
  for (const NoisePair* p : pairs) {
    for (const NoisePoint& q : p->points) ws.push_back(q.w);
    lo = std::min(lo, p->points.front().w);
    hi = std::max(hi, p->points.back().w);
  }
  const int n = int(std::ceil(std::log10(hi / lo) * per_decade));
  for (int k = 0; k <= n; ++k) ws.push_back(lo * std::pow(hi / lo, n ? double(k) / n : 0.0));
  std::sort(ws.begin(), ws.end());
  return ws;
}

void best_sine(ParameterBound& b, const Derivative& d, const std::vector<NoisePair>& pairs,
               const std::map<std::string, double>& amplitude, int per_decade) {
  std::map<std::string, std::vector<const NoisePair*>> by_input;
  for (const NoisePair& p : pairs) by_input[p.input].push_back(&p);
  for (const auto& [x, ps] : by_input) {
    const auto a = amplitude.find(x);
    if (a == amplitude.end() || !(a->second > 0)) continue;
    const double A = a->second;
    for (double w : grid(ps, per_decade)) {
      double rate = 0;
      for (const NoisePair* p : ps)
        if (const auto v = p->v_at(w)) rate += std::norm(d.at(p->pair, w, A, nullptr)) / *v;
      rate *= A * A;
      if (rate > b.rate) {
        b.rate = rate;
        b.best_input = x;
        b.best_w_rad_s = w;
        b.best_amplitude = A;
      }
    }
  }
}

}  // namespace

EngineTimeBound engine_time_bound(const Model& sim, const std::vector<Finding>& findings,
                                  const std::vector<MeasuredPair>& data,
                                  const MeasurementChain& chain, double campaign_s,
                                  const EngineTimeBoundOptions& opt) {
  opt.validate();
  if (!(campaign_s > 0) || !std::isfinite(campaign_s))
    throw InputError(
        "engine time bound: the campaign's engine time must be a positive number, "
        "not " +
        std::to_string(campaign_s));
  const Excitations e = excitations(data);
  const std::vector<NoisePair> pairs = noise_pairs(sim, data, e, opt);
  EngineTimeBound r;
  r.campaign_s = campaign_s;
  r.input_amplitude = input_amplitudes(data, e);
  for (size_t f = 0; f < findings.size(); ++f)
    for (const auto& [q, interval] : findings[f].intervals) {
      const auto it = findings[f].parameters.find(q);
      if (it == findings[f].parameters.end()) continue;
      ParameterBound b;
      b.finding = f;
      b.parameter = q;
      b.value = it->second;
      Derivative d;
      d.h = std::max(opt.step_abs, opt.step_rel * std::abs(b.value));
      d.plus = moved(sim, findings, f, q, d.h);
      d.minus = moved(sim, findings, f, q, -d.h);
      d.chain = &chain;
      for (const NoisePair& p : pairs)
        for (const NoisePoint& pt : p.points)
          b.information +=
              std::norm(d.at(p.pair, pt.w, pt.amplitude, pt.ms)) / (pt.sigma * pt.sigma);
      if (!(b.information > 0)) continue;  // no measured pair carries it
      b.sigma_data = 1 / std::sqrt(b.information);
      best_sine(b, d, pairs, r.input_amplitude, opt.grid_per_decade);
      if (!(b.rate > 0)) continue;
      b.bound_s = b.information / b.rate;
      r.bound_s = std::max(r.bound_s, b.bound_s);
      r.parameters.push_back(b);
    }
  if (r.parameters.empty()) {
    r.message = "no finding has a fitted parameter the measured pairs carry: nothing to bound";
    return r;
  }
  r.status = EngineTimeBound::Status::kOk;
  r.ratio = campaign_s / r.bound_s;
  r.message = "the best sine needs " + std::to_string(r.bound_s) +
              " s of engine time to size every parameter as the campaign's " +
              std::to_string(campaign_s) + " s did";
  return r;
}

}  // namespace fralab
