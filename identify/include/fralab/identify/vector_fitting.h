// Vector fitting: the poles of a rational model of a scalar frequency response, found by
// relocating a start set of poles (Gustavsen and Semlyen 1999, with the relaxed non-triviality
// constraint of Gustavsen 2006). fit_tf uses them as starting denominators of its SK iteration:
// from poles spread over the band, VF reaches a good basin where SK from D = 1 can stall in a poor
// one.
//
// Each iteration solves, in the least-squares sense with weights W_i on |e_i|^2,
//   sum_k c_k phi_k(s_i) + d  -  g_i (sum_k ct_k phi_k(s_i) + dt)  =  0,   s_i = j w_i,
// with phi_k the partial fractions of the current poles (real poles 1/(s - a); a pair a, conj(a) as
// 1/(s-a) + 1/(s-conj a) and j/(s-a) - j/(s-conj a)), under Re sum_i (sum_k ct_k phi_k(s_i) + dt) =
// M (the relaxation: dt is free but the scaling function cannot vanish). The zeros of the scaling
// function sigma(s) = dt + sum ct_k phi_k(s) are the new poles: the eigenvalues of A - b ct^T / dt
// (A, b the real state-space form of the partial fractions); unstable ones are reflected into the
// left half plane. Frequencies are scaled by sqrt(w_min w_max) inside.
//
// Start poles: n/2 pairs with wn log-spaced over [w_min, w_max], real part -wn/100; with n odd, one
// real pole at -sqrt(w_min w_max).
// Units: w rad/s; poles in rad/s (the s-plane), each pair listed once with its upper-half-plane
// member and its conjugate.
#pragma once

#include <complex>
#include <vector>

namespace fralab {

struct VectorFitOptions {
  int max_iterations = 10;  // pole relocations
  double tolerance = 1e-6;  // stop when no pole moves by more than this, relative to its modulus
  /// Throws InputError naming the bad option.
  void validate() const;
};

struct VectorFitResult {
  std::vector<std::complex<double>> poles;  // n poles, stable, conjugates both listed
  int iterations = 0;
  bool ok = false;  // false: fewer than n + 1 points, or a singular least-squares problem
};

/// n poles of a rational fit to g_i at s = j w_i (weights W_i >= 0; w_i > 0 and distinct).
VectorFitResult vector_fit_poles(const std::vector<double>& w,
                                 const std::vector<std::complex<double>>& g,
                                 const std::vector<double>& W, int n,
                                 const VectorFitOptions& o = {});

}  // namespace fralab
