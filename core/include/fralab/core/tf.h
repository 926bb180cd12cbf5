// The factored transfer function of docs/formats.md §1: a DC gain times unity-DC-gain factors and
// an exact time delay,
//
//   G(s) = gain * prod_zeros F_z(s) / prod_poles F_p(s) * exp(-s * delay_s),
//
// where a real root r contributes F(s) = 1 - s/r (r = -2.83 gives s/2.83 + 1; r = +192 gives
// 1 - s/192, a right-half-plane zero) and a pair (wn, zeta) contributes s^2/wn^2 + 2 zeta s/wn + 1
// (zeta < 0: right-half-plane pair). Frequencies are rad/s. Phase convention: G(jw) = |G| e^{j phi}
// with phi in radians; a lag has phi < 0 and the delay contributes -w * delay_s exactly.
#pragma once

#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "fralab/core/json_util.h"

namespace fralab {

using Complex = std::complex<double>;

/// One factor of a factored polynomial: a real root (order 1) or a conjugate pair (order 2).
struct Root {
  bool pair = false;
  double real = 0.0;  // rad/s, the root's location s = real (real roots only); never 0
  double wn = 0.0;    // rad/s, natural frequency (pairs only), > 0
  double zeta = 0.0;  // damping ratio (pairs only); < 0 is a right-half-plane pair

  static Root Real(double r) { return Root{false, r, 0.0, 0.0}; }
  static Root Pair(double wn, double zeta) { return Root{true, 0.0, wn, zeta}; }

  int order() const { return pair ? 2 : 1; }
  /// The unity-DC-gain factor at s: 1 - s/real, or s^2/wn^2 + 2 zeta s/wn + 1.
  Complex factor(Complex s) const;
  /// factor(s) at s = j w (w in rad/s), the same value to the last bit without complex products:
  /// (1 - w^2/wn^2, 2 zeta w/wn), or (1, -w/real).
  Complex factor_jw(double w) const {
    return pair ? Complex(-(w * w) / (wn * wn) + 1.0, ((2.0 * zeta) * w) / wn)
                : Complex(1.0, -(w / real));
  }
  /// The root(s) in the s-plane (one for a real root, the pair's two for a pair).
  std::vector<Complex> locations() const;
  /// The same root as b to within rel: of one kind, a real root within rel |b.real|, a pair's wn
  /// within rel b.wn and its zeta within rel (absolute).
  bool same_as(const Root& b, double rel) const {
    if (pair != b.pair) return false;
    if (!pair) return std::abs(real - b.real) <= rel * std::abs(b.real);
    return std::abs(wn - b.wn) <= rel * b.wn && std::abs(zeta - b.zeta) <= rel;
  }
  /// Strictly in the open left half plane.
  bool stable() const { return pair ? (zeta > 0.0) : (real < 0.0); }
  /// Human form: "real -2.83" or "pair wn 49.6 zeta 0.021".
  std::string str() const;
};

struct Tf {
  double gain = 1.0;  // DC gain (value of the rational part at s = 0)
  std::vector<Root> zeros;
  std::vector<Root> poles;
  double delay_s = 0.0;         // exact pure delay, seconds, >= 0
  Json extra = Json::object();  // unknown keys read from a file, written back unchanged

  /// The rational part N(s)/D(s) at complex s (delay excluded).
  Complex rational(Complex s) const;
  /// H(jw) including the delay; w in rad/s.
  Complex at(double w) const;
  int num_order() const;
  int den_order() const;
  bool proper() const { return num_order() <= den_order(); }
  /// lim_{s->inf} of the rational part (nonzero only when num_order == den_order).
  double high_frequency_gain() const;
  /// Series connection: gains multiply, roots and delays are concatenated / added.
  Tf operator*(const Tf& other) const;
  /// The rational part as polynomials in s, highest power first (MATLAB's and Octave's
  /// `tf(num, den)` convention): num = gain * prod of the zero factors, den = prod of the pole
  /// factors, each factor unity at s = 0 (so den's last coefficient is 1 and num(0) = gain).
  std::vector<double> numerator_coefficients() const;
  std::vector<double> denominator_coefficients() const;
};

/// Reads a tf object (docs/formats.md §1). Throws InputError naming `where` for a missing gain, a
/// root at s = 0, a non-positive wn, a negative delay, an unknown root form, and (unless
/// `allow_unstable`) a pole not in the open left half plane.
Tf tf_from_json(const Json& j, const JsonWhere& where, std::vector<std::string>* warnings = nullptr,
                bool allow_unstable = false);
Json tf_to_json(const Tf& tf);
Json root_to_json(const Root& r);

}  // namespace fralab
