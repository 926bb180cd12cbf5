// The spectrum of one period of a sampled signal, by FFTW's real-to-complex transform:
//   X(k) = sum_{n=0}^{P-1} x[n] exp(-j 2 pi k n / P),  k = 0 .. P/2
// (unscaled: a sine of amplitude A on line k gives |X(k)| = A P / 2). One plan per period length,
// made once (FFTW_ESTIMATE) and executed for every period given: the multisine analyser's and the
// data-quality checks' per-period spectra.
#pragma once

#include <fftw3.h>

#include <complex>
#include <vector>

namespace fralab {

class PeriodFft {
 public:
  explicit PeriodFft(int period_samples);
  ~PeriodFft();
  PeriodFft(const PeriodFft&) = delete;
  PeriodFft& operator=(const PeriodFft&) = delete;
  /// The spectrum of x[0 .. P-1] (P/2 + 1 values), valid until the next call.
  const std::vector<std::complex<double>>& operator()(const double* x);
  int period() const { return P_; }

 private:
  int P_;
  std::vector<double> buf_;
  std::vector<std::complex<double>> spec_;
  fftw_plan plan_;
};

}  // namespace fralab
