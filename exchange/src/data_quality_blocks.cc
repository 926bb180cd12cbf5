// The schedule's integration windows cut into blocks and each block's values at the excited
// lines, the slope of per-block values over a run, and small helpers the checks share
// (data_quality_checks.h).
#include <algorithm>
#include <cmath>
#include <set>

#include "data_quality_checks.h"
#include "fralab/analyze/period_fft.h"
#include "fralab/core/numerics.h"
#include "fralab/core/text.h"

namespace fralab::dq {

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

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
  return v[v.size() / 2];
}

Slope SlopeAccumulator::solve(bool empirical) const {
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

}  // namespace fralab::dq
