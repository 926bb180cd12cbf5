#include "fralab/analyze/fourier_filter.h"

#include <cmath>

namespace fralab {

Reference make_reference(size_t n, double phi0, double dphi, int harmonic) {
  Reference r;
  r.c.resize(n);
  r.s.resize(n);
  const double hd = harmonic * dphi;
  const Complex rot = std::polar(1.0, hd);
  Complex z;
  for (size_t k = 0; k < n; ++k) {
    if ((k & 1023) == 0) z = std::polar(1.0, harmonic * (phi0 + double(k) * dphi));
    r.c[k] = z.real();
    r.s[k] = z.imag();
    z *= rot;
  }
  return r;
}

Reference make_reference(const double* phase, size_t n, int harmonic) {
  Reference r;
  r.c.resize(n);
  r.s.resize(n);
  for (size_t k = 0; k < n; ++k) {
    r.c[k] = std::cos(harmonic * phase[k]);
    r.s[k] = std::sin(harmonic * phase[k]);
  }
  return r;
}

void fourier_sums(const double* x, const double* c, const double* s, size_t n, double* sum_c,
                  double* sum_s) {
  double a0 = 0, a1 = 0, b0 = 0, b1 = 0;
  size_t k = 0;
  for (; k + 1 < n; k += 2) {  // two accumulators each: lets the compiler vectorise
    a0 += x[k] * c[k];
    a1 += x[k + 1] * c[k + 1];
    b0 += x[k] * s[k];
    b1 += x[k + 1] * s[k + 1];
  }
  for (; k < n; ++k) {
    a0 += x[k] * c[k];
    b0 += x[k] * s[k];
  }
  *sum_c = a0 + a1;
  *sum_s = b0 + b1;
}

Complex fourier_phasor(const double* x, const Reference& ref, size_t begin, size_t end) {
  double sc, ss;
  fourier_sums(x + begin, ref.c.data() + begin, ref.s.data() + begin, end - begin, &sc, &ss);
  const double g = 2.0 / double(end - begin);
  return {g * ss, g * sc};  // A1 + j B1
}

std::pair<Complex, Complex> fitted_phasors(const double* x1, const double* x2, const Reference& ref,
                                           size_t begin, size_t end) {
  double cc = 0, s2 = 0, cs = 0;
  for (size_t k = begin; k < end; ++k) {
    cc += ref.c[k] * ref.c[k];
    s2 += ref.s[k] * ref.s[k];
    cs += ref.c[k] * ref.s[k];
  }
  // [s2 cs; cs cc] [A1; B1] = [sum x s; sum x c]
  const double det = s2 * cc - cs * cs;
  if (!(std::abs(det) > 1e-12 * (s2 * cc)))
    return {fourier_phasor(x1, ref, begin, end), fourier_phasor(x2, ref, begin, end)};
  auto fit = [&](const double* x) {
    double sc, ss;
    fourier_sums(x + begin, ref.c.data() + begin, ref.s.data() + begin, end - begin, &sc, &ss);
    return Complex{(ss * cc - sc * cs) / det, (sc * s2 - ss * cs) / det};
  };
  return {fit(x1), fit(x2)};
}

}  // namespace fralab
