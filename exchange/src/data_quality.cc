#include "fralab/exchange/data_quality.h"

#include <fftw3.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <map>
#include <numbers>
#include <set>

#include "fralab/analyze/period_fft.h"
#include "fralab/core/numerics.h"
#include "fralab/core/text.h"

namespace fralab {
namespace {

using Complex = std::complex<double>;
constexpr double kPi = std::numbers::pi;

constexpr std::pair<DataFaultKind, const char*> kKindWords[] = {
    {DataFaultKind::kLost, "lost_samples"},     {DataFaultKind::kHeld, "held_samples"},
    {DataFaultKind::kClipping, "clipping"},     {DataFaultKind::kHum, "hum"},
    {DataFaultKind::kDrift, "drift"},           {DataFaultKind::kClock, "clock"},
    {DataFaultKind::kNoResponse, "no_response"}};

bool checked_channel(const std::string& c) {
  return !c.starts_with("u_") && !c.starts_with("ref_") && c != "underrun";
}

std::string fmt(double v) { return significant(v, 4); }

// The largest n <= N whose prime factors are 2, 3, 5 and 7 (FFTW's fast sizes).
int64_t smooth_size(int64_t N) {
  for (int64_t n = N; n > 1; --n) {
    int64_t m = n;
    for (int p : {2, 3, 5, 7})
      while (m % p == 0) m /= p;
    if (m == 1) return n;
  }
  return N;
}

// One integration window of the schedule, cut into blocks: a multisine's periods, or a sine's
// blocks of whole cycles.
struct Window {
  int64_t from = 0, to = 0;  // first sample, one past the last (absolute)
  std::vector<int64_t> block_from, block_len;
  std::vector<double> freqs_hz;  // the excited frequencies
  bool multisine = false;
  int period = 0;
  std::vector<int> lines;  // multisine: excited bins of a period
  std::string signature;   // the excitation (inputs and amplitudes, lines): equal, equal response
  /// Multisine: the first sample of the settle's last period, just before `from` (the same
  /// excitation, its transient the least), or -1 when the series does not hold it.
  int64_t reference_from = -1;
};

std::vector<Window> windows_of(const Schedule& sch, const TimeSeries& s) {
  std::vector<Window> out;
  const double fs = s.sample_rate_hz;
  const int64_t end = s.start_sample + s.n_samples;
  const StatusEvent* settle = nullptr;
  for (const StatusEvent& e : sch.events) {
    if (e.state == RunState::kSettle) settle = &e;
    if (e.state != RunState::kIntegrate || e.n_samples <= 0) continue;
    if (e.sample < s.start_sample || e.sample + e.n_samples > end) continue;
    Window w;
    w.from = e.sample;
    w.to = e.sample + e.n_samples;
    w.signature = std::to_string(int(e.excitation)) + ":";
    for (size_t i = 0; i < e.inputs.size() && i < e.amplitudes.size(); ++i)
      w.signature += e.inputs[i] + "=" + significant(e.amplitudes[i], 6) + ",";
    if (e.excitation == Excitation::kMultisine) {
      const int P = e.period_samples;
      if (P < 8 || e.n_samples / P < 2) continue;
      w.multisine = true;
      w.period = P;
      std::set<int> lines(e.lines.begin(), e.lines.end());
      for (int k : lines)
        if (k >= 1 && k < P / 2) w.lines.push_back(k);
      for (int k : w.lines) w.freqs_hz.push_back(k * fs / P);
      w.signature += "P" + std::to_string(P);
      for (int k : w.lines) w.signature += "," + std::to_string(k);
      for (int64_t b = 0; b + P <= e.n_samples; b += P) {
        w.block_from.push_back(e.sample + b);
        w.block_len.push_back(P);
      }
      if (settle && settle->step == e.step && settle->sample <= e.sample - P &&
          settle->sample + settle->n_samples == e.sample && e.sample - P >= s.start_sample)
        w.reference_from = e.sample - P;
    } else if (e.excitation == Excitation::kStepped && e.frequency_hz > 0 && e.n_cycles >= 2) {
      const int K = std::min(8, e.n_cycles), c = e.n_cycles / K;
      const double per_cycle = fs / e.frequency_hz;
      for (int b = 0; b < K; ++b) {
        const auto a = int64_t(std::llround(b * c * per_cycle)),
                   z = int64_t(std::llround((b + 1) * c * per_cycle));
        if (z > e.n_samples) break;
        w.block_from.push_back(e.sample + a);
        w.block_len.push_back(z - a);
      }
      w.freqs_hz = {e.frequency_hz};
      w.signature += "f" + significant(e.frequency_hz, 9);
    } else {
      continue;
    }
    if (w.block_from.size() >= 2) out.push_back(std::move(w));
  }
  return out;
}

// Per block of a window: the channel's complex amplitude at each excited frequency (phase on the
// sample clock), its power there (the sum of |y|^2 over the excited frequencies), its mean, and
// the mean power on a period's non-excited bins in the excited band (multisine; NaN otherwise).
// A block holding a NaN sample has no values (empty, power 0).
struct BlockValues {
  std::vector<std::vector<Complex>> y;        // [block][frequency]
  std::vector<double> power, mean, t, noise;  // per block
};

BlockValues block_values(const Window& w, const double* x, int64_t start, double fs) {
  BlockValues v;
  const size_t B = w.block_from.size();
  v.y.resize(B);
  v.power.assign(B, 0.0);
  v.mean.assign(B, 0.0);
  v.t.assign(B, 0.0);
  v.noise.assign(B, std::nan(""));
  std::unique_ptr<PeriodFft> fft;
  if (w.multisine) fft = std::make_unique<PeriodFft>(w.period);
  std::vector<bool> excited;
  if (w.multisine) {
    excited.assign(size_t(w.period / 2 + 1), false);
    for (int k : w.lines) excited[size_t(k)] = true;
  }
  for (size_t b = 0; b < B; ++b) {
    const double* xb = x + (w.block_from[b] - start);
    const int64_t L = w.block_len[b];
    double m = 0;
    for (int64_t n = 0; n < L; ++n) m += xb[n];
    m /= double(L);
    v.mean[b] = m;
    v.t[b] = (double(w.block_from[b]) + 0.5 * double(L)) / fs;
    if (!std::isfinite(m)) continue;
    if (w.multisine) {
      const auto& X = (*fft)(xb);
      // X(k) is the phasor on the period's own start; a whole number of periods from the run's
      // sample 0 is the same phase on every line only when the period divides the start: rotate
      // to the sample clock.
      for (size_t j = 0; j < w.lines.size(); ++j) {
        const int k = w.lines[j];
        const double ph = -2 * kPi * double(k) * double(w.block_from[b] % w.period) / w.period;
        v.y[b].push_back(X[size_t(k)] * std::polar(2.0 / w.period, ph));
      }
      double pn = 0;
      int nn = 0;
      for (int k = w.lines.front(); k <= w.lines.back(); ++k) {
        if (excited[size_t(k)]) continue;
        pn += std::norm(X[size_t(k)] * (2.0 / w.period));
        ++nn;
      }
      if (nn > 0) v.noise[b] = pn / nn;
    } else {
      // Least squares of a cos + b sin + c at the step's frequency (whole cycles: the DFT).
      const double om = 2 * kPi * w.freqs_hz[0] / fs;
      Complex acc = 0;
      for (int64_t n = 0; n < L; ++n)
        acc += (xb[n] - m) * std::polar(1.0, -om * double(w.block_from[b] + n));
      v.y[b].push_back(acc * (2.0 / double(L)));
    }
    for (const Complex& y : v.y[b]) v.power[b] += std::norm(y);
  }
  return v;
}

// Within-window regression of per-block values z_b on the blocks' times over every window:
// slope = sum_w W_w sum_b (t - tbar_w)(z - zbar_w) / sum_w W_w sum_b (t - tbar_w)^2, its sigma
// from the weights' information scaled by the residuals' reduced chi-square when above 1.
struct Slope {
  double value = 0, sigma = 0;
  int blocks = 0;
};
struct SlopeAccumulator {
  std::vector<std::vector<double>> t, z;
  std::vector<double> weight;
  void add(std::vector<double> tb, std::vector<double> zb, double W) {
    if (tb.size() < 2 || !(W > 0)) return;
    t.push_back(std::move(tb));
    z.push_back(std::move(zb));
    weight.push_back(W);
  }
  // `empirical`: sigma from the residual scatter alone (weights relative only).
  Slope solve(bool empirical) const {
    Slope s;
    double sxy = 0, sxx = 0;
    std::vector<double> tbar(t.size()), zbar(t.size());
    int n = 0;
    for (size_t w = 0; w < t.size(); ++w) {
      for (size_t b = 0; b < t[w].size(); ++b) {
        tbar[w] += t[w][b] / double(t[w].size());
        zbar[w] += z[w][b] / double(t[w].size());
      }
      for (size_t b = 0; b < t[w].size(); ++b) {
        sxy += weight[w] * (t[w][b] - tbar[w]) * (z[w][b] - zbar[w]);
        sxx += weight[w] * (t[w][b] - tbar[w]) * (t[w][b] - tbar[w]);
        ++n;
      }
    }
    // The residuals' scale needs degrees of freedom; the weights alone need none (one window of
    // two periods: a single-input multisine).
    const int dof = n - int(t.size()) - 1;
    if (!(sxx > 0) || dof < (empirical ? 4 : 0)) return s;
    s.value = sxy / sxx;
    double chi2 = 0;
    for (size_t w = 0; w < t.size(); ++w)
      for (size_t b = 0; b < t[w].size(); ++b) {
        const double r = z[w][b] - zbar[w] - s.value * (t[w][b] - tbar[w]);
        chi2 += weight[w] * r * r;
      }
    const double red = dof > 0 ? chi2 / dof : 1.0;
    s.sigma = std::sqrt((empirical ? red : std::max(1.0, red)) / sxx);
    s.blocks = n;
    return s;
  }
};

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// ---- sample-level checks -------------------------------------------------------------------

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

// ---- spectral checks -------------------------------------------------------------------------

// |sum_n w_n x_n e^{-j 2 pi f t_n}| with a Hann window w over the series, and that sum.
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

// Over the channel's first n_live samples (all by default: a channel that died keeps its hum only
// while it lives).
void check_hum(const std::string& ch, const double* x, const TimeSeries& s,
               const std::vector<Window>& windows, const DataQualityOptions& o,
               std::vector<DataFault>* out, int64_t n_live = -1) {
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

// `values`: block_values of each of `windows` on x.
constexpr int kMinSineBlocks = 4;

void check_drift_and_clock(const std::string& ch, const double* x, const TimeSeries& s,
                           const std::vector<Window>& windows,
                           const std::vector<BlockValues>& values, const DataQualityOptions& o,
                           std::vector<DataFault>* out, std::vector<ClockEstimate>* clocks) {
  SlopeAccumulator drift;
  double t0 = INFINITY, t1 = -INFINITY;
  // Drift: the means of each eighth of a multisine's period (a sine's blocks), compared across
  // the periods of one window: each eighth's own level is its group's offset, a drift the slope
  // they share (eighths give the residuals enough degrees of freedom in a window of few periods).
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
      if (tb.size() >= 2) t0 = std::min(t0, tb.front()), t1 = std::max(t1, tb.back());
      drift.add(tb, zb, 1.0);
    }
  }
  // Clock: each block's delay against its window's mean, in two passes (the second on the
  // first's residual, so that lines the first pass would wrap are used in the second).
  auto clock_pass = [&](double eps0, double fmax, double fmin) {
    SlopeAccumulator acc;
    for (size_t i = 0; i < windows.size(); ++i) {
      const Window& w = windows[i];
      const BlockValues& v = values[i];
      // Blocks with the window's response: a clock moves phases, not power, so where a
      // multisine's lines stand far above the noise (the strongest block's power over 100 times
      // what its non-excited lines give them), a block with less than half that power (the
      // channel dead or stuck for part of the window) has no phase to follow. A channel near
      // its noise keeps every block: choosing its strongest would choose noise that agrees.
      const std::vector<double>& power = v.power;
      const size_t strongest = size_t(std::max_element(power.begin(), power.end()) - power.begin());
      const bool visible =
          w.multisine && !v.y[strongest].empty() &&
          power[strongest] > 100 * double(v.y[strongest].size()) * v.noise[strongest];
      std::vector<size_t> ok;
      for (size_t b = 0; b < v.y.size(); ++b)
        if (!v.y[b].empty() && (!visible || power[b] >= 0.5 * power[strongest])) ok.push_back(b);
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
  };
  double fmax_all = 0;
  for (const Window& w : windows)
    for (double f : w.freqs_hz) fmax_all = std::max(fmax_all, f);
  // The lines of the band's top 1.3 decades: a clock walks a line's phase in proportion to its
  // frequency, while a slow mode's leftover transient in a window's first period moves the low
  // lines' phases most (over the lab's machine runs, a 2 s mode's made a clean channel's pooled
  // estimate 7.6 sigma; without the lines below a twentieth of the top, at most 4.8 sigma).
  const double fmin = fmax_all / 20;
  Slope c1 = clock_pass(0.0, fmax_all / 4, fmin);
  if (c1.blocks == 0) c1 = clock_pass(0.0, fmax_all, fmin);
  Slope c = c1;
  if (c1.blocks > 0) {
    Slope c2 = clock_pass(c1.value, fmax_all, fmin);
    if (c2.blocks > 0) c = Slope{c1.value + c2.value, c2.sigma, c2.blocks};
  }
  // A fault sized by a slope over [t0, t1], mended.
  auto sloped = [&](DataFaultKind kind, const Slope& sl) {
    DataFault f;
    f.channel = ch;
    f.kind = kind;
    f.size = sl.value;
    f.sigma = sl.sigma;
    f.from_s = t0;
    f.to_s = t1;
    f.mended = true;
    return f;
  };
  const Slope d = drift.solve(true);
  if (d.blocks > 0 && std::abs(d.value) > o.drift_sigmas * d.sigma) {
    DataFault f = sloped(DataFaultKind::kDrift, d);
    f.text = ch + " drifts by " + fmt(d.value) + " units per second (+-" + fmt(d.sigma) +
             ") within the excitation's periods: " + fmt(d.value * (t1 - t0)) + " over the run";
    f.action = "the straight line removed before the Fourier filter";
    out->push_back(std::move(f));
  }
  // This run's estimate, pooled (weights 1 / sigma^2) with the campaign's other runs' of the same
  // channel that agree with it within 4 sigma of their difference (all of them where this run
  // has none: a sine of two-cycle steps).
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
  if (std::abs(pooled.value) > o.clock_sigmas * pooled.sigma &&
      std::abs(pooled.value) > o.min_clock) {
    if (!std::isfinite(t0)) {  // no window of its own: the run's span
      t0 = double(s.start_sample) / s.sample_rate_hz;
      t1 = double(s.start_sample + s.n_samples) / s.sample_rate_hz;
    }
    DataFault f = sloped(DataFaultKind::kClock, pooled);
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
}

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

void check_silent_eighths(const std::string& ch, const double* x, const TimeSeries& s,
                          const std::vector<Window>& windows, std::vector<DataFault>* out) {
  struct Eighth {
    int64_t from, to, period_from, period_to;  // samples (absolute)
    bool shown;   // another period's same eighth stands above the noise (kLiveRatio)
    bool silent;  // shown, and this one at the noise
    double live;  // the largest ratio of the same eighth over the window's periods
  };
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
                  const std::vector<Window>* windows = nullptr) {
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

}  // namespace

const char* to_string(DataFaultKind k) { return enum_word(kKindWords, k); }

std::map<std::string, ClockEstimate> pool_clocks(const std::vector<ClockEstimate>& all) {
  std::map<std::string, std::pair<double, double>> sums;  // channel -> (sum w, sum w eps)
  std::map<std::string, ClockEstimate> out;
  for (const ClockEstimate& e : all) {
    if (!(e.sigma > 0)) continue;
    auto& [w, wx] = sums[e.channel];
    w += 1 / (e.sigma * e.sigma);
    wx += e.eps / (e.sigma * e.sigma);
    if (!out.count(e.channel)) out[e.channel] = e;  // its time and run: the first's
  }
  for (auto& [ch, e] : out) {
    e.eps = sums[ch].second / sums[ch].first;
    e.sigma = 1 / std::sqrt(sums[ch].first);
  }
  return out;
}

void DataQualityOptions::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0) || !std::isfinite(v))
      throw InputError(std::string("data quality: ") + name + " must be a positive number");
  };
  positive(max_gap_s, "max_gap_s");
  positive(mains_search_hz, "mains_search_hz");
  positive(hum_ratio, "hum_ratio");
  positive(drift_sigmas, "drift_sigmas");
  positive(clock_sigmas, "clock_sigmas");
  positive(min_clock, "min_clock");
  if (max_harmonic < 1 || max_harmonic > 20)
    throw InputError("data quality: max_harmonic must be in 1..20");
}

