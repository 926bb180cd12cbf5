// The sample-level checks: lost samples, clipping, held runs (data_quality_checks.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "data_quality_checks.h"
#include "fralab/core/numerics.h"

namespace fralab::dq {

// Whether the channel carries noise: white noise's 4th differences change sign from one sample
// to the next four times in five (their lag-1 correlation is -56/70), a smooth signal's keep
// theirs; more than three in five sign changes over the nonzero ones, noise dominates. Counting
// signs, a noise-free channel's rare kinks (a backlash's reversals) do not decide. A noise-free
// channel (a simulation's position without sensor noise) holds a value exactly where the plant
// does (a backlash's dwell, an actuator at its stop): repeats and flat tops are then the plant's.
bool noisy(const double* x, int64_t N) {
  int64_t pairs = 0, changes = 0;
  double prev = 0;
  // From first differences, which are exactly 0 over a flat stretch (the samples' own sum
  // leaves a rounding residue of one sign there: a clipped stretch read as a smooth signal).
  auto d = [x](int64_t k) { return x[k] - x[k - 1]; };
  for (int64_t k = 4; k < N; ++k) {
    const double v = d(k) - 3 * d(k - 1) + 3 * d(k - 2) - d(k - 3);
    if (!std::isfinite(v) || v == 0) {
      prev = 0;
      continue;
    }
    if (prev != 0) {
      ++pairs;
      changes += (v > 0) != (prev > 0);
    }
    prev = v;
  }
  return pairs >= 10 && double(changes) > 0.6 * double(pairs);
}

void check_lost(const std::string& ch, const double* x, const TimeSeries& s,
                const DataQualityOptions& o, std::vector<DataFault>* out) {
  DataFault f;
  int64_t lost = 0, mended = 0;
  const int64_t max_gap = int64_t(std::llround(o.max_gap_s * s.sample_rate_hz));
  for (int64_t k = 0; k < s.n_samples;) {
    if (!std::isnan(x[k])) {
      ++k;
      continue;
    }
    int64_t e = k;
    while (e + 1 < s.n_samples && std::isnan(x[e + 1])) ++e;
    lost += e - k + 1;
    if (e - k + 1 <= max_gap) {
      f.spans.emplace_back(s.start_sample + k, s.start_sample + e);
      mended += e - k + 1;
    }
    if (lost == e - k + 1) f.from_s = double(s.start_sample + k) / s.sample_rate_hz;
    f.to_s = double(s.start_sample + e + 1) / s.sample_rate_hz;
    k = e + 1;
  }
  if (lost == 0) return;
  f.channel = ch;
  f.kind = DataFaultKind::kLost;
  f.size = double(lost) / double(s.n_samples);
  f.level = double(mended);
  f.mended = mended > 0;
  f.text = std::to_string(lost) + " samples of " + ch + " are missing (" + fmt(100 * f.size) +
           " % of the run)";
  f.action = mended == lost
                 ? "interpolated between the samples either side"
                 : std::to_string(mended) + " interpolated (gaps up to " + fmt(o.max_gap_s) +
                       " s); the windows holding longer gaps give invalid points";
  out->push_back(std::move(f));
}

// Clipping at the largest and the smallest value; returns them (held runs there are clipping).
std::pair<double, double> check_clipping(const std::string& ch, const double* x,
                                         const TimeSeries& s, std::vector<DataFault>* out) {
  double hi = -INFINITY, lo = INFINITY;
  for (int64_t k = 0; k < s.n_samples; ++k)
    if (std::isfinite(x[k])) hi = std::max(hi, x[k]), lo = std::min(lo, x[k]);
  if (!(hi > lo)) return {hi, lo};
  for (int side = 0; side < 2; ++side) {
    const double level = side == 0 ? hi : lo;
    // The next value inside: how many share it (a quantised channel's neighbour level).
    double next = side == 0 ? -INFINITY : INFINITY;
    int64_t at = 0, first = -1, last = -1;
    for (int64_t k = 0; k < s.n_samples; ++k) {
      if (!std::isfinite(x[k])) continue;
      if (x[k] == level) {
        ++at;
        if (first < 0) first = k;
        last = k;
      } else if (side == 0 ? x[k] > next : x[k] < next) {
        next = x[k];
      }
    }
    int64_t at_next = 0;
    for (int64_t k = 0; k < s.n_samples; ++k) at_next += x[k] == next;
    if (at < std::max<int64_t>(20, 3 * at_next + 3) || double(at) < 1e-4 * double(s.n_samples))
      continue;
    DataFault f;
    f.channel = ch;
    f.kind = DataFaultKind::kClipping;
    f.size = double(at) / double(s.n_samples);
    f.level = level;
    f.from_s = double(s.start_sample + first) / s.sample_rate_hz;
    f.to_s = double(s.start_sample + last + 1) / s.sample_rate_hz;
    f.text = ch + " sits at its " + (side == 0 ? "largest" : "smallest") + " value " + fmt(level) +
             " in " + std::to_string(at) + " samples (" + fmt(100 * f.size) +
             " % of the run): a transducer or converter at its range";
    f.mended = true;
    f.action =
        "the clipped samples inside the integration windows replaced by the least-squares fit "
        "of the excited lines to the samples inside the range, period by period (a sine step "
        "over its window); a stretch with too few samples left gives invalid points";
    out->push_back(std::move(f));
  }
  return {hi, lo};
}

void check_held(const std::string& ch, const double* x, const TimeSeries& s, double hi, double lo,
                const DataQualityOptions& o, std::vector<DataFault>* out) {
  const int64_t N = s.n_samples;
  std::vector<double> d;
  double q = INFINITY;
  for (int64_t k = 1; k < N; ++k) {
    if (!std::isfinite(x[k]) || !std::isfinite(x[k - 1])) continue;
    const double v = x[k] - x[k - 1];
    d.push_back(v);
    if (v != 0) q = std::min(q, std::abs(v));
  }
  if (d.size() < 10 || !std::isfinite(q)) return;
  // A quantised channel's steps are whole multiples of its resolution q; a continuous one's
  // smallest step is no resolution at all (repeats then have probability 0).
  int64_t multiples = 0;
  for (double v : d) {
    const double r = std::abs(v) / q;
    multiples += r <= 1e4 && std::abs(r - std::round(r)) < 0.01;
  }
  if (double(multiples) < 0.9 * double(d.size())) q = 0;
  const double med = median(d);
  for (double& v : d) v = std::abs(v - med);
  const double sd = 1.4826 * median(d);
  if (!(sd > 0)) return;
  const double p = std::min(1.0, q / (sd * std::sqrt(2 * kPi)));
  // The shortest run of repeats a clean channel of this resolution holds fewer than 0.01 times.
  int Lmin = 1;
  while (Lmin < 1000 && double(N) * std::pow(p, Lmin) >= 0.01) ++Lmin;
  if (Lmin >= 1000) return;  // so coarse a channel repeats by itself
  DataFault f;
  int64_t held = 0;
  const int64_t max_gap = int64_t(std::llround(o.max_gap_s * s.sample_rate_hz));
  for (int64_t k = 1; k < N;) {
    if (!(x[k] == x[k - 1]) || x[k] == hi || x[k] == lo) {
      ++k;
      continue;
    }
    int64_t e = k;
    while (e + 1 < N && x[e + 1] == x[k]) ++e;
    const int64_t L = e - k + 1;
    if (L >= Lmin) {
      held += L;
      if (L <= max_gap) f.spans.emplace_back(s.start_sample + k, s.start_sample + e);
      if (held == L) f.from_s = double(s.start_sample + k) / s.sample_rate_hz;
      f.to_s = double(s.start_sample + e + 1) / s.sample_rate_hz;
    }
    k = e + 1;
  }
  if (held < 3) return;
  int64_t mended = 0;
  for (const auto& [a, b] : f.spans) mended += b - a + 1;
  f.channel = ch;
  f.kind = DataFaultKind::kHeld;
  f.size = double(held) / double(N);
  f.level = double(mended);
  f.mended = mended > 0;
  f.text = std::to_string(held) + " samples of " + ch + " repeat the one before (" +
           fmt(100 * f.size) + " % of the run; " +
           (Lmin == 1
                ? std::string("a continuous channel does not repeat")
                : "its resolution makes a run of " + std::to_string(Lmin) + " repeats improbable") +
           "): a link that held its last value";
  f.action = "the repeated samples interpolated between the good ones either side";
  out->push_back(std::move(f));
}

}  // namespace fralab::dq
