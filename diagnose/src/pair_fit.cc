#include "pair_fit.h"

#include <algorithm>
#include <cmath>

#include "fralab/core/numerics.h"
#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"

namespace fralab::diag {

bool usable(const FrdPoint& p, const DiagnoseOptions& o) {
  return p.valid && p.sigma > 0 && p.mag > 0 && p.sigma <= o.max_rel_sigma * p.mag;
}

std::map<std::string, MultisineExcitation> input_multisines(
    const std::vector<MeasuredPair>& data,
    const std::function<const Frd*(const MeasuredPair&)>& curve) {
  std::map<std::string, MultisineExcitation> out;
  for (bool actuator : {true, false})
    for (const MeasuredPair& mp : data) {
      const PairId id = PairId::parse(mp.pair);
      if (id.actuator() != actuator || out.count(id.input)) continue;
      if (const Frd* f = curve(mp))
        if (auto ms = multisine_excitation(*f)) out.emplace(id.input, std::move(*ms));
    }
  return out;
}

void add_point(PairFit& p, const FrdPoint& pt, C sim, const DiagnoseOptions& o) {
  p.w.push_back(pt.w);
  p.meas.push_back(pt.value());
  p.sim.push_back(sim);
  p.amp.push_back(pt.amplitude);
  p.h3.push_back(pt.h3_rel);
  p.line_amp.push_back(pt.line_amplitude);
  p.nl.push_back(pt.nl_rel);
  p.realisations.push_back(pt.realisations);
  const double wh = o.chain.sample_rate_hz > 0 ? pt.w / o.chain.sample_rate_hz : 0.0;
  p.sig.push_back(std::hypot(pt.sigma, (o.sigma_floor + o.aliasing_floor * wh * wh) * pt.mag));
  p.factor.push_back(1.0);
}

double chi2(const PairFit& p, const std::vector<C>& F) {
  double c = 0;
  for (size_t i = 0; i < p.w.size(); ++i)
    c += std::norm(p.meas[i] - p.sim[i] * p.factor[i] * F[i]) / (p.sig[i] * p.sig[i]);
  return c;
}

std::vector<C> factor_of(const std::vector<double>& w, const std::function<C(C)>& f) {
  std::vector<C> F;
  for (double x : w) F.push_back(f(C(0, x)));
  return F;
}

double minimise_1d(const std::function<double(double)>& f, double lo, double hi, int grid) {
  double best = lo, fb = INFINITY;
  for (int k = 0; k <= grid; ++k) {
    double x = lo + (hi - lo) * k / grid, v = f(x);
    if (v < fb) fb = v, best = x;
  }
  const double step = (hi - lo) / grid;
  return detail::brent_minimum(f, std::max(lo, best - step), std::min(hi, best + step));
}

std::string fmt(double v, int prec) { return significant(v, prec); }

}  // namespace fralab::diag
