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

// The channel's Hann-windowed spectrum over its first N samples and the search for mains lines
// in it: bins within 3 of an excited frequency (or of 0 Hz) are the excitation's (a sine step's
// harmonics last only its step: the steadiness test tells them from hum).
class HumScan {
 public:
  HumScan(const double* x, int64_t N, const TimeSeries& s, const std::vector<Window>& windows)
      : x_(x), N_(N), start_(s.start_sample), fs_(s.sample_rate_hz), windows_(windows) {
    for (int64_t n = 0; n < N; ++n) {
      mean_ += x[n] / double(N);
      lo_ = std::min(lo_, x[n]), hi_ = std::max(hi_, x[n]);
    }
    if (!std::isfinite(mean_)) return;
    std::vector<double> buf(static_cast<size_t>(N));
    for (int64_t n = 0; n < N; ++n)
      buf[size_t(n)] = (x[n] - mean_) * (0.5 - 0.5 * std::cos(2 * kPi * double(n) / double(N)));
    X_.resize(size_t(N / 2 + 1));
    fftw_plan plan = fftw_plan_dft_r2c_1d(
        int(N), buf.data(), reinterpret_cast<fftw_complex*>(X_.data()), FFTW_ESTIMATE);
    fftw_execute(plan);
    fftw_destroy_plan(plan);
    df_ = fs_ / double(N);
    excluded_.assign(X_.size(), false);
    for (const Window& w : windows)
      for (double f : w.freqs_hz) exclude(f);
    exclude(0);
  }
  bool finite() const { return std::isfinite(mean_); }
  double df() const { return df_; }
  double power(int64_t k) const { return std::norm(X_[size_t(k)]); }

  /// The strongest bin not the excitation's within search_hz of fc; -1 for none.
  int64_t peak_near(double fc, double search_hz) const {
    const auto a = int64_t(std::ceil((fc - search_hz) / df_)),
               b = int64_t(std::floor((fc + search_hz) / df_));
    int64_t peak = -1;
    for (int64_t k = a; k <= b; ++k)
      if (!excluded_[size_t(k)] && (peak < 0 || power(k) > power(peak))) peak = k;
    return peak;
  }

  /// The noise power at fc: the median of the free bins within 2 Hz, more than 4 from the peak,
  /// over ln 2 (an exponential's mean from its median); NaN for fewer than 20 such bins.
  double noise_at(double fc, int64_t peak) const {
    std::vector<double> floor_bins;
    const auto fa = int64_t(std::ceil((fc - 2.0) / df_)),
               fb = int64_t(std::floor((fc + 2.0) / df_));
    for (int64_t k = fa; k <= fb; ++k)
      if (!excluded_[size_t(k)] && std::abs(k - peak) > 4) floor_bins.push_back(power(k));
    if (floor_bins.size() < 20) return NAN;
    return median(floor_bins) / std::log(2.0);
  }

  /// A periodic excitation's distortion sits on its period's grid, on every line alike: the
  /// peak must also stand `ratio` above each multisine grid's non-excited lines within 2 Hz.
  bool above_grid(double fc, int64_t peak, double ratio) const {
    for (const Window& w : windows_) {
      if (!w.multisine) continue;
      const double g = fs_ / w.period;
      std::vector<double> grid;
      for (auto j = int64_t(std::ceil((fc - 2.0) / g)); double(j) * g <= fc + 2.0; ++j) {
        const auto k = int64_t(std::llround(double(j) * g / df_));
        if (std::abs(k - peak) > 4 && k >= 0 && k < int64_t(X_.size()) && !excluded_[size_t(k)])
          grid.push_back(power(k));
      }
      if (grid.size() >= 5 && !(power(peak) > ratio * median(grid) / std::log(2.0))) return false;
    }
    return true;
  }

  /// The line's frequency: where the Hann-weighted amplitude peaks, within a bin either side.
  double line_frequency(int64_t peak) const {
    return detail::brent_minimum(
        [&](double ff) { return -std::abs(hann_dft(x_, N_, mean_, ff, fs_, start_)); },
        (double(peak) - 1) * df_, (double(peak) + 1) * df_, 24, 40);
  }
  /// The line's complex amplitude at f over the N samples.
  Complex amplitude(double f) const {
    return hann_dft(x_, N_, mean_, f, fs_, start_) * (4.0 / double(N_));
  }
  /// Rounding's own lines in a noise-free channel are no hum.
  bool above_rounding(Complex c) const {
    return std::abs(c) > 1e-9 * std::max(hi_ - lo_, std::abs(mean_));
  }
  /// Mains hum lasts: the line at f must hold half its amplitude |c| in every quarter of the run
  /// (a sine step's harmonic, or a transient, holds in one).
  bool steady(double f, Complex c) const {
    for (int part = 0; part < 4; ++part) {
      const int64_t a = part * N_ / 4, len = (part + 1) * N_ / 4 - a;
      double m = 0;
      for (int64_t n = a; n < a + len; ++n) m += x_[n] / double(len);
      const double amp = std::abs(hann_dft(x_ + a, len, m, f, fs_, start_ + a)) * 4.0 / double(len);
      if (!(amp >= 0.5 * std::abs(c))) return false;
    }
    return true;
  }

 private:
  void exclude(double f) {
    const auto c = int64_t(std::llround(f / df_));
    for (int64_t k = c - 3; k <= c + 3; ++k)
      if (k >= 0 && k < int64_t(X_.size())) excluded_[size_t(k)] = true;
  }

  const double* x_;
  int64_t N_, start_;
  double fs_, mean_ = 0, lo_ = INFINITY, hi_ = -INFINITY, df_ = 0;
  const std::vector<Window>& windows_;
  std::vector<Complex> X_;
  std::vector<bool> excluded_;
};

}  // namespace

// Over the channel's first n_live samples (all by default: a channel that died keeps its hum only
// while it lives).
void check_hum(const std::string& ch, const double* x, const TimeSeries& s,
               const std::vector<Window>& windows, const DataQualityOptions& o,
               std::vector<DataFault>* out, int64_t n_live) {
  const int64_t N = smooth_size(n_live < 0 ? s.n_samples : std::min(n_live, s.n_samples));
  const double fs = s.sample_rate_hz;
  if (N < 1024) return;
  const HumScan scan(x, N, s, windows);
  if (!scan.finite()) return;
  std::set<int64_t> found;
  for (double mains : {50.0, 60.0}) {
    for (int m = 1; m <= o.max_harmonic; ++m) {
      const double fc = m * mains;
      if (fc + 2.5 >= fs / 2) break;
      const int64_t peak = scan.peak_near(fc, o.mains_search_hz);
      if (peak < 0 || found.count(peak)) continue;
      const double noise = scan.noise_at(fc, peak);
      if (std::isnan(noise) || !(scan.power(peak) > o.hum_ratio * noise)) continue;
      if (!scan.above_grid(fc, peak, o.hum_ratio)) continue;
      found.insert(peak);
      const double f = scan.line_frequency(peak);
      const Complex c = scan.amplitude(f);
      if (!scan.above_rounding(c) || !scan.steady(f, c)) continue;
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
               fmt(10 * std::log10(scan.power(peak) / noise)) +
               " dB above the noise there), off every excited line: mains hum";
      h.action = n_live < 0
                     ? "subtracted (its frequency, amplitude and phase fitted over the run)"
                     : "subtracted (its frequency, amplitude and phase fitted while it lived)";
      out->push_back(std::move(h));
    }
  }
}

}  // namespace fralab::dq
