#include "random_frd.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

namespace fralab::testing {
namespace {

using Rng = std::mt19937_64;

double uni(Rng& g, double a, double b) { return std::uniform_real_distribution<double>(a, b)(g); }
double loguni(Rng& g, double a, double b) { return std::exp(uni(g, std::log(a), std::log(b))); }
int irange(Rng& g, int a, int b) { return std::uniform_int_distribution<int>(a, b)(g); }
double freq(const Root& r) { return r.pair ? r.wn : std::abs(r.real); }

// `count` roots (pairs and reals) with frequencies log-uniform in [lo, hi], at least `sep` apart in
// log-frequency from each other and from `avoid`; zeta in [z_lo, z_hi] for pairs.
std::vector<Root> draw_roots(Rng& g, int count, double lo, double hi, double z_lo, double z_hi,
                             bool lhp, const std::vector<Root>& avoid, double sep = 0.15) {
  for (int attempt = 0;; ++attempt) {
    std::vector<Root> out;
    int left = count;
    while (left > 0) {
      const double w = loguni(g, lo, hi);
      if (left >= 2 && uni(g, 0, 1) < 0.5) {
        out.push_back(Root::Pair(w, (lhp ? 1 : -1) * uni(g, z_lo, z_hi)));
        left -= 2;
      } else {
        out.push_back(Root::Real(lhp ? -w : w));
        left -= 1;
      }
    }
    bool ok = true;
    for (size_t i = 0; i < out.size() && ok; ++i) {
      for (size_t j = 0; j < i && ok; ++j)
        ok = std::abs(std::log(freq(out[i]) / freq(out[j]))) > sep;
      for (const Root& a : avoid) ok = ok && std::abs(std::log(freq(out[i]) / freq(a))) > sep;
    }
    if (ok || attempt > 200) return out;
  }
}

}  // namespace

RandomFrdCase random_frd_case(int index, double noise, bool sigma_given, uint64_t seed,
                              NoiseKind kind) {
  Rng g(seed * 1000003u + uint64_t(index) * 7919u);
  RandomFrdCase c;
  c.noise = noise;
  c.kind = kind;
  c.sigma_given = sigma_given && noise > 0;
  c.w_lo = 2 * std::numbers::pi * 0.05;  // the lab's band: 0.05-100 Hz
  c.w_hi = 2 * std::numbers::pi * 100;
  const double lo = c.w_lo * 1.5, hi = c.w_hi / 1.5;
  int points = irange(g, 40, 60);
  Tf& t = c.truth;
  t.gain = loguni(g, 0.1, 10.0);
  const int cat = index % kRandomCategories;
  auto generic = [&](int n_min, int n_max) {
    const int n = irange(g, n_min, n_max), m = irange(g, 0, n);
    t.poles = draw_roots(g, n, lo, hi, 0.1, 0.7, true, {});
    t.zeros = draw_roots(g, m, lo, hi, 0.1, 0.9, true, t.poles, 0.25);
  };
  switch (cat) {
    case 0:
      c.category = "generic";
      generic(1, 8);
      break;
    case 1: {  // two resonances 2-10 % apart, lightly damped
      c.category = "close resonances";
      const double w = loguni(g, lo * 2, hi / 2), r = 1 + uni(g, 0.02, 0.10);
      t.poles = {Root::Pair(w, uni(g, 0.005, 0.05)), Root::Pair(w * r, uni(g, 0.005, 0.05))};
      if (irange(g, 0, 1)) t.poles.push_back(Root::Real(-loguni(g, lo, hi)));
      // a zero pair between them (antiresonance) or none
      if (irange(g, 0, 1)) t.zeros = {Root::Pair(w * std::sqrt(r), uni(g, 0.01, 0.05))};
      if (std::abs(std::log(freq(t.poles.back()) / w)) < 0.3) t.poles.back() = Root::Real(-hi);
      break;
    }
    case 2: {  // right-half-plane zeros
      c.category = "rhp zeros";
      generic(2, 7);
      const auto rhp = draw_roots(g, irange(g, 1, 2), lo, hi, 0.2, 0.8, false, t.poles, 0.25);
      if (int(t.zeros.size()) > 0) t.zeros.pop_back();
      for (const Root& z : rhp) t.zeros.push_back(z);
      while (t.num_order() > t.den_order()) t.zeros.erase(t.zeros.begin());
      break;
    }
    case 3: {  // poles spread over four decades (beyond the band's 3.3 at both ends)
      c.category = "four decades";
      const int n = irange(g, 3, 6);
      t.poles = draw_roots(g, n, c.w_lo * 0.5, c.w_lo * 0.5 * 1e4, 0.1, 0.7, true, {}, 0.3);
      t.zeros = draw_roots(g, irange(g, 0, n - 1), lo, hi, 0.2, 0.9, true, t.poles, 0.3);
      break;
    }
    case 4: {  // a pole 2-10x outside the band
      c.category = "pole outside";
      generic(1, 5);
      const double f = loguni(g, 2, 10);
      t.poles.push_back(Root::Real(-(irange(g, 0, 1) ? c.w_hi * f : c.w_lo / f)));
      break;
    }
    case 5:
      c.category = "sparse grid";
      generic(1, 6);
      points = irange(g, 20, 30);
      break;
    case 6:
      c.category = "delay";
      generic(1, 5);
      t.delay_s = uni(g, 0.010, 0.030);
      break;
    default:  // high relative degree with a delay on a sparse grid
      c.category = "rel. degree + delay";
      t.poles = draw_roots(g, irange(g, 4, 7), lo, hi, 0.2, 0.7, true, {});
      if (irange(g, 0, 1)) t.zeros = draw_roots(g, 1, lo, hi, 0.2, 0.9, true, t.poles, 0.25);
      t.delay_s = uni(g, 0.010, 0.030);
      points = irange(g, 25, 35);
      break;
  }
  // Noise: its own stream (the truth above does not depend on it).
  Rng gn(seed * 31u + uint64_t(index) * 104729u + uint64_t(std::llround(noise * 1e6)));
  std::normal_distribution<double> nd(0.0, std::sqrt(0.5));
  auto w_at = [&](int i) { return c.w_lo * std::pow(c.w_hi / c.w_lo, double(i) / (points - 1)); };
  double peak = 0;
  for (int i = 0; i < points; ++i) peak = std::max(peak, std::abs(t.at(w_at(i))));
  for (int i = 0; i < points; ++i) {
    const double w = w_at(i);
    std::complex<double> v = t.at(w);
    const double s = noise * (kind == NoiseKind::kAdditive ? peak : std::abs(v));
    if (noise > 0) v += std::complex<double>(nd(gn), nd(gn)) * s;
    FrdPoint p;
    p.w = w;
    p.mag = std::abs(v);
    p.phase_deg = std::arg(v) * 180 / std::numbers::pi;
    if (c.sigma_given) p.sigma = s;
    c.points.push_back(p);
  }
  return c;
}

double model_error(const Tf& fit, const Tf& truth, double w_lo, double w_hi, int n) {
  double s = 0;
  for (int i = 0; i < n; ++i) {
    const double w = w_lo * std::pow(w_hi / w_lo, double(i) / (n - 1));
    const std::complex<double> gt = truth.at(w);
    s += std::norm(fit.at(w) - gt) / std::norm(gt);
  }
  return std::sqrt(s / n);
}

}  // namespace fralab::testing
