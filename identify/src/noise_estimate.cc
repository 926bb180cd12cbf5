#include "noise_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "fralab/identify/noise_model.h"
#include "sk_fit.h"

namespace fralab::tfns_detail {

namespace {

// An over-fit's error is that of its model as roots (the form every fit is refined and judged in:
// noise-free data are estimated at the precision such a model reaches), unless rooting lost more
// than this factor over its polynomials' own error. An over-fit of a low order is degenerate
// (near-cancelling couples that root finding does not resolve): the rooted model of one misfits
// noise-free 85 % A8:P5 data by 537 %, and judged against that level a 0/1 fit with 0.9 % error
// passes as converged.
constexpr double kRootedSlack = 100;

// The noise level from the over-fits: the lowest error per degree of freedom of SK at orders (n,
// n) well above any the order loop accepts.
struct OverFitLevel {
  double s2 = INFINITY;  // the relative level squared (the data weighted by 1 / |g_i|^2)
  double dof = 1e9;      // the degrees of freedom it comes with
  Tf over;               // the over-fit it comes from, as roots (its delay)
  int over_n = -1;  // its order (n, n); < 0: none, or a degenerate one (its roots' error is not its
                    // polynomials')
};

// Over-fits at the two highest orders of one parity the points allow (up to 14), without a delay
// (or with the fixed one), and with delay auto also with the coarse delay removed. Not when the
// delay-free over-fits are already at the floor: the estimate cannot go lower, and only the
// slack's dof could differ (that of the other over-fit order, moving 1 + 2/sqrt(dof) by ~1 %: no
// case of the random identification benchmark changes); the coarse grid over the whole delay range
// is then left to the order search, if it searches a delay. A coarse delay below 0.05 rad at the
// top frequency is no delay: tau = 0 has served.
OverFitLevel over_fit_level(const Data& d, const FitOptions& o, DelaySearch& delays) {
  OverFitLevel l;
  const int N = int(d.w.size());
  const int n_hi = std::min(14, (N - 3) / 2);
  FitOptions oo = o;
  oo.max_iterations = 12;
  auto over_fit = [&](double tau) {
    for (int n = n_hi; n >= std::max(1, n_hi - 2); n -= 2) {
      const auto [rooted, sk] = delays.sk_at(tau, n, n, oo);
      const bool as_roots = rooted <= kRootedSlack * sk.sse;
      const double sse = as_roots ? rooted : sk.sse;
      const double dof = N - (2 * n + 1) / 2.0;
      if (dof < 2 || !(sse < 1e300)) continue;
      if (sse / dof < l.s2) {
        l.s2 = sse / dof, l.dof = dof;
        l.over = sk.tf;
        l.over_n = as_roots ? n : -1;
      }
    }
  };
  over_fit(o.delay == FitOptions::Delay::kFixed ? o.delay_s : 0.0);
  if (o.delay == FitOptions::Delay::kAuto && !(l.s2 <= o.noise_floor * o.noise_floor) &&
      delays.coarse(o.max_delay_s) * d.w.back() > 0.05)
    over_fit(delays.coarse(o.max_delay_s));
  return l;
}

// The noise's shape, for a level from a sound over-fit above the floor: three hypotheses, each
// judged by the restricted likelihood of the data under its own over-fit (the level's, at its order
// and delay, weighted for that hypothesis): relative, sigma_i = s |g_i| (that over-fit itself);
// absolute, sigma_i = b (weighted flat); and, when the flat over-fit's residuals, each with the
// variance that fit leaves it, are better explained by sigma_i^2 = a^2 |g_i|^2 + b^2
// (fit_noise_model's test), that shape (weighted by it). One replaces the relative `noise` when it
// beats it by 2 x NoiseFitOptions::evidence in -2 l (a likelihood ratio of e^5); its level is its
// restricted scale times its shape.
// Not the relative over-fit's residuals alone: weighted by 1 / |g_i|^2, the points where the data
// are noise take all the weight and the fit is far from linear elsewhere (an estimate 0.35-1.3x the
// level in noise_model_test). Nor the flat over-fit's alone: on relative noise its residuals are
// 30-90 chi^2 units better explained with an absolute part (SK weighted flat fits the points of
// small |G| to a floor), which the restricted likelihoods then refuse by 90-600 (the random
// benchmark's seeds 1-3 at 2 % without sigma).
NoiseModel noise_shape(const Data& d, const FitOptions& o, DelaySearch& delays,
                       const OverFitLevel& l, NoiseModel noise) {
  std::vector<double> mag2(d.w.size());  // the relative shape, as d.W's
  for (size_t i = 0; i < d.w.size(); ++i) mag2[i] = std::max(std::norm(d.g[i]), 1e-300);
  FitOptions oo = o;
  oo.max_iterations = 12;  // as the over-fits'
  // |g_i - fit(j w_i)|^2 at every point.
  auto residuals = [&](const Tf& fit) {
    std::vector<double> e2(d.w.size());
    for (size_t i = 0; i < d.w.size(); ++i) e2[i] = std::norm(d.g[i] - fit.at(d.w[i]));
    return e2;
  };
  // The over-fit with weights W, its residuals and their noise model (not ok: no fit).
  struct OverFit {
    bool ok = false;
    Tf fit;
    std::vector<double> e2;
    NoiseFit nf;
  };
  auto over_fit_at = [&](const std::vector<double>& W) {
    OverFit r;
    Data dw = d;
    dw.W = W;
    const Sk sk =
        sk_fit(dw, delays.without_delay(l.over.delay_s), l.over_n, l.over_n, delays.ws(), oo);
    if (!sk.ok) return r;
    r.fit = sk.tf;
    r.fit.delay_s = l.over.delay_s;
    if (!(score(dw, r.fit).sse <= kRootedSlack * sk.sse)) return r;
    r.e2 = residuals(r.fit);
    r.nf = fit_noise_model(r.e2, mag2, residual_variance(dw.w, dw.W, mag2, r.fit));
    r.ok = r.nf.ok;
    return r;
  };
  const Restricted h_rel = restricted_likelihood(d.w, residuals(l.over), mag2, l.over);
  const std::vector<double> ones(d.w.size(), 1.0);
  const OverFit flat = over_fit_at(ones);
  double best = h_rel.m2l - 2 * NoiseFitOptions{}.evidence;
  if (flat.ok) {
    const Restricted h_add = restricted_likelihood(d.w, flat.e2, ones, flat.fit);
    if (h_add.rank == h_rel.rank && h_add.m2l < best) {
      best = h_add.m2l;
      noise = NoiseModel{0, std::sqrt(h_add.scale)};
    }
  }
  if (flat.ok && flat.nf.absolute_part && flat.nf.mixed.rel > 0) {
    std::vector<double> u(d.w.size()), W(d.w.size());
    for (size_t i = 0; i < d.w.size(); ++i) {
      const double mag = std::sqrt(mag2[i]);
      u[i] = std::pow(std::max(flat.nf.mixed.sigma(mag), o.noise_floor * mag), 2);
      W[i] = 1 / u[i];
    }
    const OverFit mixed = over_fit_at(W);
    if (mixed.ok) {
      const Restricted h_mix = restricted_likelihood(d.w, mixed.e2, u, mixed.fit);
      if (h_mix.rank == h_rel.rank && h_mix.m2l < best) {
        best = h_mix.m2l;
        const double k = std::sqrt(h_mix.scale);
        noise = NoiseModel{k * flat.nf.mixed.rel, k * flat.nf.mixed.abs};
      }
    }
  }
  return noise;
}

}  // namespace

bool estimate_noise(Data& d, const FitOptions& o, DelaySearch& delays, FitResult& res) {
  OverFitLevel l;
  if (o.tolerance > 0)
    l.s2 = o.tolerance * o.tolerance;
  else
    l = over_fit_level(d, o, delays);
  if (!std::isfinite(l.s2)) return true;
  NoiseModel noise;  // the relative level s alone, or with an absolute part
  noise.rel = std::max(std::sqrt(l.s2), o.noise_floor);
  // The shape is estimated only from a level the data gave: not at the floor (noise-free data),
  // with a tolerance imposed, or from a degenerate over-fit.
  if (!(o.tolerance > 0) && l.over_n > 0 && noise.rel > o.noise_floor)
    noise = noise_shape(d, o, delays, l, noise);
  res.noise_rel = noise.rel;
  if (noise.abs > 0) res.noise_abs = noise.abs;
  d.has_sigma = true;
  d.chi2_slack = 1.0 + 2.0 / std::sqrt(l.dof);
  for (size_t i = 0; i < d.w.size(); ++i) {
    const double mag = std::max(std::abs(d.g[i]), 1e-300);
    d.sigma[i] = std::max(noise.sigma(mag), o.noise_floor * mag);
    d.W[i] = 1.0 / (d.sigma[i] * d.sigma[i]);
  }
  // The rule for a sigma given (prepare_data in tfns.cc): a path that is noise (relative noise of
  // 30 % or more at every point, or an absolute part above 30 % of |g| at all but 2 points). Not
  // with a tolerance imposed: that is the user's level, not the data's.
  if (!(o.tolerance > 0)) {
    int clear = 0;
    for (size_t i = 0; i < d.w.size(); ++i) clear += d.sigma[i] <= 0.3 * std::abs(d.g[i]);
    if (clear < 3) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "no response above the noise estimated without sigma (%.3g relative, %.3g "
                    "absolute): %d of %zu points above it by 3.3x or more",
                    noise.rel, noise.abs, clear, d.w.size());
      res.status = FitResult::Status::kNoResponse;
      res.message = buf;
      return false;
    }
  }
  return true;
}

std::string noise_note(const FitResult& res) {
  if (!(res.noise_abs > 0)) return "";
  char buf[160];
  std::snprintf(buf, sizeof buf,
                "; noise estimated without sigma: %.3g relative, %.3g absolute (the ratio's "
                "units)",
                res.noise_rel, res.noise_abs);
  return buf;
}

}  // namespace fralab::tfns_detail
