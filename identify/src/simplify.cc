#include "simplify.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <utility>
#include <vector>

#include "output_error.h"

namespace fralab::tfns_detail {

namespace {

// Pruning thresholds: a pole-zero couple closer than this fraction of the pole's modulus, a root
// with at least this relative sigma. On the random identification benchmark (seeds 1-5) pruning
// brings a 2/5 pair of close resonances at 2 % noise back to its orders from 7/10 with three
// couples within 0.3 % (the truth's criterion 91 against 127), raises the orders found right at
// 2-5 % noise by 3-7 points on seeds 3, 4 and 5, and lowers them nowhere.
// The sigma threshold is 0.5 / sqrt(2): it was tuned on sigmas that, with the data's sigma, were
// sqrt(2) too large, and keeps the same roots.
constexpr double kPruneNear = 0.5, kPruneSigma = 0.5 / std::numbers::sqrt2;
// A cancelling dipole: a zero and a pole of one kind closer than this fraction of the pole's
// modulus.
constexpr double kDipole = 1e-3;
// A light pair: |zeta| below this. It is physical only when the grid resolves it: at least
// kResolvePoints points within kResolveBand half-power half-widths (zeta wn) of wn. Noise fitted
// by a sharp pair between two points has no point on its peak; a measured light mode (a
// microwave resonator's Q of 50 000 in a zoom band, a structure's 0.03 % damped mode on 1 Hz
// lines) has its peak sampled. On the log-spaced grids of a stepped sine (a few % apart) no pair
// below 1e-3 can have two points within 0.4 % of wn, so such grids keep refusing every light pair.
constexpr double kLight = 1e-3, kResolveBand = 2;
constexpr int kResolvePoints = 2;
// A dipole of light roots: a zero and a pole closer than this fraction of their real parts (the
// couple changes the response by at most that fraction anywhere). Relative to the modulus, as
// kDipole is, a notch resonator's pole and zero (0.001 % apart, a 30 dB dip) would be a cancelling
// couple.
constexpr double kLightDipole = 0.01;
// The criterion (chi^2 units) by which a right-half-plane zero above the band must beat the lag it
// imitates: a likelihood ratio of e, the lower edge of "positive" evidence on Kass and Raftery's
// scale. On the random benchmark's seeds 1-10 (1920 fits), 0 gives 1 fit more at its orders, and
// 1, 2 or 3 the same 10 more; none is lost with any.
constexpr double kLagEvidence = 1.0;

// A root's location in the upper half plane (a pair's upper member).
C upper(const Root& r) {
  const C l = r.locations()[0];
  return l.imag() < 0 ? std::conj(l) : l;
}

// How close zero z is to pole p, relative to |p|: between their upper-half-plane locations, a pair
// against a pair and a real root against a real root; +inf between kinds.
double couple_distance(const Root& z, const Root& p) {
  if (z.pair != p.pair) return INFINITY;
  const C lp = upper(p);
  return std::abs(upper(z) - lp) / std::abs(lp);
}

}  // namespace

int reflect_unstable(Tf& t) {
  int k = 0;
  for (Root& p : t.poles) {
    if (p.pair && p.zeta <= 0) {
      p.zeta = std::max(-p.zeta, 1e-6);
      ++k;
    }
    if (!p.pair && p.real >= 0) {
      p.real = -std::max(p.real, 1e-9);
      ++k;
    }
  }
  return k;
}

bool light(const Root& r) { return r.pair && std::abs(r.zeta) < kLight; }

bool resolved(const Root& r, const std::vector<double>& w) {
  const double half = kResolveBand * std::abs(r.zeta) * r.wn;
  int inside = 0;
  for (double wi : w)
    if (std::abs(wi - r.wn) <= half && ++inside >= kResolvePoints) return true;
  return false;
}

double dipole_measure(const Root& z, const Root& p) {
  if (z.pair != p.pair) return INFINITY;
  if (!light(z) && !light(p)) return couple_distance(z, p) / kDipole;
  const double width = std::max(std::abs(upper(z).real()), std::abs(upper(p).real()));
  return std::abs(upper(z) - upper(p)) / (kLightDipole * width);
}

bool nonphysical(const Tf& t, const std::vector<double>& w) {
  for (const Root& p : t.poles)
    if (light(p) && !resolved(p, w)) return true;
  for (const Root& z : t.zeros)
    if (light(z) && !resolved(z, w)) return true;
  for (const Root& z : t.zeros)
    for (const Root& p : t.poles)
      if (dipole_measure(z, p) < 1) return true;
  return false;
}

bool remove_dipoles(Tf& t) {
  bool any = false;
  for (;;) {
    int bi = -1, bj = -1;
    double bd = 1;
    for (size_t i = 0; i < t.zeros.size(); ++i) {
      for (size_t j = 0; j < t.poles.size(); ++j) {
        const double dd = dipole_measure(t.zeros[i], t.poles[j]);
        if (dd < bd) bd = dd, bi = int(i), bj = int(j);
      }
    }
    if (bi < 0) return any;
    t.zeros.erase(t.zeros.begin() + bi);
    t.poles.erase(t.poles.begin() + bj);
    any = true;
  }
}

bool orders_allowed(const Tf& t, const FitOptions& o) {
  return t.num_order() >= o.min_num_order && t.den_order() >= o.den_order_start &&
         t.num_order() <= t.den_order();
}

void prune(Candidate& fit, const Data& d, const FitOptions& o, const RefineCandidate& refine) {
  for (bool better = true; better;) {
    better = false;
    std::vector<std::pair<int, int>> cuts;  // (zero index or -1, pole index or -1)
    for (size_t i = 0; i < fit.tf.zeros.size(); ++i) {
      int jb = -1;
      double db = kPruneNear;
      for (size_t j = 0; j < fit.tf.poles.size(); ++j) {
        const double dist = couple_distance(fit.tf.zeros[i], fit.tf.poles[j]);
        if (dist < db) db = dist, jb = int(j);
      }
      if (jb >= 0) cuts.push_back({int(i), jb});
    }
    const Sigmas sg = parameter_sigmas(d, fit.tf, fit.free_delay, fit.s.sse);
    for (size_t i = 0; i < sg.zeros.size(); ++i)
      if (!(sg.zeros[i] < kPruneSigma)) cuts.push_back({int(i), -1});
    for (size_t j = 0; j < sg.poles.size(); ++j)
      if (!(sg.poles[j] < kPruneSigma)) cuts.push_back({-1, int(j)});
    Candidate next = fit;
    for (const auto& [i, j] : cuts) {
      Candidate c = fit;
      if (i >= 0) c.tf.zeros.erase(c.tf.zeros.begin() + i);
      if (j >= 0) c.tf.poles.erase(c.tf.poles.begin() + j);
      if (!orders_allowed(c.tf, o)) continue;
      refine(c);
      if (c.adequate != next.adequate ? c.adequate
                                      : (c.adequate ? c.crit < next.crit : c.rank < next.rank)) {
        next = c;
        better = true;
      }
    }
    if (better) fit = next;
  }
}

// A real right-half-plane zero above the band imitates there the lag of a pole at the same
// frequency: 1 - s/z and 1 / (1 + s/z) have the same phase, -atan(w/z), and magnitudes that differ
// by (w/z)^2 / 2 (3 % at w/z = 0.25). At 5-10 % noise the data cannot tell them apart and the
// search keeps whichever its starts reached (on the random benchmark's seeds 1-10, a pole 2-10x
// above the band comes back as a zero in 10 of 1920 fits, every one with a criterion within 0.4 of
// the lag's). So a non-minimum-phase zero needs evidence a lag does not: each such zero is replaced
// by the pole and the rest refined, and the lag is kept unless the zero's criterion is lower by
// kLagEvidence or more. Only with a sigma given or estimated: under TFNS's c_n rule the criterion
// cannot compare them.
void prefer_lags(Candidate& fit, const Data& d, const RefineCandidate& refine, std::string* note) {
  if (!d.has_sigma) return;
  for (bool again = true; again;) {
    again = false;
    for (size_t i = 0; i < fit.tf.zeros.size() && !again; ++i) {
      const Root z = fit.tf.zeros[i];
      if (z.pair || !(z.real > d.w.back())) continue;
      Candidate c = fit;
      c.tf.zeros.erase(c.tf.zeros.begin() + long(i));
      c.tf.poles.push_back(Root::Real(-z.real));
      refine(c);
      if (c.nonphysical || (fit.adequate && !c.adequate) || c.crit >= fit.crit + kLagEvidence)
        continue;
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "; the right-half-plane zero at %.4g rad/s above the band is the lag it "
                    "imitates (criterion %.4g against %.4g)",
                    z.real, c.crit, fit.crit);
      *note += buf;
      fit = c;
      again = true;
    }
  }
}

}  // namespace fralab::tfns_detail
