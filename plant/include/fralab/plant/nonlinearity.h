// Actuator nonlinearities of docs/formats.md §2, applied sample by sample to the actuator's
// deviation from its operating point x (input units), and their sinusoidal-input describing
// functions N(A) = (first harmonic of the output) / (input amplitude A), complex, phase in radians
// (negative = lag), for x = A sin(w t).
#pragma once

#include <complex>
#include <cstdint>
#include <memory>
#include <vector>

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

/// The counterpart of a describing function for a multisine: the best linear
/// approximation (BLA) of a rate-independent element (hysteresis, deadband) whose input is a
/// random-phase multisine x[n] = sum_j a_j cos(2 pi k_j n / P + phi_j), phi_j uniform, lines k_j
/// (harmonics of one period, any positive integers), a_j the peak amplitude of each (input units,
/// at the element's input). Per line, BLA_j = E[Y(k_j) / X(k_j)] over the phases, estimated from
/// `realisations` seeded random-phase periods (P the power of 2 >= max(1024, 16 max k_j) samples;
/// the element run for two periods from rest, the second, periodic one transformed: a backlash
/// forgets its start after one period). Only the input's path matters to such an element, not its
/// speed, so neither the sample rate nor the frequency of a line enters. var_nl: the variance of
/// one realisation's Y/X about the BLA (its stochastic nonlinear distortion). A small multisine
/// inside a backlash's width moves nothing: BLA 0. InputError for another element, lines outside
/// 1..kMaxMultisineLine, amplitudes not finite >= 0, sizes that disagree, or realisations < 2.
inline constexpr int kMaxMultisineLine = 1 << 16;  // periods of up to 2^20 samples simulated
struct MultisineBla {
  std::vector<std::complex<double>> g;
  std::vector<double> var_nl;
};
MultisineBla multisine_bla(const NonlinearitySpec& spec, const std::vector<int>& lines,
                           const std::vector<double>& amplitudes, int realisations = 8,
                           uint64_t seed = 1);

}  // namespace fralab
