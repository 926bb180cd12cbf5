// The Fourier filter of the report's Appendix A, digital and over whole cycles.
//
// For a signal x[k] = A1 sin(phi_k) + B1 cos(phi_k) + (DC, harmonics, noise), with the reference
// phase phi_k = phi0 + k dphi (radians) spanning a whole number N of cycles in L samples,
//
//   A1 = (2/L) sum x[k] sin(phi_k),   B1 = (2/L) sum x[k] cos(phi_k)
//
// and the fundamental's phasor is P = A1 + j B1: x ~ |P| sin(phi + arg P) (A-10: E = |P|,
// phi = atan2(B1, A1)). DC and harmonics 2, 3, ... integrate to zero over whole cycles. The ratio
// of two channels' phasors P2/P1 is the amplitude ratio |E2/E1| and phase phi2 - phi1 (radians,
// positive = E2 leads E1). Harmonic h uses h * phi.
//
// Kernel: the reference e^{j h phi_k} is generated once per window by a rotation recurrence
// (recomputed exactly every 1024 samples: over a 400-cycle window the reference stays within 1e-12
// of exact), then every
// channel costs two multiply-adds per sample.
#pragma once

#include <complex>
#include <cstddef>
#include <utility>
#include <vector>

namespace fralab {

using Complex = std::complex<double>;

/// cos(h phi_k) and sin(h phi_k) for k in [0, n): the reference of harmonic h.
struct Reference {
  std::vector<double> c, s;
};
Reference make_reference(size_t n, double phi0, double dphi, int harmonic = 1);
/// The same for an arbitrary per-sample reference phase (a sweep: phase from the tape).
Reference make_reference(const double* phase, size_t n, int harmonic = 1);

/// The phasor P = A1 + j B1 of x[0..n) against `ref` (n samples), normalised by 2/n.
Complex fourier_phasor(const double* x, const Reference& ref, size_t begin, size_t end);

/// The same phasors of two channels x1, x2 fitted by least squares, x ~ A1 sin(phi) + B1 cos(phi)
/// over [begin, end) (one normal matrix for both): fourier_phasor's over whole cycles; over a span
/// that splits a cycle (a block of a window), free of the negative-frequency image the plain sums
/// leak there.
std::pair<Complex, Complex> fitted_phasors(const double* x1, const double* x2, const Reference& ref,
                                           size_t begin, size_t end);

/// Raw sums sum x c and sum x s over [begin, end): the two multiply-adds per sample.
void fourier_sums(const double* x, const double* c, const double* s, size_t n, double* sum_c,
                  double* sum_s);

}  // namespace fralab
