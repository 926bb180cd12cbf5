// The mending of a channel: gaps interpolated, hum and drift taken out, clipped and missing
// samples filled from the excited lines, a clock resampled, spans without response set aside
// (data_quality_checks.h).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "data_quality_checks.h"
#include "fralab/core/numerics.h"

namespace fralab::dq {

// The blocks overlapping a span set aside (spans of `faults`) emptied, as a block holding a NaN
// sample is: the period comparisons pass them over.
void leave_out_spans(const std::vector<Window>& windows, const std::vector<DataFault>& faults,
                     std::vector<BlockValues>& values) {
  for (size_t i = 0; i < windows.size(); ++i)
    for (size_t b = 0; b < windows[i].block_from.size(); ++b) {
      const int64_t a = windows[i].block_from[b], z = a + windows[i].block_len[b] - 1;
      for (const DataFault& f : faults)
        for (const auto& [from, to] : f.spans)
          if (a <= to && z >= from) {
            values[i].y[b].clear();
            values[i].power[b] = 0;
            values[i].mean[b] = std::nan("");
          }
    }
}

// Linear interpolation over [a, b] (sample indices into the series) from the samples either side.
void interpolate(double* x, int64_t N, int64_t a, int64_t b) {
  const double left = a > 0 ? x[a - 1] : (b + 1 < N ? x[b + 1] : 0.0);
  const double right = b + 1 < N ? x[b + 1] : left;
  for (int64_t k = a; k <= b; ++k)
    x[k] = left + (right - left) * double(k - a + 1) / double(b - a + 2);
}

// The least-squares basis of a window's steady response at local sample n: 1, then cos and sin of
// each excited line (a multisine's bins k of its period; a sine's frequency and its 2nd and 3rd
// harmonics, and a straight line for what settles within the window).
constexpr int kSineHarmonics = 3;

int basis_size(const Window& w) {
  return w.multisine ? 1 + 2 * int(w.lines.size()) : 2 + 2 * kSineHarmonics;
}

void basis_row(const Window& w, int64_t n, double fs, double* a) {
  a[0] = 1.0;
  int j = 1;
  if (w.multisine) {
    for (int k : w.lines) {
      const double ph = 2 * kPi * double((int64_t(k) * n) % w.period) / w.period;
      a[j++] = std::cos(ph);
      a[j++] = std::sin(ph);
    }
    return;
  }
  a[j++] = double(n) / double(w.to - w.from);
  for (int h = 1; h <= kSineHarmonics; ++h) {
    const double ph = 2 * kPi * h * w.freqs_hz[0] * double(n) / fs;
    a[j++] = std::cos(ph);
    a[j++] = std::sin(ph);
  }
}

// Missing samples (missing[n]: missing, or a gap's) inside one stretch [from, from + len) of window
// w replaced by the least-squares fit of w's basis to the stretch's other samples, evaluated over
// [from, until); a stretch whose samples kept are fewer than twice the basis, or hold a NaN, gets
// NaN there instead (its window then gives invalid points).
void fill_stretch(double* x, const std::vector<bool>& missing, const Window& w, int64_t from,
                  int64_t len, int64_t until, double fs) {
  if (std::find(missing.begin() + from, missing.begin() + until, true) == missing.begin() + until)
    return;
  const int m = basis_size(w);
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(m), a(m);
  int64_t kept = 0;
  bool finite = true;
  for (int64_t n = 0; n < len; ++n) {
    if (missing[size_t(from + n)]) continue;
    finite = finite && std::isfinite(x[from + n]);
    basis_row(w, n, fs, a.data());
    G.selfadjointView<Eigen::Lower>().rankUpdate(a);
    b += a * x[from + n];
    ++kept;
  }
  Eigen::VectorXd c;
  if (finite && kept >= 2 * m) {
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(G.selfadjointView<Eigen::Lower>());
    if (ldlt.info() == Eigen::Success) c = ldlt.solve(b);
  }
  const bool ok = c.size() == m && c.allFinite();
  for (int64_t n = 0; n < until - from; ++n) {
    if (!missing[size_t(from + n)]) continue;
    basis_row(w, n, fs, a.data());
    x[from + n] = ok ? a.dot(c) : std::numeric_limits<double>::quiet_NaN();
  }
}

// Every missing sample inside the windows filled: a multisine period by period (a window's last,
// partial period from the whole one before it), a sine step over its whole window.
void fill_missing(double* x, const TimeSeries& s, const std::vector<Window>& windows,
                  const std::vector<bool>& missing) {
  const double fs = s.sample_rate_hz;
  for (const Window& w : windows) {
    const int64_t a = w.from - s.start_sample, z = w.to - s.start_sample;
    if (!w.multisine) {
      fill_stretch(x, missing, w, a, z - a, z, fs);
      continue;
    }
    for (size_t i = 0; i < w.block_from.size(); ++i) {
      const int64_t from = w.block_from[i] - s.start_sample;
      const bool last = i + 1 == w.block_from.size();
      fill_stretch(x, missing, w, from, w.block_len[i], last ? z : from + w.block_len[i], fs);
    }
  }
}

// The samples of the series the fill treats as missing (x as recorded): those at the level of a
// mended clipping of `faults`, and those of its mended gaps (lost or held: interpolated first, so
// that the hum and drift checks see no hole, then filled from the excited lines as the clipped
// ones are); empty when there are none.
std::vector<bool> missing_samples(const double* x, const TimeSeries& s,
                                  const std::vector<const DataFault*>& faults) {
  const int64_t N = s.n_samples;
  std::vector<bool> missing;
  for (const DataFault* f : faults) {
    if (!f->mended) continue;
    if (f->kind == DataFaultKind::kClipping) {
      missing.resize(size_t(N), false);
      for (int64_t n = 0; n < N; ++n)
        if (x[n] == f->level) missing[size_t(n)] = true;
    } else if (f->kind == DataFaultKind::kLost || f->kind == DataFaultKind::kHeld) {
      missing.resize(size_t(N), false);
      for (const auto& [a, b] : f->spans)
        for (int64_t n = std::max(a, s.start_sample); n <= std::min(b, s.start_sample + N - 1); ++n)
          missing[size_t(n - s.start_sample)] = true;
    }
  }
  return missing;
}

// The mending of one channel in the documented order: gaps, hum, drift, clipping (given the
// schedule's windows), clock, spans without response.
void mend_channel(double* x, const TimeSeries& s, const std::vector<const DataFault*>& faults,
                  const std::vector<Window>* windows) {
  const int64_t N = s.n_samples;
  const double fs = s.sample_rate_hz;
  // The clipped samples, told by their value before anything else changes it, and the gaps.
  const std::vector<bool> missing = windows ? missing_samples(x, s, faults) : std::vector<bool>{};
  for (const DataFault* f : faults) {
    if (!f->mended || (f->kind != DataFaultKind::kLost && f->kind != DataFaultKind::kHeld))
      continue;
    for (const auto& [a, b] : f->spans) interpolate(x, N, a - s.start_sample, b - s.start_sample);
  }
  for (const DataFault* f : faults) {
    if (!f->mended || f->kind != DataFaultKind::kHum) continue;
    const double om = 2 * kPi * f->frequency_hz / fs, ph = f->phase_deg * kPi / 180;
    for (int64_t n = 0; n < N; ++n)
      x[n] -= f->size * std::cos(om * double(s.start_sample + n) + ph);
  }
  for (const DataFault* f : faults) {
    if (!f->mended || f->kind != DataFaultKind::kDrift) continue;
    const double tm = 0.5 * (f->from_s + f->to_s);
    for (int64_t n = 0; n < N; ++n) x[n] -= f->size * (double(s.start_sample + n) / fs - tm);
  }
  if (!missing.empty()) fill_missing(x, s, *windows, missing);
  for (const DataFault* f : faults) {
    if (!f->mended || f->kind != DataFaultKind::kClock) continue;
    // Sample n on the excitation's clock is the channel's sample n / (1 - eps).
    std::vector<double> y(x, x + N);
    for (int64_t n = 0; n < N; ++n) {
      const double at = double(s.start_sample + n) / (1.0 - f->size) - double(s.start_sample);
      if (at <= 0) {
        x[n] = y[0];
      } else if (at >= double(N - 1)) {
        x[n] = y[size_t(N - 1)];
      } else {
        const auto i = int64_t(at);
        const double a = at - double(i);
        x[n] = (1 - a) * y[size_t(i)] + a * y[size_t(i + 1)];
      }
    }
  }
  // Spans without response last: NaN, which the analyser refuses in any window.
  for (const DataFault* f : faults) {
    if (!f->mended || f->kind != DataFaultKind::kNoResponse) continue;
    for (const auto& [a, b] : f->spans)
      for (int64_t n = std::max(a, s.start_sample); n <= std::min(b, s.start_sample + N - 1); ++n)
        x[n - s.start_sample] = std::numeric_limits<double>::quiet_NaN();
  }
}

}  // namespace fralab::dq