bool DataQuality::changes_curves() const {
  return any_mended() || std::any_of(faults.begin(), faults.end(), [](const DataFault& f) {
           return f.kind == DataFaultKind::kClipping;
         });
}

bool DataQuality::any_mended() const {
  return std::any_of(faults.begin(), faults.end(), [](const DataFault& f) { return f.mended; });
}

DataQuality check_data_quality(const TimeSeries& s, const Schedule& schedule,
                               const DataQualityOptions& o) {
  o.validate();
  DataQuality q;
  const std::vector<Window> windows = windows_of(schedule, s);
  TimeSeries work = s;
  for (size_t c = 0; c < s.channels.size(); ++c) {
    const std::string& ch = s.channels[c];
    if (!checked_channel(ch)) continue;
    q.checked.push_back(ch);
    const double* raw = s.samples.data() + c * size_t(s.n_samples);
    double* x = work.samples.data() + c * size_t(s.n_samples);
    std::vector<DataFault> found;
    check_lost(ch, raw, s, o, &found);
    // Repeats and flat tops are faults only where noise makes them improbable.
    if (!o.noise_free && noisy(raw, s.n_samples)) {
      const auto [hi, lo] = check_clipping(ch, raw, s, &found);
      check_held(ch, raw, s, hi, lo, o, &found);
    }
    // The spectral checks see the gaps mended (a NaN would spoil every period it falls in).
    std::vector<const DataFault*> so_far;
    for (const DataFault& f : found) so_far.push_back(&f);
    mend_channel(x, s, so_far);
    const size_t before_hum = found.size();
    check_hum(ch, x, s, windows, o, &found);
    std::vector<const DataFault*> hums;
    for (size_t i = before_hum; i < found.size(); ++i) hums.push_back(&found[i]);
    mend_channel(x, s, hums);
    // The periods compared with clipping and gaps filled: a clipped peak moves a period's mean
    // and phase, a gap's straight line its higher lines.
    std::vector<const DataFault*> holes;
    for (const DataFault& f : found) holes.push_back(&f);
    if (const std::vector<bool> c = missing_samples(raw, s, holes); !c.empty())
      fill_missing(x, s, windows, c);
    // Each window's blocks, transformed once for the tests that compare periods.
    std::vector<BlockValues> values;
    for (const Window& w : windows)
      values.push_back(block_values(w, x, s.start_sample, s.sample_rate_hz));
    // The spans without response first: the periods they set aside enter neither the drift nor
    // the clock (a dead stretch's phases are noise).
    std::vector<DataFault> silent;
    check_no_response(ch, s, windows, values, &silent);
    check_silent_eighths(ch, x, s, windows, &silent);
    leave_out_spans(windows, silent, values);
    // A channel silent from some time on may have carried a hum only while it lived: looked for
    // again over the stretch before its first silent span.
    if (hums.empty() && !silent.empty()) {
      int64_t live = s.n_samples;
      for (const DataFault& f : silent)
        for (const auto& span : f.spans) live = std::min(live, span.first - s.start_sample);
      std::vector<DataFault> late;
      if (live > 0) check_hum(ch, x, s, windows, o, &late, live);
      std::vector<const DataFault*> late_hums;
      for (const DataFault& f : late) late_hums.push_back(&f);
      mend_channel(x, s, late_hums);
      found.insert(found.begin() + long(before_hum), std::make_move_iterator(late.begin()),
                   std::make_move_iterator(late.end()));
    }
    check_drift_and_clock(ch, x, s, windows, values, o, &found, &q.clocks);
    for (DataFault& f : silent) found.push_back(std::move(f));
    for (DataFault& f : found) q.faults.push_back(std::move(f));
  }
  return q;
}

