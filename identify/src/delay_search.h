// Internal to the identify library: the delay searches of fit_tf, and the SK fits of the data with
// a trial delay removed that score them (docs/method/identifier.md, step 6). Not installed.
#pragma once

#include <cstddef>
#include <map>
#include <utility>
#include <vector>

#include "fit_data.h"
#include "fralab/identify/tfns.h"
#include "sk_fit.h"

namespace fralab::tfns_detail {

// The longest delay the grid w (rad/s) can tell apart from a shorter one: 2 pi / the median spacing
// of its sorted distinct frequencies (seconds; +inf with fewer than 2). On a uniform grid of
// spacing dw, the delays tau and tau + 2 pi / dw differ at every point by a whole turn times the
// point's index, a constant phase over a zoom band: a delay longer than this is an alias (a VNA's
// 100 MHz grid cannot see 10 ns). The median, not the smallest spacing: one close pair of points
// does not resolve a delay the rest of the grid aliases.
double delay_ambiguity(const std::vector<double>& w);

// A delay shows as right-half-plane zeros or as a misfit. It is searched at a low order first
// (coarse: a short rational cannot imitate a large high-frequency phase lag, so the error has a
// clear minimum near the delay), then per order around that (starts: the joint refinement's
// starting delays), then jointly with the roots in refine().
//
// Holds the data by reference: their weights change between calls (once the noise is estimated,
// and when sigma is scaled), and every fit is made with the weights of the moment.
class DelaySearch {
 public:
  DelaySearch(const Data& d, const FitOptions& o);

  // The data's values with delay tau removed, kept per tau (the order loop's delay grids visit the
  // same delays at every order and numerator order).
  const std::vector<C>& without_delay(double tau);

  // SK's fit at orders (n, m) of the data with delay tau removed, with tau as its delay, and its
  // error as a model of roots (score's sse; 1e300 when SK failed). den_start: SK's first
  // denominator (sk_fit.h).
  std::pair<double, Sk> sk_at(double tau, int n, int m, const FitOptions& oo,
                              const std::vector<C>* den_start = nullptr);

  // Only the error of SK's fit at (n, m) with delay tau removed, SK's own last sum (no roots, no
  // model evaluation; 1e300 when SK failed): the delay grids' measure.
  double sk_sse(double tau, int n, int m, const FitOptions& oo);

  // The coarse search over [0, top] (top <= max_delay_s: the whole range unless a cheaper hint
  // says where a delay can be): a grid of SK errors at (2, 2) whose phase step at the top
  // frequency stays below ~3 rad, then Brent's method within one step of its best. The last search
  // is remembered: the same top returns its delay without searching again.
  double coarse(double top);
  // The last coarse search's runner-up local minimum (< 0: none).
  double runner_up() const { return coarse_alt_; }
  // Forgets the last coarse search (the weights have changed).
  void forget();

  // The n_starts best separated points of a grid of SK errors at (n, n) over tau0 +- 10 windows,
  // and over the runner-up +- 10 windows when there is one: the joint refinement's starting delays
  // at order n.
  std::vector<double> starts(double tau0, int n, size_t n_starts);

  // SK's frequency scale, sqrt(w_min w_max) (tfns.h, step 1).
  double ws() const { return ws_; }

 private:
  const Data& d_;
  const FitOptions& o_;
  double ws_;
  double window_;  // the starts' grid step
  std::map<double, std::vector<C>> undelayed_;
  double coarse_tau_ = -1, coarse_top_ = -1;  // the last coarse search (< 0: none)
  double coarse_alt_ = -1;                    // its runner-up (< 0: none)
};

// The delay a fit's right-half-plane zeros can imitate: per zero, the largest over the band of its
// all-pass phase lag over w, or its group delay at low frequency (2/z for a real zero, 4 |zeta| /
// wn for a pair), summed over the zeros imitating at most max_delay (a larger one is not a
// delay's). any: there is such a zero.
struct ImitatedDelay {
  bool any = false;
  double tau = 0;
};
ImitatedDelay imitated_delay(const Tf& t, const std::vector<double>& w, double max_delay);

}  // namespace fralab::tfns_detail
