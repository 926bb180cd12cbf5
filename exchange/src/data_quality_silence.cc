// The checks for spans without response: whole blocks, and eighths of periods
// (data_quality_checks.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "data_quality_checks.h"
#include "fralab/core/numerics.h"

namespace fralab::dq {

void check_no_response(const std::string& ch, const TimeSeries& s,
                       const std::vector<Window>& windows, const std::vector<BlockValues>& values,
                       std::vector<DataFault>* out) {
  // Per excitation signature, the blocks' ratio of excited-line power to the noise.
  struct Item {
    double t0, t1, ratio;
    std::string sig;
  };
  std::vector<Item> items;
  std::map<std::string, std::vector<double>> by_sig;
  for (size_t i = 0; i < windows.size(); ++i) {
    const Window& w = windows[i];
    if (!w.multisine) continue;
    const BlockValues& v = values[i];
    for (size_t b = 0; b < v.y.size(); ++b) {
      if (v.y[b].empty() || !(v.noise[b] > 0)) continue;
      const double r = v.power[b] / double(v.y[b].size()) / v.noise[b];
      const double t0 = double(w.block_from[b]) / s.sample_rate_hz;
      items.push_back({t0, t0 + double(w.block_len[b]) / s.sample_rate_hz, r, w.signature});
      by_sig[w.signature].push_back(r);
    }
  }
  std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) { return a.t0 < b.t0; });
  std::map<std::string, double> typical;
  for (auto& [sig, r] : by_sig) {  // the upper quartile: a channel dead for most of a run too
    std::sort(r.begin(), r.end());
    typical[sig] = r[r.size() * 3 / 4];
  }
  for (size_t i = 0; i < items.size();) {
    if (!(typical[items[i].sig] > 30 && items[i].ratio < 4)) {
      ++i;
      continue;
    }
    size_t e = i;
    while (e + 1 < items.size() && typical[items[e + 1].sig] > 30 && items[e + 1].ratio < 4) ++e;
    DataFault f;
    f.channel = ch;
    f.kind = DataFaultKind::kNoResponse;
    f.from_s = items[i].t0;
    f.to_s = items[e].t1;
    f.size = f.to_s - f.from_s;
    const bool to_end = e + 1 == items.size();
    f.text = ch + " holds no more than its noise at the excited lines from " + fmt(f.from_s) +
             " s" + (to_end ? " to the end of the run" : " to " + fmt(f.to_s) + " s") +
             ", where the same excitation gives " + fmt(10 * std::log10(typical[items[i].sig])) +
             " dB elsewhere: " +
             (to_end ? "a dead channel" : "an actuator stuck or a sensor silent for a while");
    // The span set aside, with the period either side (the fault began or ended within it): the
    // windows holding them give invalid points, naming the samples.
    const double a = i > 0 ? items[i - 1].t0 : f.from_s, z = to_end ? f.to_s : items[e + 1].t1;
    f.spans.emplace_back(int64_t(std::llround(a * s.sample_rate_hz)),
                         int64_t(std::llround(z * s.sample_rate_hz)) - 1);
    f.mended = true;
    f.action = "set aside from " + fmt(a) + " to " + fmt(z) +
               " s (a period either side): the windows holding it give no points";
    out->push_back(std::move(f));
    i = e + 1;
  }
}

// A stretch's variance about its mean over half the variance of its first differences: white
// noise gives 1, a response well above the noise far more. NaN when a sample is NaN; 0 for a
// stretch holding one value (a noise-free channel's dead end).
double variance_ratio(const double* x, int64_t n) {
  double m = 0, md = 0;
  for (int64_t k = 0; k < n; ++k) m += x[k] / double(n);
  for (int64_t k = 1; k < n; ++k) md += (x[k] - x[k - 1]) / double(n - 1);
  double v = 0, vd = 0;
  for (int64_t k = 0; k < n; ++k) v += (x[k] - m) * (x[k] - m);
  for (int64_t k = 1; k < n; ++k) vd += (x[k] - x[k - 1] - md) * (x[k] - x[k - 1] - md);
  v /= double(n);
  vd /= double(n - 1);
  if (!std::isfinite(v) || !std::isfinite(vd)) return std::nan("");
  if (vd == 0) return v == 0 ? 0.0 : INFINITY;
  return v / (0.5 * vd);
}

// Silent stretches inside periods: a multisine's response repeats every period, so each eighth
// of a measured period is compared with the same eighth of the window's other periods and of
// the settle's last period (a reference only: it shows the response where every measured
// period is already dead). An eighth at the noise (variance_ratio below kSilentRatio) where
// another period's same eighth stands well above it (above kLiveRatio) is silent; two or more
// silent eighths in a row, not already inside a span named by check_no_response, are a span
// without response (a channel that died within a period, or before the first measured one).
constexpr double kSilentRatio = 1.5, kLiveRatio = 30.0;
constexpr int kEighths = 8;