TimeSeries mend_series(const TimeSeries& s, const DataQuality& q, const Schedule& schedule) {
  const std::vector<Window> windows = windows_of(schedule, s);
  TimeSeries out = s;
  for (size_t c = 0; c < s.channels.size(); ++c) {
    std::vector<const DataFault*> mine;
    for (const DataFault& f : q.faults)
      if (f.channel == s.channels[c] && f.mended) mine.push_back(&f);
    if (!mine.empty())
      mend_channel(out.samples.data() + c * size_t(s.n_samples), s, mine, &windows);
  }
  return out;
}

void widen_for_mending(std::vector<Frd>& curves, const DataQuality& q) {
  for (Frd& c : curves) {
    const auto [e1, e2] = split_pair(c.pair);
    for (const DataFault& f : q.faults) {
      if (f.channel != e1 && f.channel != e2) continue;
      for (FrdPoint& p : c.points) {
        if (!p.valid || !(p.sigma > 0)) continue;
        double extra = 0;
        if (f.kind == DataFaultKind::kClock && f.mended) extra = p.mag * p.w * f.sigma * f.to_s;
        if (f.kind == DataFaultKind::kClipping && !f.mended) extra = p.mag * f.size;
        p.sigma = std::sqrt(p.sigma * p.sigma + extra * extra);
      }
    }
  }
}

