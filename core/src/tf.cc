#include "fralab/core/tf.h"

#include <cmath>
#include <sstream>

#include "fralab/core/numerics.h"

namespace fralab {

Complex Root::factor(Complex s) const {
  if (pair) return s * s / (wn * wn) + 2.0 * zeta * s / wn + 1.0;
  return 1.0 - s / real;
}

std::vector<Complex> Root::locations() const {
  if (!pair) return {Complex(real, 0.0)};
  // s^2 + 2 zeta wn s + wn^2 = 0
  Complex disc = std::sqrt(Complex(zeta * zeta - 1.0, 0.0));
  return {wn * (-zeta + disc), wn * (-zeta - disc)};
}

std::string Root::str() const {
  std::ostringstream os;
  if (pair) {
    os << "pair wn " << wn << " rad/s zeta " << zeta;
  } else {
    os << "real " << real << " rad/s";
  }
  return os.str();
}

// One complex division for the whole denominator. The running products are kept within
// 2^-500..2^500 by exact power-of-two scalings whose exponent is applied to the quotient, so roots
// decades away from s cannot overflow (or underflow) them; inside that range the arithmetic is the
// plain quotient.
namespace {
template <class Factor>
Complex rational_with(const Tf& t, Factor factor) {
  static const double kBig = std::ldexp(1.0, 500), kSmall = std::ldexp(1.0, -500);
  Complex num(t.gain, 0.0), den(1.0, 0.0);
  int exponent = 0;  // the value is num / den * 2^exponent
  auto keep_in_range = [&](Complex& v, int sign) {
    const double m = std::abs(v.real()) + std::abs(v.imag());
    if (m > kBig) {
      v = Complex(std::ldexp(v.real(), -500), std::ldexp(v.imag(), -500));
      exponent += sign * 500;
    } else if (m < kSmall && m > 0) {
      v = Complex(std::ldexp(v.real(), 500), std::ldexp(v.imag(), 500));
      exponent -= sign * 500;
    }
  };
  for (const Root& z : t.zeros) {
    num *= factor(z);
    keep_in_range(num, 1);
  }
  for (const Root& p : t.poles) {
    den *= factor(p);
    keep_in_range(den, -1);
  }
  const Complex q = detail::quotient(num, den);
  return exponent == 0 ? q
                       : Complex(std::ldexp(q.real(), exponent), std::ldexp(q.imag(), exponent));
}
}  // namespace

Complex Tf::rational(Complex s) const {
  return rational_with(*this, [s](const Root& r) { return r.factor(s); });
}

Complex Tf::at(double w) const {
  const Complex r = rational_with(*this, [w](const Root& f) { return f.factor_jw(w); });
  return delay_s == 0 ? r : r * std::polar(1.0, -w * delay_s);
}

namespace {
// prod of the factors as a polynomial, highest power first.
std::vector<double> expand(const std::vector<Root>& roots, double scale) {
  std::vector<double> c{scale};
  for (const Root& r : roots) {
    const std::vector<double> f =
        r.pair ? std::vector<double>{1.0 / (r.wn * r.wn), 2.0 * r.zeta / r.wn, 1.0}
               : std::vector<double>{-1.0 / r.real, 1.0};
    std::vector<double> out(c.size() + f.size() - 1, 0.0);
    for (size_t i = 0; i < c.size(); ++i)
      for (size_t k = 0; k < f.size(); ++k) out[i + k] += c[i] * f[k];
    c = std::move(out);
  }
  return c;
}
}  // namespace

std::vector<double> Tf::numerator_coefficients() const { return expand(zeros, gain); }
std::vector<double> Tf::denominator_coefficients() const { return expand(poles, 1.0); }

int Tf::num_order() const {
  int n = 0;
  for (const Root& z : zeros) n += z.order();
  return n;
}

int Tf::den_order() const {
  int n = 0;
  for (const Root& p : poles) n += p.order();
  return n;
}

double Tf::high_frequency_gain() const {
  if (num_order() != den_order()) return 0.0;
  // Leading coefficients: -1/r for a real factor, 1/wn^2 for a pair.
  double v = gain;
  for (const Root& z : zeros) v *= z.pair ? 1.0 / (z.wn * z.wn) : -1.0 / z.real;
  for (const Root& p : poles) v /= p.pair ? 1.0 / (p.wn * p.wn) : -1.0 / p.real;
  return v;
}

Tf Tf::operator*(const Tf& o) const {
  Tf r;
  r.gain = gain * o.gain;
  r.zeros = zeros;
  r.zeros.insert(r.zeros.end(), o.zeros.begin(), o.zeros.end());
  r.poles = poles;
  r.poles.insert(r.poles.end(), o.poles.begin(), o.poles.end());
  r.delay_s = delay_s + o.delay_s;
  return r;
}

static Root root_from_json(const Json& j, const JsonWhere& where, bool is_pole, bool allow_unstable,
                           std::vector<std::string>* warnings) {
  json_require_object(j, where);
  const bool has_real = j.contains("real");
  const bool has_pair = j.contains("wn") || j.contains("zeta");
  if (has_real == has_pair) {
    json_fail(where,
              "a root is either {\"real\": r} or {\"wn\": w, \"zeta\": z}, found " + j.dump());
  }
  Root r;
  if (has_real) {
    json_unknown_members(j, where, {"real"}, warnings);
    r = Root::Real(json_number_member(j, where, "real"));
    if (r.real == 0.0) {
      json_fail(where / "real", "a root at s = 0 is not allowed (the gain is the DC gain)");
    }
  } else {
    json_unknown_members(j, where, {"wn", "zeta"}, warnings);
    r = Root::Pair(json_number_member(j, where, "wn"), json_number_member(j, where, "zeta"));
    if (r.wn <= 0.0) json_fail(where / "wn", "wn must be > 0 rad/s, found " + std::to_string(r.wn));
  }
  if (is_pole && !allow_unstable && !r.stable()) {
    std::string fix = r.pair ? "zeta must be > 0 for a pole pair"
                             : "a stable real pole has real < 0, e.g. {\"real\": " +
                                   std::to_string(-std::abs(r.real)) + "}";
    json_fail(where, "unstable pole (" + r.str() +
                         "): poles must lie in the open left half plane; " + fix);
  }
  return r;
}

Tf tf_from_json(const Json& j, const JsonWhere& where, std::vector<std::string>* warnings,
                bool allow_unstable) {
  json_require_object(j, where);
  Tf tf;
  tf.extra = json_unknown_members(j, where, {"gain", "zeros", "poles", "delay_s"}, warnings);
  tf.gain = json_number_member(j, where, "gain");
  const Json& zs = json_array_member(j, where, "zeros", true);
  for (size_t i = 0; i < zs.size(); ++i) {
    tf.zeros.push_back(root_from_json(zs[i], where / "zeros" / i, false, true, warnings));
  }
  const Json& ps = json_array_member(j, where, "poles", true);
  for (size_t i = 0; i < ps.size(); ++i) {
    tf.poles.push_back(root_from_json(ps[i], where / "poles" / i, true, allow_unstable, warnings));
  }
  tf.delay_s = json_number_member(j, where, "delay_s", 0.0);
  if (tf.delay_s < 0.0) {
    json_fail(where / "delay_s", "a delay must be >= 0 s, found " + std::to_string(tf.delay_s));
  }
  return tf;
}

Json root_to_json(const Root& r) {
  if (r.pair) return Json{{"wn", r.wn}, {"zeta", r.zeta}};
  return Json{{"real", r.real}};
}

Json tf_to_json(const Tf& tf) {
  Json j = tf.extra.is_object() ? tf.extra : Json::object();
  j["gain"] = tf.gain;
  j["zeros"] = Json::array();
  for (const Root& z : tf.zeros) j["zeros"].push_back(root_to_json(z));
  j["poles"] = Json::array();
  for (const Root& p : tf.poles) j["poles"].push_back(root_to_json(p));
  if (tf.delay_s != 0.0) j["delay_s"] = tf.delay_s;
  return j;
}

}  // namespace fralab
