#include "fralab/plant/nonlinearity.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

namespace fralab {
namespace {

class Deadband : public Nonlinearity {
 public:
  explicit Deadband(double w) : half_(w / 2) {}
  double apply(double x) override {
    if (x > half_) return x - half_;
    if (x < -half_) return x + half_;
    return 0.0;
  }
  void reset() override {}

 private:
  double half_;
};

class Backlash : public Nonlinearity {
 public:
  explicit Backlash(double w) : half_(w / 2) {}
  double apply(double x) override {
    y_ = std::clamp(y_, x - half_, x + half_);
    return y_;
  }
  void reset() override { y_ = 0.0; }

 private:
  double half_;
  double y_ = 0.0;
};

class RateLimit : public Nonlinearity {
 public:
  RateLimit(double rate, double h) : step_(rate * h) {}
  double apply(double x) override {
    y_ += std::clamp(x - y_, -step_, step_);
    return y_;
  }
  void reset() override { y_ = 0.0; }

 private:
  double step_;
  double y_ = 0.0;
};

class Saturation : public Nonlinearity {
 public:
  Saturation(double lo, double hi) : lo_(lo), hi_(hi) {}
  double apply(double x) override { return std::clamp(x, lo_, hi_); }
  void reset() override {}

 private:
  double lo_, hi_;
};

}  // namespace

std::unique_ptr<Nonlinearity> make_nonlinearity(const NonlinearitySpec& s, double dc, double h) {
  switch (s.kind) {
    case NonlinearityKind::kDeadband:
      return std::make_unique<Deadband>(s.width);
    case NonlinearityKind::kHysteresis:
      return std::make_unique<Backlash>(s.width);
    case NonlinearityKind::kRateLimit:
      return std::make_unique<RateLimit>(s.rate, h);
    case NonlinearityKind::kSaturation:
      if (!(s.min <= dc && dc <= s.max)) {
        throw InputError("saturation [" + std::to_string(s.min) + ", " + std::to_string(s.max) +
                         "] excludes the operating point " + std::to_string(dc));
      }
      return std::make_unique<Saturation>(s.min - dc, s.max - dc);
  }
  throw InputError("unknown nonlinearity kind");
}

std::complex<double> backlash_describing_function(double a, double w) {
  const double b = w / 2;
  if (a <= b) return {0.0, 0.0};
  const double r = b / a;
  const double pi = std::numbers::pi;
  const double re = (pi / 2 + std::asin(1 - 2 * r) + 2 * (1 - 2 * r) * std::sqrt(r * (1 - r))) / pi;
  const double im = -(4 * r / pi) * (1 - r);
  return {re, im};
}

double deadband_describing_function(double a, double w) {
  const double b = w / 2;
  if (a <= b) return 0.0;
  const double r = b / a;
  return 1.0 - (2 / std::numbers::pi) * (std::asin(r) + r * std::sqrt(1 - r * r));
}

MultisineBla multisine_bla(const NonlinearitySpec& spec, const std::vector<int>& lines,
                           const std::vector<double>& amplitudes, int realisations, uint64_t seed) {
  if (!has_width(spec.kind))
    throw InputError(std::string("multisine_bla: \"") + to_string(spec.kind) +
                     "\" is not a rate-independent element (hysteresis or deadband)");
  if (lines.empty() || lines.size() != amplitudes.size())
    throw InputError("multisine_bla: " + std::to_string(lines.size()) + " lines for " +
                     std::to_string(amplitudes.size()) + " amplitudes");
  if (realisations < 2) throw InputError("multisine_bla: realisations must be >= 2");
  int kmax = 0;
  for (int k : lines) {
    if (k < 1 || k > kMaxMultisineLine)
      throw InputError("multisine_bla: line " + std::to_string(k) + " outside 1.." +
                       std::to_string(kMaxMultisineLine));
    kmax = std::max(kmax, k);
  }
  for (double a : amplitudes)
    if (!std::isfinite(a) || a < 0)
      throw InputError("multisine_bla: amplitude " + std::to_string(a) + " is not finite >= 0");
  int P = 1024;  // >= 16 samples a cycle of the highest line (the element sees its peaks)
  while (P < 16 * kmax) P *= 2;
  const size_t L = lines.size(), B = size_t(P / 2 + 1);
  std::vector<double> x(P), y(P);
  std::vector<std::complex<double>> spec_x(B), spec_y(B);
  fftw_plan synth = fftw_plan_dft_c2r_1d(P, reinterpret_cast<fftw_complex*>(spec_x.data()),
                                         x.data(), FFTW_ESTIMATE);
  fftw_plan analyse = fftw_plan_dft_r2c_1d(
      P, y.data(), reinterpret_cast<fftw_complex*>(spec_y.data()), FFTW_ESTIMATE);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 2 * std::numbers::pi);
  std::vector<std::vector<std::complex<double>>> ratio(L);
  for (int r = 0; r < realisations; ++r) {
    // x[n] = sum a cos(2 pi k n / P + phi): bin k of the half spectrum holds (a / 2) e^{j phi}.
    std::fill(spec_x.begin(), spec_x.end(), 0.0);
    for (size_t j = 0; j < L; ++j)
      spec_x[size_t(lines[j])] += std::polar(amplitudes[j] / 2, phase(rng));
    const std::vector<std::complex<double>> line_x = [&] {
      std::vector<std::complex<double>> v(L);
      for (size_t j = 0; j < L; ++j) v[j] = spec_x[size_t(lines[j])];
      return v;
    }();
    fftw_execute(synth);  // unnormalised: x as defined above
    auto element = make_nonlinearity(spec, 0.0, 1.0 / P);
    for (int n = 0; n < P; ++n) element->apply(x[size_t(n)]);  // the first period: from rest
    for (int n = 0; n < P; ++n) y[size_t(n)] = element->apply(x[size_t(n)]);
    fftw_execute(analyse);
    for (size_t j = 0; j < L; ++j)
      ratio[j].push_back(line_x[j] == 0.0 ? 0.0
                                          : spec_y[size_t(lines[j])] / (double(P) * line_x[j]));
  }
  fftw_destroy_plan(synth);
  fftw_destroy_plan(analyse);
  MultisineBla out;
  for (size_t j = 0; j < L; ++j) {
    std::complex<double> m = 0;
    for (const auto& v : ratio[j]) m += v / double(realisations);
    double var = 0;
    for (const auto& v : ratio[j]) var += std::norm(v - m) / double(realisations - 1);
    out.g.push_back(m);
    out.var_nl.push_back(var);
  }
  return out;
}

}  // namespace fralab