namespace {

// One eighth of a multisine period (samples, absolute) and how it compares with the same eighth
// of the window's other periods.
struct Eighth {
  int64_t from, to, period_from, period_to;
  bool shown;   // another period's same eighth stands above the noise (kLiveRatio)
  bool silent;  // shown, and this one at the noise
  double live;  // the largest ratio of the same eighth over the window's periods
};

// Every multisine window's measured periods cut into eighths, each with its variance ratio
// against the same eighth of the window's other periods (the settle's last one included where the
// series holds it), in time order.
std::vector<Eighth> period_eighths(const double* x, const TimeSeries& s,
                                   const std::vector<Window>& windows) {
  std::vector<Eighth> eighths;
  for (const Window& w : windows) {
    if (!w.multisine) continue;
    std::vector<int64_t> starts = w.block_from;
    const bool ref = w.reference_from >= 0;
    if (ref) starts.insert(starts.begin(), w.reference_from);
    std::vector<std::vector<double>> r(starts.size(), std::vector<double>(kEighths));
    for (size_t b = 0; b < starts.size(); ++b)
      for (int j = 0; j < kEighths; ++j) {
        const int64_t a = starts[b] + int64_t(w.period) * j / kEighths,
                      z = starts[b] + int64_t(w.period) * (j + 1) / kEighths;
        r[b][size_t(j)] = variance_ratio(x + (a - s.start_sample), z - a);
      }
    for (size_t b = ref ? 1 : 0; b < starts.size(); ++b)
      for (int j = 0; j < kEighths; ++j) {
        double live = 0;
        for (size_t c = 0; c < starts.size(); ++c)
          if (std::isfinite(r[c][size_t(j)])) live = std::max(live, r[c][size_t(j)]);
        const int64_t a = starts[b] + int64_t(w.period) * j / kEighths,
                      z = starts[b] + int64_t(w.period) * (j + 1) / kEighths;
        const bool shown = live > kLiveRatio;
        eighths.push_back({a, z, starts[b], starts[b] + w.period, shown,
                           shown && r[b][size_t(j)] < kSilentRatio, live});
      }
  }
  std::sort(eighths.begin(), eighths.end(),
            [](const Eighth& a, const Eighth& b) { return a.from < b.from; });
  return eighths;
}

}  // namespace

void check_silent_eighths(const std::string& ch, const double* x, const TimeSeries& s,
                          const std::vector<Window>& windows, std::vector<DataFault>* out) {
  const std::vector<Eighth> eighths = period_eighths(x, s, windows);
  const double fs = s.sample_rate_hz;
  auto named = [&](const Eighth& e) {
    for (const DataFault& f : *out)
      if (f.channel == ch && f.kind == DataFaultKind::kNoResponse && double(e.to) / fs > f.from_s &&
          double(e.from) / fs < f.to_s)
        return true;
    return false;
  };
  // A silent stretch runs over eighths that no period shows (nothing to compare there) and ends
  // at the first one shown and not silent.
  for (size_t i = 0; i < eighths.size();) {
    if (!eighths[i].silent || named(eighths[i])) {
      ++i;
      continue;
    }
    size_t e = i, j = i + 1, n_silent = 1;
    double live = eighths[i].live;
    for (; j < eighths.size() && (eighths[j].silent || !eighths[j].shown) && !named(eighths[j]);
         ++j) {
      if (!eighths[j].silent) continue;
      e = j;
      ++n_silent;
      live = std::min(live, eighths[j].live);
    }
    // A silent stretch running into a span already named is that span's start, inside the period
    // it sets aside before it.
    if (n_silent < 2 || (j < eighths.size() && named(eighths[j]))) {
      i = j;
      continue;
    }
    const bool to_end = j == eighths.size();
    DataFault f;
    f.channel = ch;
    f.kind = DataFaultKind::kNoResponse;
    f.from_s = double(eighths[i].from) / fs;
    f.to_s = double(to_end ? eighths.back().to : eighths[e].to) / fs;
    f.size = f.to_s - f.from_s;
    f.text = ch + " stays at its noise from " + fmt(f.from_s) + " s" +
             (to_end ? " to the end of the run" : " to " + fmt(f.to_s) + " s") +
             " where the same part of another period of the excitation varies " + fmt(live) +
             " times as much: " +
             (to_end ? "a dead channel" : "an actuator stuck or a sensor silent for a while");
    // The periods holding it set aside whole (a period partly silent is no period).
    const int64_t a = eighths[i].period_from,
                  z = to_end ? s.start_sample + s.n_samples : eighths[e].period_to;
    f.spans.emplace_back(a, z - 1);
    f.mended = true;
    f.action = "set aside from " + fmt(double(a) / fs) + " to " + fmt(double(z) / fs) +
               " s (the periods holding it): the windows holding it give no points";
    out->push_back(std::move(f));
    i = j;
  }
}

}  // namespace fralab::dq