Json data_quality_to_json(const DataQuality& q) {
  Json faults = Json::array();
  for (const DataFault& f : q.faults) {
    faults.push_back({{"channel", f.channel},
                      {"kind", to_string(f.kind)},
                      {"from_s", f.from_s},
                      {"to_s", f.to_s},
                      {"size", f.size},
                      {"sigma", f.sigma},
                      {"frequency_hz", f.frequency_hz},
                      {"phase_deg", f.phase_deg},
                      {"level", f.level},
                      {"mended", f.mended},
                      {"action", f.action},
                      {"text", f.text}});
  }
  return Json{{"checked", q.checked}, {"faults", faults}};
}

DataQuality data_quality_from_json(const Json& j, const JsonWhere& where) {
  json_require_object(j, where);
  DataQuality q;
  const Json& checked = json_array_member(j, where, "checked");
  for (size_t i = 0; i < checked.size(); ++i)
    q.checked.push_back(json_string(checked[i], where / "checked" / i));
  const Json& faults = json_array_member(j, where, "faults");
  for (size_t i = 0; i < faults.size(); ++i) {
    const JsonWhere w = where / "faults" / i;
    const Json& f = faults[i];
    json_require_object(f, w);
    DataFault d;
    d.channel = json_string_member(f, w, "channel");
    const std::string kind = json_string_member(f, w, "kind");
    const auto k = enum_from_word(kKindWords, kind);
    if (!k) json_fail(w / "kind", "unknown data fault kind \"" + kind + "\"");
    d.kind = *k;
    d.from_s = json_number_member(f, w, "from_s");
    d.to_s = json_number_member(f, w, "to_s");
    d.size = json_number_member(f, w, "size");
    d.sigma = json_number_member(f, w, "sigma", 0.0);
    d.frequency_hz = json_number_member(f, w, "frequency_hz", 0.0);
    d.phase_deg = json_number_member(f, w, "phase_deg", 0.0);
    d.level = json_number_member(f, w, "level", 0.0);
    d.mended = f.contains("mended") && json_bool(f["mended"], w / "mended");
    d.action = f.contains("action") ? json_string(f["action"], w / "action") : "";
    d.text = f.contains("text") ? json_string(f["text"], w / "text") : "";
    q.faults.push_back(std::move(d));
  }
  return q;
}

}  // namespace fralab
