#include "fralab/core/tf.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

using namespace fralab;

namespace {
constexpr double kDeg = 180.0 / std::numbers::pi;
Json J(const char* s) { return Json::parse(s); }
}  // namespace

TEST(Tf, RealPoleIsALagOfMinus45DegreesAtItsCorner) {
  Tf tf = tf_from_json(J(R"({"gain": 2.0, "poles": [{"real": -2.83}]})"), {"t", ""});
  Complex g = tf.at(2.83);
  EXPECT_NEAR(std::abs(g), 2.0 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(std::arg(g) * kDeg, -45.0, 1e-9);
  EXPECT_NEAR(std::abs(tf.at(0.0)), 2.0, 1e-15);  // gain is the DC gain
}

TEST(Tf, RightHalfPlaneZeroLagsAndKeepsDcGainSign) {
  // [S/192 - 1] written {"real": 192}: factor 1 - s/192, DC gain +1, phase -45 deg at 192 rad/s.
  Tf tf = tf_from_json(J(R"({"gain": 1.0, "zeros": [{"real": 192}]})"), {"t", ""});
  EXPECT_NEAR(tf.at(0.0).real(), 1.0, 1e-15);
  EXPECT_NEAR(std::arg(tf.at(192.0)) * kDeg, -45.0, 1e-9);
}

TEST(Tf, PairFactorAtItsNaturalFrequencyIsTwoZetaJ) {
  Tf tf = tf_from_json(J(R"({"gain": 1.0, "zeros": [{"wn": 50.1, "zeta": 0.013}]})"), {"t", ""});
  Complex g = tf.at(50.1);
  EXPECT_NEAR(g.real(), 0.0, 1e-12);
  EXPECT_NEAR(g.imag(), 2 * 0.013, 1e-12);
}

TEST(Tf, DelayIsExactMinusOmegaTau) {
  Tf tf = tf_from_json(J(R"({"gain": 1.0, "delay_s": 0.011})"), {"t", ""});
  for (double w : {1.0, 100.0, 628.0}) {
    EXPECT_NEAR(std::abs(tf.at(w)), 1.0, 1e-14);
    EXPECT_NEAR(std::remainder(std::arg(tf.at(w)) + w * 0.011, 2 * std::numbers::pi), 0.0, 1e-12);
  }
}

TEST(Tf, HighFrequencyGainOfBiproperTf) {
  // (1 + s/10) / (1 + s/100): lim = 10.
  Tf tf = tf_from_json(J(R"({"gain": 1.0, "zeros": [{"real": -10}], "poles": [{"real": -100}]})"),
                       {"t", ""});
  EXPECT_NEAR(tf.high_frequency_gain(), 10.0, 1e-12);
  EXPECT_NEAR(std::abs(tf.at(1e7)), 10.0, 1e-3);
}

TEST(Tf, UnstablePoleIsRejectedNamingFileAndPath) {
  try {
    tf_from_json(J(R"({"gain": 1.0, "poles": [{"real": -1}, {"real": 2.83}]})"),
                 {"m.json", "/paths/3/tf"});
    FAIL() << "no throw";
  } catch (const InputError& e) {
    std::string msg = e.what();
    EXPECT_THAT(msg, ::testing::HasSubstr("m.json: /paths/3/tf/poles/1")) << msg;
    EXPECT_THAT(msg, ::testing::HasSubstr("unstable pole")) << msg;
    EXPECT_THAT(msg, ::testing::HasSubstr("{\"real\": -2.83")) << msg;
  }
}

TEST(Tf, NegativeDampingPoleIsRejected) {
  EXPECT_THROW(
      tf_from_json(J(R"({"gain": 1.0, "poles": [{"wn": 63.6, "zeta": -0.188}]})"), {"f", ""}),
      InputError);
  // ... but allowed for zeros (a right-half-plane pair).
  EXPECT_NO_THROW(
      tf_from_json(J(R"({"gain": 1.0, "zeros": [{"wn": 63.6, "zeta": -0.188}]})"), {"f", ""}));
}

TEST(Tf, MalformedRootsAndMissingGainNameTheProblem) {
  auto msg = [](const char* s) {
    try {
      tf_from_json(Json::parse(s), {"f.json", "/tf"});
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(msg(R"({"poles": []})"), ::testing::HasSubstr("missing required key \"gain\""));
  EXPECT_THAT(msg(R"({"gain": 1, "zeros": [{"real": 0}]})"), ::testing::HasSubstr("s = 0"));
  EXPECT_THAT(msg(R"({"gain": 1, "poles": [{"wn": -3, "zeta": 0.5}]})"),
              ::testing::HasSubstr("wn must be > 0"));
  EXPECT_THAT(msg(R"({"gain": "1"})"), ::testing::HasSubstr("expected a number"));
  EXPECT_THAT(msg(R"({"gain": 1, "delay_s": -0.01})"), ::testing::HasSubstr("delay must be >= 0"));
  EXPECT_THAT(msg(R"({"gain": 1, "poles": [{"real": -1, "wn": 2}]})"),
              ::testing::HasSubstr("either"));
}

namespace {
// Every field of two tfs compared bit for bit, the roots in listing order and the unknown keys as
// JSON: one line per difference, none when the same.
std::vector<std::string> differences(const Tf& a, const Tf& b) {
  std::vector<std::string> out;
  auto roots = [&](const char* what, const std::vector<Root>& x, const std::vector<Root>& y) {
    if (x.size() != y.size()) {
      out.push_back(std::string(what) + ": " + std::to_string(x.size()) + " against " +
                    std::to_string(y.size()));
      return;
    }
    for (size_t i = 0; i < x.size(); ++i)
      if (x[i].pair != y[i].pair || x[i].real != y[i].real || x[i].wn != y[i].wn ||
          x[i].zeta != y[i].zeta)
        out.push_back(std::string(what) + "[" + std::to_string(i) + "]: " + x[i].str() +
                      " against " + y[i].str());
  };
  if (a.gain != b.gain) out.push_back("gain");
  roots("zeros", a.zeros, b.zeros);
  roots("poles", a.poles, b.poles);
  if (a.delay_s != b.delay_s) out.push_back("delay_s");
  if (a.extra != b.extra) out.push_back("extra: " + a.extra.dump() + " against " + b.extra.dump());
  return out;
}
}  // namespace

// Read, written, written out as text and read again: every field of the file comes back as read,
// bit for bit. The roots are listed out of frequency order on purpose (the writer keeps the
// listing order, it does not sort) and the file carries keys the format does not define (kept
// and written back unchanged, nested values included). Written back, the file is the one read.
// Each single change (a root swapped with its neighbour, a root's value or kind, the gain, the
// delay, an unknown key dropped or changed) is a difference the comparison names.
TEST(Tf, JsonRoundTripKeepsEveryFieldTheRootOrderAndTheUnknownKeys) {
  const char* src = R"({"gain": 0.0308,
                        "zeros": [{"wn": 50.1, "zeta": 0.013}, {"real": -10.8}, {"real": 192}],
                        "poles": [{"wn": 49.6, "zeta": 0.021}, {"real": -2.83}, {"real": -700}],
                        "delay_s": 0.011,
                        "units": "rad/s", "note": {"by": "hand", "rev": 3}, "tags": [1, "a", null]})";
  Tf want;
  want.gain = 0.0308;
  want.zeros = {Root::Pair(50.1, 0.013), Root::Real(-10.8), Root::Real(192)};
  want.poles = {Root::Pair(49.6, 0.021), Root::Real(-2.83), Root::Real(-700)};
  want.delay_s = 0.011;
  want.extra = J(R"({"units": "rad/s", "note": {"by": "hand", "rev": 3}, "tags": [1, "a", null]})");
  const Tf a = tf_from_json(J(src), {"t", ""});
  EXPECT_THAT(differences(a, want), ::testing::IsEmpty()) << "as read";
  const Json written = tf_to_json(a);
  EXPECT_EQ(written, J(src));
  const Tf b = tf_from_json(Json::parse(written.dump()), {"t", ""});
  EXPECT_THAT(differences(a, b), ::testing::IsEmpty()) << "read back";

  std::vector<std::pair<const char*, Tf>> changed;
  auto change = [&](const char* what, auto edit) {
    Tf c = b;
    edit(c);
    changed.emplace_back(what, c);
  };
  change("poles swapped", [](Tf& c) { std::swap(c.poles[0], c.poles[1]); });
  change("zeros swapped", [](Tf& c) { std::swap(c.zeros[1], c.zeros[2]); });
  change("a zeta", [](Tf& c) { c.poles[0].zeta = std::nextafter(c.poles[0].zeta, 1.0); });
  change("a wn", [](Tf& c) { c.zeros[0].wn = std::nextafter(c.zeros[0].wn, 100.0); });
  change("a real root", [](Tf& c) { c.poles[2].real = std::nextafter(c.poles[2].real, 0.0); });
  change("a pair made real", [](Tf& c) { c.zeros[0] = Root::Real(-50.1); });
  change("the gain", [](Tf& c) { c.gain = std::nextafter(c.gain, 1.0); });
  change("the delay", [](Tf& c) { c.delay_s = std::nextafter(c.delay_s, 1.0); });
  change("an unknown key dropped", [](Tf& c) { c.extra.erase("units"); });
  change("an unknown nested value", [](Tf& c) { c.extra["note"]["rev"] = 4; });
  for (const auto& [what, c] : changed)
    EXPECT_THAT(differences(a, c), ::testing::Not(::testing::IsEmpty())) << what;
}

// num/den, highest power first: 2 [1 - s/4] / ([s/2 + 1][(s/10)^2 + 2 (0.3) s/10 + 1]).
TEST(Tf, PolynomialCoefficientsAreTheFactorsExpanded) {
  Tf tf;
  tf.gain = 2.0;
  tf.zeros = {Root::Real(4.0)};
  tf.poles = {Root::Real(-2.0), Root::Pair(10.0, 0.3)};
  const auto num = tf.numerator_coefficients(), den = tf.denominator_coefficients();
  ASSERT_EQ(num.size(), 2u);
  EXPECT_DOUBLE_EQ(num[0], -0.5);
  EXPECT_DOUBLE_EQ(num[1], 2.0);
  ASSERT_EQ(den.size(), 4u);
  EXPECT_DOUBLE_EQ(den[0], 0.5 * 0.01);         // s^3
  EXPECT_DOUBLE_EQ(den[1], 0.01 + 0.5 * 0.06);  // s^2
  EXPECT_DOUBLE_EQ(den[2], 0.06 + 0.5);         // s
  EXPECT_DOUBLE_EQ(den[3], 1.0);
  for (double w : {0.3, 3.0, 30.0}) {
    const Complex s{0, w};
    Complex n = 0, d = 0;
    for (double c : num) n = n * s + c;
    for (double c : den) d = d * s + c;
    EXPECT_LT(std::abs(n / d - tf.rational(s)), 1e-14 * std::abs(tf.rational(s))) << w;
  }
}

// 40 zeros at 1e-8 rad/s and 40 poles at 1.0001e-8: at 1e4 rad/s each factor is ~1e12, so the
// numerator's and the denominator's products alone are ~1e480 (beyond double); the value is the
// ratio, (1.0001)^40 in magnitude and a phase of 40 (atan(w/1e-8) - atan(w/1.0001e-8)) ~ 0.
TEST(Tf, ManyRootsFarBelowTheFrequencyDoNotOverflow) {
  Tf t;
  t.gain = 1.0;
  for (int k = 0; k < 40; ++k) {
    t.zeros.push_back(Root::Real(-1e-8));
    t.poles.push_back(Root::Real(-1.0001e-8));
  }
  const Complex g = t.at(1e4);
  ASSERT_TRUE(std::isfinite(std::abs(g)));
  EXPECT_NEAR(std::abs(g), std::pow(1.0001, 40), 1e-9);
  EXPECT_NEAR(std::arg(g), 0.0, 1e-9);
}

// The fitter evaluates factors on the imaginary axis by factor_jw; it must be factor(j w) to the
// last bit (the fits' results must not depend on which one computed them). Random roots over 12
// decades, both signs, pairs from zeta -2 to 2, frequencies over 12 decades.
TEST(Tf, FactorOnTheImaginaryAxisIsTheGenericFactorBitForBit) {
  unsigned long long state = 12345;
  auto uniform = [&] {  // a 64-bit LCG: the same draws on every machine
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return double(state >> 11) * 0x1.0p-53;
  };
  int compared = 0;
  for (int k = 0; k < 2000; ++k) {
    const double mag = std::pow(10.0, -6 + 12 * uniform());
    const Root r = uniform() < 0.5 ? Root::Real(uniform() < 0.5 ? -mag : mag)
                                   : Root::Pair(mag, -2 + 4 * uniform());
    Tf t;
    (uniform() < 0.5 ? t.zeros : t.poles).push_back(r);
    const double w = std::pow(10.0, -6 + 12 * uniform());
    const Complex a = r.factor_jw(w), b = r.factor(Complex(0.0, w));
    ASSERT_EQ(a.real(), b.real()) << r.str() << " at " << w;
    ASSERT_EQ(a.imag(), b.imag()) << r.str() << " at " << w;
    const Complex ta = t.at(w), tb = t.rational(Complex(0.0, w));
    ASSERT_EQ(ta.real(), tb.real()) << r.str() << " at " << w;
    ASSERT_EQ(ta.imag(), tb.imag()) << r.str() << " at " << w;
    ++compared;
  }
  EXPECT_EQ(compared, 2000);
}
