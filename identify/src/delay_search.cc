#include "delay_search.h"

#include <algorithm>
#include <cmath>

#include "fralab/core/numerics.h"

namespace fralab::tfns_detail {

double delay_ambiguity(const std::vector<double>& w) {
  std::vector<double> v(w);
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  if (v.size() < 2) return INFINITY;
  std::vector<double> dw(v.size() - 1);
  for (size_t i = 0; i + 1 < v.size(); ++i) dw[i] = v[i + 1] - v[i];
  std::nth_element(dw.begin(), dw.begin() + dw.size() / 2, dw.end());
  return 2 * M_PI / dw[dw.size() / 2];
}

namespace {

// The coarse grid's runner-up is kept when its error is within this factor of the best's: a grid
// that (2, 2) cannot tell apart. A relative degree of 7 with a 25 ms delay at 10 % noise has
// minima at 28 and 74 ms within 1 %, and searched around 74 ms alone the order loop misses the
// delay.
constexpr double kAltRatio = 1.1;
// Brent's method searches the coarse grid's best +- 1 step to 2^-16 of the delay (~12
// evaluations).
constexpr int kCoarseBits = 17;

std::vector<C> remove_delay(const Data& d, double tau) {
  std::vector<C> g(d.g);
  for (size_t i = 0; i < g.size(); ++i) g[i] *= std::polar(1.0, d.w[i] * tau);
  return g;
}

}  // namespace

DelaySearch::DelaySearch(const Data& d, const FitOptions& o)
    : d_(d),
      o_(o),
      ws_(std::sqrt(d.w.front() * d.w.back())),
      window_(std::min(o.max_delay_s / 100, 0.5e-3)) {}

const std::vector<C>& DelaySearch::without_delay(double tau) {
  auto it = undelayed_.find(tau);
  if (it == undelayed_.end()) it = undelayed_.emplace(tau, remove_delay(d_, tau)).first;
  return it->second;
}

std::pair<double, Sk> DelaySearch::sk_at(double tau, int n, int m, const FitOptions& oo,
                                         const std::vector<C>* den_start) {
  Sk sk = sk_fit(d_, without_delay(tau), n, m, ws_, oo, den_start);
  if (!sk.ok) return std::make_pair(1e300, sk);
  sk.tf.delay_s = tau;
  return std::make_pair(score(d_, sk.tf).sse, sk);
}

double DelaySearch::sk_sse(double tau, int n, int m, const FitOptions& oo) {
  const Sk sk = sk_fit(d_, without_delay(tau), n, m, ws_, oo, nullptr, false);
  return sk.ok && std::isfinite(sk.sse) ? sk.sse : 1e300;
}

double DelaySearch::coarse(double top) {
  top = std::min(top, o_.max_delay_s);
  if (coarse_tau_ >= 0 && top == coarse_top_) return coarse_tau_;
  // SK's error at (2, 2) after 3 iterations: on the random identification benchmark (seeds 1-5)
  // it finds the same delays as the min of (2, 1) and (2, 2) in half the time, and the same
  // orders and delays as 6 iterations with the grid a third faster.
  FitOptions quick = o_;
  quick.max_iterations = 3;
  auto err_at = [&](double tau) { return sk_sse(tau, 2, 2, quick); };
  const int G =
      std::clamp(int(std::ceil(top * d_.w.back() / 3.0)) + 1, top < o_.max_delay_s ? 6 : 16, 100);
  std::vector<double> errs(G);
  for (int k = 0; k < G; ++k) errs[k] = err_at(top * k / (G - 1));
  const int kb = int(std::min_element(errs.begin(), errs.end()) - errs.begin());
  const double bt = top * kb / (G - 1);
  // The runner-up: the lowest local minimum of the grid more than two steps from the best, kept
  // when within kAltRatio of it.
  coarse_alt_ = -1;
  double ea = INFINITY;
  for (int k = 1; k + 1 < G; ++k) {
    if (std::abs(k - kb) <= 2 || errs[k] > errs[k - 1] || errs[k] > errs[k + 1]) continue;
    if (errs[k] < ea) ea = errs[k], coarse_alt_ = top * k / (G - 1);
  }
  if (ea > kAltRatio * errs[kb]) coarse_alt_ = -1;
  const double step = top / (G - 1);
  const double lo = std::max(0.0, bt - step), hi = std::min(top, bt + step);
  coarse_tau_ = detail::brent_minimum(err_at, lo, hi, kCoarseBits);
  coarse_top_ = top;
  return coarse_tau_;
}

void DelaySearch::forget() { coarse_tau_ = coarse_top_ = coarse_alt_ = -1; }

// SK's error is spiky in tau: the joint refinement from several separated starts finds a basin
// that one start can miss. The grid lies on multiples of the window, the nearest to the centre in
// its middle, so which points rank best does not hang on the centre's last digits (centred on tau0
// itself, a coarse delay 3e-10 s different takes the J85 tape's u_Wf:P3 from 9/9 with chi^2/dof 1.2
// to max_order_reached at 7/7).
std::vector<double> DelaySearch::starts(double tau0, int n, size_t n_starts) {
  FitOptions quick = o_;
  quick.max_iterations = 6;
  std::vector<std::pair<double, double>> grid;  // (err, tau)
  std::vector<double> centres = {tau0};
  if (coarse_alt_ >= 0) centres.push_back(coarse_alt_);
  for (const double c0 : centres) {
    for (int k = -10; k <= 10; ++k) {
      const double t = (std::round(c0 / window_) + k) * window_;
      if (t >= 0 && t <= o_.max_delay_s) grid.push_back({sk_sse(t, n, n, quick), t});
    }
  }
  std::sort(grid.begin(), grid.end());
  std::vector<double> out;
  for (const auto& [e, t] : grid) {
    bool far = true;
    for (double u : out) far = far && std::abs(u - t) > 1.5 * window_;
    if (far) out.push_back(t);
    if (out.size() == n_starts) break;
  }
  return out;
}

ImitatedDelay imitated_delay(const Tf& t, const std::vector<double>& w, double max_delay) {
  ImitatedDelay r;
  for (const Root& z : t.zeros) {
    if (!(z.pair ? z.zeta < 0 : z.real > 0)) continue;
    double tz = z.pair ? 4 * std::abs(z.zeta) / z.wn : 2 / z.real;
    for (const double wi : w) {
      const double lag =
          z.pair ? 2 * std::atan2(2 * std::abs(z.zeta) * z.wn * wi, z.wn * z.wn - wi * wi)
                 : 2 * std::atan(wi / z.real);
      tz = std::max(tz, lag / wi);
    }
    if (tz > max_delay) continue;
    r.any = true;
    r.tau += tz;
  }
  return r;
}

}  // namespace fralab::tfns_detail
