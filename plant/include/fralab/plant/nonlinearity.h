// Actuator nonlinearities of contracts 2, applied sample by sample to the actuator's deviation from
// its operating point x (input units), and their sinusoidal-input describing functions
// N(A) = (first harmonic of the output) / (input amplitude A), complex, phase in radians
// (negative = lag), for x = A sin(w t).
#pragma once

#include <complex>
#include <memory>

#include "fralab/plant/model.h"

namespace fralab {

class Nonlinearity {
 public:
  virtual ~Nonlinearity() = default;
  /// One sample: input deviation -> output deviation.
  virtual double apply(double x) = 0;
  virtual void reset() = 0;
};

/// Builds the element; `dc` is the operating point (for absolute saturation limits), `h` the sample
/// period in seconds (rate limits).
std::unique_ptr<Nonlinearity> make_nonlinearity(const NonlinearitySpec& spec, double dc, double h);

/// Backlash of total width w: the output holds until the input is w/2 beyond it, then follows.
/// For A > w/2, with r = (w/2)/A:
///   Re N = (1/pi) [pi/2 + asin(1 - 2r) + 2 (1 - 2r) sqrt(r (1 - r))],  Im N = -(4 r / pi)(1 - r);
/// N = 0 for A <= w/2 (the output never moves).
std::complex<double> backlash_describing_function(double amplitude, double width);

/// Deadband of total width w (zero while |x| < w/2, else x -/+ w/2). Real; for A > w/2, with
/// r = (w/2)/A: N = 1 - (2/pi)(asin r + r sqrt(1 - r^2)); 0 for A <= w/2.
double deadband_describing_function(double amplitude, double width);

}  // namespace fralab
