#include "fralab/analyze/period_fft.h"

#include <algorithm>

namespace fralab {

PeriodFft::PeriodFft(int period_samples)
    : P_(period_samples), buf_(size_t(period_samples)), spec_(size_t(period_samples / 2 + 1)) {
  plan_ = fftw_plan_dft_r2c_1d(P_, buf_.data(), reinterpret_cast<fftw_complex*>(spec_.data()),
                               FFTW_ESTIMATE);
}

PeriodFft::~PeriodFft() { fftw_destroy_plan(plan_); }

const std::vector<std::complex<double>>& PeriodFft::operator()(const double* x) {
  std::copy(x, x + P_, buf_.begin());
  fftw_execute(plan_);
  return spec_;
}

}  // namespace fralab
