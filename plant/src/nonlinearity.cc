#include "fralab/plant/nonlinearity.h"

#include <algorithm>
#include <cmath>
#include <numbers>

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
  if (s.type == "deadband") return std::make_unique<Deadband>(s.width);
  if (s.type == "hysteresis") return std::make_unique<Backlash>(s.width);
  if (s.type == "rate_limit") return std::make_unique<RateLimit>(s.rate, h);
  if (s.type == "saturation") {
    if (!(s.min <= dc && dc <= s.max)) {
      throw InputError("saturation [" + std::to_string(s.min) + ", " + std::to_string(s.max) +
                       "] excludes the operating point " + std::to_string(dc));
    }
    return std::make_unique<Saturation>(s.min - dc, s.max - dc);
  }
  throw InputError("unknown nonlinearity type \"" + s.type + "\"");
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

}  // namespace fralab
