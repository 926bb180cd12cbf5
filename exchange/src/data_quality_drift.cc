// The checks over a run's periods: drift and a clock error (data_quality_checks.h).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "data_quality_checks.h"
#include "fralab/core/numerics.h"

namespace fralab::dq {

// The fewest blocks of a sine step that give it a slope.
constexpr int kMinSineBlocks = 4;

namespace {

// The drift: each eighth of a multisine's period (a sine's blocks) by its mean, compared across
// the periods of one window: each eighth's own level is its group's offset, a drift the slope
// they share (eighths give the residuals enough degrees of freedom in a window of few periods).
// [t0, t1] is the span of the blocks the slope was taken over (seconds).
struct DriftFit {
  Slope slope;
  double t0 = INFINITY, t1 = -INFINITY;
};
DriftFit drift_of(const double* x, const TimeSeries& s, const std::vector<Window>& windows,
                  const std::vector<BlockValues>& values) {
  SlopeAccumulator drift;
  DriftFit fit;
  for (size_t i = 0; i < windows.size(); ++i) {
    const Window& w = windows[i];
    const BlockValues& v = values[i];
    const int J = w.multisine ? 8 : 1;
    for (int j = 0; j < J; ++j) {
      std::vector<double> tb, zb;
      for (size_t b = 0; b < v.mean.size(); ++b) {
        if (!std::isfinite(v.mean[b]) || v.y[b].empty()) continue;
        const int64_t a = w.block_len[b] * j / J, z = w.block_len[b] * (j + 1) / J;
        const double* xb = x + (w.block_from[b] - s.start_sample);
        double m = 0;
        for (int64_t n = a; n < z; ++n) m += xb[n] / double(z - a);
        tb.push_back((double(w.block_from[b]) + 0.5 * double(a + z)) / s.sample_rate_hz);
        zb.push_back(m);
      }
      if (tb.size() >= 2)
        fit.t0 = std::min(fit.t0, tb.front()), fit.t1 = std::max(fit.t1, tb.back());
      drift.add(tb, zb, 1.0);
    }
  }
  fit.slope = drift.solve(true);
  return fit;
}

// The blocks of window w whose phase a clock moves visibly: a clock moves phases, not power, so
// where a multisine's lines stand far above the noise (the strongest block's power over 100 times
// what its non-excited lines give them), a block with less than half that power (the channel dead
// or stuck for part of the window) has no phase to follow. A channel near its noise keeps every
// block: choosing its strongest would choose noise that agrees.
std::vector<size_t> phased_blocks(const Window& w, const BlockValues& v) {
  const std::vector<double>& power = v.power;
  const size_t strongest = size_t(std::max_element(power.begin(), power.end()) - power.begin());
  const bool visible = w.multisine && !v.y[strongest].empty() &&
                       power[strongest] > 100 * double(v.y[strongest].size()) * v.noise[strongest];
  std::vector<size_t> ok;
  for (size_t b = 0; b < v.y.size(); ++b)
    if (!v.y[b].empty() && (!visible || power[b] >= 0.5 * power[strongest])) ok.push_back(b);
  return ok;
}

// One pass of the clock's estimate: each block's delay against its window's mean (the blocks'
// phases first turned back by a clock eps0), from the lines in [fmin, fmax] Hz that stand 5 times
// above their noise, regressed on the blocks' times.
Slope clock_pass(const std::vector<Window>& windows, const std::vector<BlockValues>& values,
                 double eps0, double fmax, double fmin) {
  SlopeAccumulator acc;
  for (size_t i = 0; i < windows.size(); ++i) {
    const Window& w = windows[i];
    const BlockValues& v = values[i];
    const std::vector<size_t> ok = phased_blocks(w, v);
    // A sine's noise comes from its blocks' scatter: from fewer than four (three degrees of
    // freedom) it can be any size, and one window's chance agreement would outweigh the rest.
    if (ok.size() < (w.multisine ? 2u : size_t(kMinSineBlocks))) continue;
    double tbar = 0;
    for (size_t b : ok) tbar += v.t[b] / double(ok.size());
    const size_t F = w.freqs_hz.size();
    std::vector<std::vector<Complex>> y(ok.size(), std::vector<Complex>(F));
    std::vector<Complex> mean(F, 0.0);
    for (size_t j = 0; j < ok.size(); ++j)
      for (size_t k = 0; k < F; ++k) {
        const double om = 2 * kPi * w.freqs_hz[k];
        y[j][k] = v.y[ok[j]][k] * std::polar(1.0, om * eps0 * (v.t[ok[j]] - tbar));
        mean[k] += y[j][k] / double(ok.size());
      }
    std::vector<double> wk(F, 0.0);
    double W = 0, den = 0;
    // A block's noise power at a line: a multisine's from its non-excited lines (the phase
    // walk itself does not enter it), a sine's from the scatter over its blocks.
    double noise = 0;
    if (w.multisine)
      for (size_t b : ok) noise += v.noise[b] / double(ok.size());
    for (size_t k = 0; k < F; ++k) {
      if (w.freqs_hz[k] > fmax || w.freqs_hz[k] < fmin) continue;
      double var = noise;
      if (!w.multisine) {
        for (size_t j = 0; j < ok.size(); ++j) var += std::norm(y[j][k] - mean[k]);
        var /= double(ok.size() - 1);
      }
      if (!(std::norm(mean[k]) > 25 * var) || !(var > 0)) continue;
      const double om = 2 * kPi * w.freqs_hz[k];
      wk[k] = std::norm(mean[k]);
      den += wk[k] * om * om;
      W += 2 * om * om * std::norm(mean[k]) / var;
    }
    if (!(den > 0)) continue;
    std::vector<double> tb, zb;
    for (size_t j = 0; j < ok.size(); ++j) {
      double num = 0;
      for (size_t k = 0; k < F; ++k) {
        if (wk[k] == 0) continue;
        const double om = 2 * kPi * w.freqs_hz[k];
        num += wk[k] * om * std::arg(y[j][k] * std::conj(mean[k]));
      }
      tb.push_back(v.t[ok[j]]);
      zb.push_back(-num / den);
    }
    acc.add(tb, zb, W);
  }
  return acc.solve(false);
}

// The clock error of one channel, in two passes (the second on the first's residual, so that
// lines the first pass would wrap are used in the second), from the lines of the band's top 1.3
// decades: a clock walks a line's phase in proportion to its frequency, while a slow mode's
// leftover transient in a window's first period moves the low lines' phases most (over the lab's
// machine runs, a 2 s mode's made a clean channel's pooled estimate 7.6 sigma; without the lines
// below a twentieth of the top, at most 4.8 sigma).
Slope clock_of(const std::vector<Window>& windows, const std::vector<BlockValues>& values) {
  double fmax_all = 0;
  for (const Window& w : windows)
    for (double f : w.freqs_hz) fmax_all = std::max(fmax_all, f);
  const double fmin = fmax_all / 20;
  Slope c1 = clock_pass(windows, values, 0.0, fmax_all / 4, fmin);
  if (c1.blocks == 0) c1 = clock_pass(windows, values, 0.0, fmax_all, fmin);
  Slope c = c1;
  if (c1.blocks > 0) {
    Slope c2 = clock_pass(windows, values, c1.value, fmax_all, fmin);
    if (c2.blocks > 0) c = Slope{c1.value + c2.value, c2.sigma, c2.blocks};
  }
  return c;
}

// A fault of channel ch sized by a slope over [t0, t1] seconds, mended.
DataFault sloped(const std::string& ch, DataFaultKind kind, const Slope& sl, double t0, double t1) {
  DataFault f;
  f.channel = ch;
  f.kind = kind;
  f.size = sl.value;
  f.sigma = sl.sigma;
  f.from_s = t0;
  f.to_s = t1;
  f.mended = true;
  return f;
}

// The clock fault of channel ch from this run's estimate c, pooled (weights 1 / sigma^2) with the
// campaign's other runs' of the same channel that agree with it within 4 sigma of their
// difference (all of them where this run has none: a sine of two-cycle steps); this run's
// estimate is appended to clocks. [t0, t1]: the span of this run's windows (infinite for none).
void report_clock(const std::string& ch, const Slope& c, double t0, double t1, const TimeSeries& s,
                  const DataQualityOptions& o, std::vector<DataFault>* out,
                  std::vector<ClockEstimate>* clocks) {
  const bool own = c.blocks > 0 && c.sigma > 0;
  std::vector<ClockEstimate> agreeing;
  if (own) {
    clocks->push_back({ch, c.value, c.sigma, std::isfinite(t0) ? 0.5 * (t0 + t1) : 0.0, ""});
    agreeing.push_back(clocks->back());
  }
  int others = 0;
  for (const ClockEstimate& e : o.other_runs) {
    if (e.channel != ch || !(e.sigma > 0)) continue;
    if (own && std::abs(e.eps - c.value) > 4 * std::hypot(e.sigma, c.sigma)) continue;
    agreeing.push_back(e);
    ++others;
  }
  const auto pool = pool_clocks(agreeing);
  if (pool.empty()) return;
  const Slope pooled{pool.begin()->second.eps, pool.begin()->second.sigma, c.blocks};
  if (!(std::abs(pooled.value) > o.clock_sigmas * pooled.sigma &&
        std::abs(pooled.value) > o.min_clock))
    return;
  if (!std::isfinite(t0)) {  // no window of its own: the run's span
    t0 = double(s.start_sample) / s.sample_rate_hz;
    t1 = double(s.start_sample + s.n_samples) / s.sample_rate_hz;
  }
  DataFault f = sloped(ch, DataFaultKind::kClock, pooled, t0, t1);
  const std::string rate = fmt(pooled.value * 1e3) + " ms more each second (+-" +
                           fmt(pooled.sigma * 1e3) + "), a clock " +
                           fmt(std::abs(pooled.value) * 100) + " % " +
                           (pooled.value > 0 ? "fast" : "slow") + " against the excitation's";
  if (!own)
    f.text = ch + "'s samples lag " + rate + " in the campaign's other runs (" +
             std::to_string(others) + "); this run's windows are too short to see it";
  else if (others == 0)
    f.text = ch + "'s phase walks with time: its samples lag " + rate;
  else
    f.text = ch + "'s phase walks with time: its samples lag " + rate + ", this run's " +
             fmt(c.value * 1e3) + " +- " + fmt(c.sigma * 1e3) + " with the campaign's other " +
             "runs (" + std::to_string(others) + ")";
  f.action =
      "resampled on the excitation's clock (taken to agree at sample 0: an offset between the "
      "clocks is a delay the data cannot tell from the plant's)";
  out->push_back(std::move(f));
}

}  // namespace

void check_drift_and_clock(const std::string& ch, const double* x, const TimeSeries& s,
                           const std::vector<Window>& windows,
                           const std::vector<BlockValues>& values, const DataQualityOptions& o,
                           std::vector<DataFault>* out, std::vector<ClockEstimate>* clocks) {
  const DriftFit drift = drift_of(x, s, windows, values);
  const Slope c = clock_of(windows, values);
  const Slope& d = drift.slope;
  const double t0 = drift.t0, t1 = drift.t1;
  if (d.blocks > 0 && std::abs(d.value) > o.drift_sigmas * d.sigma) {
    DataFault f = sloped(ch, DataFaultKind::kDrift, d, t0, t1);
    f.text = ch + " drifts by " + fmt(d.value) + " units per second (+-" + fmt(d.sigma) +
             ") within the excitation's periods: " + fmt(d.value * (t1 - t0)) + " over the run";
    f.action = "the straight line removed before the Fourier filter";
    out->push_back(std::move(f));
  }
  report_clock(ch, c, t0, t1, s, o, out, clocks);
}

}  // namespace fralab::dq
