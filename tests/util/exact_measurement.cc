#include "exact_measurement.h"

#include <cmath>
#include <complex>
#include <numbers>
#include <random>

namespace fralab::testing {

std::vector<MeasuredPair> exact_measurement(const Model& engine, const std::vector<double>& w,
                                            uint64_t seed, double rel_sigma) {
  using C = std::complex<double>;
  std::mt19937_64 fit_rng(seed), val_rng(seed + 1);
  std::normal_distribution<double> nd(0, std::sqrt(0.5));
  auto curve = [&](size_t o, size_t i, std::mt19937_64& rng) {
    Frd f;
    f.pair = engine.inputs[i].name + ":" + engine.outputs[o].name;
    for (double wq : w) {
      const C g = engine.position_to_output(int(o), int(i), wq);
      if (std::abs(g) == 0) continue;
      const C v = g + rel_sigma * std::abs(g) * C(nd(rng), nd(rng));
      FrdPoint p;
      p.w = wq, p.mag = std::abs(v), p.phase_deg = std::arg(v) * 180 / std::numbers::pi;
      p.sigma = rel_sigma * std::abs(g);
      f.points.push_back(p);
    }
    return f;
  };
  std::vector<MeasuredPair> out;
  for (size_t o = 0; o < engine.outputs.size(); ++o)
    for (size_t i = 0; i < engine.inputs.size(); ++i) {
      if (!engine.path(engine.outputs[o].name, engine.inputs[i].name)) continue;
      MeasuredPair mp;
      mp.frd = curve(o, i, fit_rng);
      mp.pair = mp.frd.pair;
      mp.validation = curve(o, i, val_rng);
      out.push_back(mp);
    }
  return out;
}

}  // namespace fralab::testing
