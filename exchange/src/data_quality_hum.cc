// The spectral check: mains hum and its harmonics off the excitation's grid
// (data_quality_checks.h).
#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "data_quality_checks.h"
#include "fralab/core/numerics.h"

namespace fralab::dq {

// |sum_n w_n x_n e^{-j 2 pi f t_n}| with a Hann window w over the series, and that sum.
namespace {

Complex hann_dft(const double* x, int64_t N, double mean, double f, double fs, int64_t start) {
  Complex acc = 0;
  const Complex step = std::polar(1.0, -2 * kPi * f / fs);
  Complex rot = std::polar(1.0, -2 * kPi * f * double(start) / fs);
  for (int64_t n = 0; n < N; ++n) {
    const double w = 0.5 - 0.5 * std::cos(2 * kPi * double(n) / double(N));
    acc += w * (x[n] - mean) * rot;
    rot *= step;
    if ((n & 1023) == 1023) rot /= std::abs(rot);
  }
  return acc;
}

}  // namespace

// Over the channel's first n_live samples (all by default: a channel that died keeps its hum only
// while it lives).
void check_hum(const std::string& ch, const double* x, const TimeSeries& s,
               const std::vector<Window>& windows, const DataQualityOptions& o,
               std::vector<DataFault>* out, int64_t n_live) {
  const int64_t N = smooth_size(n_live < 0 ? s.n_samples : std::min(n_live, s.n_samples));
  const double fs = s.sample_rate_hz;
  if (N < 1024) return;
  double mean = 0, range_lo = INFINITY, range_hi = -INFINITY;
  for (int64_t n = 0; n < N; ++n) {
    mean += x[n] / double(N);
    range_lo = std::min(range_lo, x[n]), range_hi = std::max(range_hi, x[n]);
  }
  if (!std::isfinite(mean)) return;
  const double range = range_hi - range_lo;
  std::vector<double> buf(static_cast<size_t>(N));
  for (int64_t n = 0; n < N; ++n)
    buf[size_t(n)] = (x[n] - mean) * (0.5 - 0.5 * std::cos(2 * kPi * double(n) / double(N)));
  std::vector<Complex> X(size_t(N / 2 + 1));
  fftw_plan plan = fftw_plan_dft_r2c_1d(int(N), buf.data(),
                                        reinterpret_cast<fftw_complex*>(X.data()), FFTW_ESTIMATE);
  fftw_execute(plan);
  fftw_destroy_plan(plan);
  const double df = fs / double(N);
  // Bins within 3 of an excited frequency are the excitation's (a sine step's harmonics last
  // only its step: the steadiness test below tells them from hum).
  std::vector<bool> excluded(X.size(), false);
  auto exclude = [&](double f) {
    const auto c = int64_t(std::llround(f / df));
    for (int64_t k = c - 3; k <= c + 3; ++k)
      if (k >= 0 && k < int64_t(X.size())) excluded[size_t(k)] = true;
  };
  for (const Window& w : windows)
    for (double f : w.freqs_hz) exclude(f);
  exclude(0);
  std::set<int64_t> found;
  for (double mains : {50.0, 60.0}) {
    for (int m = 1; m <= o.max_harmonic; ++m) {
      const double fc = m * mains;
      if (fc + 2.5 >= fs / 2) break;
      const auto a = int64_t(std::ceil((fc - o.mains_search_hz) / df)),
                 b = int64_t(std::floor((fc + o.mains_search_hz) / df));
      int64_t peak = -1;
      for (int64_t k = a; k <= b; ++k)
        if (!excluded[size_t(k)] &&
            (peak < 0 || std::norm(X[size_t(k)]) > std::norm(X[size_t(peak)])))
          peak = k;
      if (peak < 0 || found.count(peak)) continue;
      std::vector<double> floor_bins;
      const auto fa = int64_t(std::ceil((fc - 2.0) / df)),
                 fb = int64_t(std::floor((fc + 2.0) / df));
      for (int64_t k = fa; k <= fb; ++k)
        if (!excluded[size_t(k)] && std::abs(k - peak) > 4)
          floor_bins.push_back(std::norm(X[size_t(k)]));
      if (floor_bins.size() < 20) continue;
      const double noise = median(floor_bins) / std::log(2.0);
      if (!(std::norm(X[size_t(peak)]) > o.hum_ratio * noise)) continue;
      // A periodic excitation's distortion sits on its period's grid, on every line alike: the
      // line must also stand above the multisine grid's non-excited lines around it.
      bool above_grid = true;
      for (const Window& w : windows) {
        if (!w.multisine) continue;
        const double g = fs / w.period;
        std::vector<double> grid;
        for (auto j = int64_t(std::ceil((fc - 2.0) / g)); double(j) * g <= fc + 2.0; ++j) {
          const auto k = int64_t(std::llround(double(j) * g / df));
          if (std::abs(k - peak) > 4 && k >= 0 && k < int64_t(X.size()) && !excluded[size_t(k)])
            grid.push_back(std::norm(X[size_t(k)]));
        }
        if (grid.size() >= 5 &&
            !(std::norm(X[size_t(peak)]) > o.hum_ratio * median(grid) / std::log(2.0)))
          above_grid = false;
      }
      if (!above_grid) continue;
      found.insert(peak);
      // The line's frequency: where the Hann-weighted amplitude peaks, within a bin either side.
      const double f = detail::brent_minimum(
          [&](double ff) { return -std::abs(hann_dft(x, N, mean, ff, fs, s.start_sample)); },
          (double(peak) - 1) * df, (double(peak) + 1) * df, 24, 40);
      const Complex c = hann_dft(x, N, mean, f, fs, s.start_sample) * (4.0 / double(N));
      // Rounding's own lines in a noise-free channel are no hum.
      if (!(std::abs(c) > 1e-9 * std::max(range, std::abs(mean)))) continue;
      // Mains hum lasts: it must hold in every quarter of the run (a sine step's harmonic, or a
      // transient, holds in one).
      bool steady = true;
      for (int part = 0; part < 4 && steady; ++part) {
        const int64_t a = part * N / 4, len = (part + 1) * N / 4 - a;
        double m = 0;
        for (int64_t n = a; n < a + len; ++n) m += x[n] / double(len);
        const double amp =
            std::abs(hann_dft(x + a, len, m, f, fs, s.start_sample + a)) * 4.0 / double(len);
        steady = amp >= 0.5 * std::abs(c);
      }
      if (!steady) continue;
      DataFault h;
      h.channel = ch;
      h.kind = DataFaultKind::kHum;
      h.frequency_hz = f;
      h.size = std::abs(c);
      h.phase_deg = std::arg(c) * 180 / kPi;
      h.from_s = double(s.start_sample) / fs;
      h.to_s = double(s.start_sample + N) / fs;
      h.mended = true;
      h.text = "a line at " + fmt(f) + " Hz on " + ch + ", amplitude " + fmt(h.size) + " (" +
               fmt(10 * std::log10(std::norm(X[size_t(peak)]) / noise)) +
               " dB above the noise there), off every excited line: mains hum";
      h.action = n_live < 0
                     ? "subtracted (its frequency, amplitude and phase fitted over the run)"
                     : "subtracted (its frequency, amplitude and phase fitted while it lived)";
      out->push_back(std::move(h));
    }
  }
}

}  // namespace fralab::dq
