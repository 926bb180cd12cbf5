#include "fralab/analyze/repeats.h"

#include <algorithm>
#include <cmath>
#include <complex>

#include "fralab/core/json_util.h"

namespace fralab {

namespace {

FrdPoint combine(const FrdPoint& a, const FrdPoint& b) {
  const double wa = 1 / (a.sigma * a.sigma), wb = 1 / (b.sigma * b.sigma), W = wa + wb;
  const std::complex<double> g = (wa * a.value() + wb * b.value()) / W;
  FrdPoint p = a;
  p.mag = std::abs(g);
  p.phase_deg = std::arg(g) * 180 / M_PI;
  // The phase stays on the branch of the first measurement (the curve's unwrapping).
  p.phase_deg += 360 * std::round((a.phase_deg - p.phase_deg) / 360);
  p.sigma = 1 / std::sqrt(W);
  auto mean = [&](double x, double y) { return (wa * x + wb * y) / W; };
  if (a.coherence >= 0 && b.coherence >= 0) p.coherence = mean(a.coherence, b.coherence);
  p.h2_rel = mean(a.h2_rel, b.h2_rel);
  p.h3_rel = mean(a.h3_rel, b.h3_rel);
  p.n_cycles = a.n_cycles + b.n_cycles;
  return p;
}

}  // namespace

Frd merge_repeated(const Frd& base, const Frd& more) {
  if (base.pair != more.pair)
    throw InputError("merging repeated measurements of " + base.pair + " with " + more.pair);
  Frd out = base;
  for (const FrdPoint& q : more.points) {
    auto usable = [](const FrdPoint& p) { return p.valid && p.sigma > 0; };
    auto it = std::find_if(out.points.begin(), out.points.end(), [&](const FrdPoint& p) {
      return usable(p) && p.input == q.input && p.step == q.step &&
             std::abs(p.w - q.w) <= 1e-9 * q.w;
    });
    if (it != out.points.end() && usable(q))
      *it = combine(*it, q);
    else
      out.points.push_back(q);
  }
  std::stable_sort(out.points.begin(), out.points.end(),
                   [](const FrdPoint& a, const FrdPoint& b) { return a.w < b.w; });
  return out;
}

}  // namespace fralab
