// The identifier on measured data nobody here made (tests/data/realdata, each folder's
// PROVENANCE.md says where it comes from and what was published): one test per data set, each
// checked against the published figure or, where none is published, against what the data show
// (said at each test). Default options, as a new user runs `fralab fit --frd FILE`.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <string>
#include <vector>

#include "fralab/identify/common_poles.h"
#include "fralab/identify/readers.h"
#include "fralab/identify/tfns.h"
#include "test_util.h"

namespace fralab {
namespace {

using fralab::testing::source_path;

std::vector<FrdPoint> load(const std::string& rel) {
  return read_frd_csv(source_path("tests/data/realdata/" + rel)).points;
}

FitResult fit(const std::vector<FrdPoint>& pts) { return fit_tf(pts, FitOptions{}); }

// The lightest pole pair of a fit (nullptr: none): the resonance of a one-mode sweep.
const Root* lightest_pair(const Tf& t) {
  const Root* best = nullptr;
  for (const Root& p : t.poles)
    if (p.pair && (!best || p.zeta < best->zeta)) best = &p;
  return best;
}

// rms over the points of |G_fit(j w) - G|.
double rms_error(const Tf& t, const std::vector<FrdPoint>& pts) {
  double s = 0;
  for (const FrdPoint& p : pts) s += std::norm(t.at(p.w) - p.value());
  return std::sqrt(s / double(pts.size()));
}

// NPL Report MAT 58 (A. P. Gregory, 2021): four VNA sweeps across single microwave resonances, zoom
// bands 0.003-0.7 % wide, Q_L 708-56 020. The fit's lightest pole pair is the resonance: its
// frequency within 1e-5 of MAT 58's loaded frequency f_L and its Q = 1 / (2 zeta) within 5 % of
// Q_L. (Figure23's published figures come after de-embedding 0.5 m of cable, which the file is
// not; Figure27's Q_L from NLQFIT6 weights the points near the notch more: least squares on the
// same points gives 53 704, PROVENANCE.md.)
struct NplCase {
  const char* file;
  double f_l_hz, q_l;
};
constexpr double kNplFreqTol = 1e-5, kNplQTol = 0.05;

void check_npl(const NplCase& c) {
  const FitResult r = fit(load(std::string("npl_qfactor_mat58/") + c.file));
  ASSERT_TRUE(r.has_model()) << c.file << ": " << r.message;
  const Root* p = lightest_pair(r.tf);
  ASSERT_NE(p, nullptr) << c.file << ": " << r.message;
  EXPECT_NEAR(p->wn / (2 * std::numbers::pi) / c.f_l_hz, 1.0, kNplFreqTol)
      << c.file << ": " << r.message;
  EXPECT_NEAR(1 / (2 * p->zeta) / c.q_l, 1.0, kNplQTol) << c.file << ": " << r.message;
}

TEST(RealData, NplFigure6bTransmission) {
  check_npl({"figure6b_s21_transmission.csv", 3.987848e9, 7454});
}
TEST(RealData, NplFigure23TransmissionWithLeakage) {
  check_npl({"figure23_s21_transmission.csv", 9.76015571e9, 4760.04});
}
TEST(RealData, NplFigure27AbsorptionNotch) {
  check_npl({"figure27_s21_absorption_notch.csv", 6.07225567e9, 56019.85});
}
TEST(RealData, NplTable6c27Reflection) {
  check_npl({"table6c27_s11_reflection.csv", 3.65293800e9, 708});
}

// The Silverbox (Wigren and Schoukens 2013): an electronic mass-spring-damper with a hardening
// spring. No numbers are published for its linear part; the data show one resonance whose frequency
// rises with the excitation level (PROVENANCE.md: a weighted least-squares fit of K / (s^2 + 2 zeta
// wn s + wn^2) to each file gives 68.41, 69.53 and 70.67 Hz for the low-level arrow, the random
// multisine's BLA and the high-level arrow). The fit's resonance is each of those within 0.2 % (a
// fifth of the level's shift), its damping within 5 %.
TEST(RealData, SilverboxResonanceRisesWithLevel) {
  constexpr double kFreqTol = 2e-3, kZetaTol = 0.05;
  struct Level {
    const char* file;
    double fn_hz, zeta;
  };
  const Level levels[] = {{"arrow_h1_low_amplitude.csv", 68.41, 0.0480},
                          {"bla_random_odd_multisine.csv", 69.53, 0.0488},
                          {"arrow_h1_high_amplitude.csv", 70.67, 0.0492}};
  double prev = 0;
  for (const Level& l : levels) {
    const FitResult r = fit(load(std::string("silverbox/") + l.file));
    ASSERT_TRUE(r.has_model()) << l.file << ": " << r.message;
    const Root* p = lightest_pair(r.tf);
    ASSERT_NE(p, nullptr) << l.file << ": " << r.message;
    const double fn = p->wn / (2 * std::numbers::pi);
    EXPECT_NEAR(fn / l.fn_hz, 1.0, kFreqTol) << l.file << ": " << r.message;
    EXPECT_NEAR(p->zeta / l.zeta, 1.0, kZetaTol) << l.file << ": " << r.message;
    EXPECT_GT(fn, prev) << l.file;
    prev = fn;
  }
}

// scikit-rf's measured 190 GHz two-port: four S-parameters on a 100 MHz grid. scikit-rf's vector
// fitting test asserts sqrt(sum over the four of mean |S - S_fit|^2) < 0.02 (with one pole set for
// all four); fitted one by one, fralab must meet the same figure. S12 is mostly noise: on a 100
// MHz grid any delay of 10 ns more is the same data, so the delay found lies within 10 ns.
TEST(RealData, SkrfTwoPortEachResponse) {
  constexpr double kSkrfRms = 0.02;
  constexpr double kAmbiguity = 10e-9;  // 1 / 100 MHz
  double sum = 0;
  for (const char* s : {"S11", "S12", "S21", "S22"}) {
    const auto pts = load(std::string("skrf_vna_measured/190ghz_tx_measured_") + s + ".csv");
    const FitResult r = fit(pts);
    ASSERT_TRUE(r.has_model()) << s << ": " << r.message;
    const double e = rms_error(r.tf, pts);
    sum += e * e;
    EXPECT_LE(r.tf.delay_s, kAmbiguity) << s << ": " << r.message;
  }
  EXPECT_LT(std::sqrt(sum), kSkrfRms);
}

// Cascaded tanks (Schoukens and Noel 2017): two tanks in series, water level out, pump voltage in.
// No linear model is published; linearised, Torricelli's outflow gives two real poles (one per
// tank) and no resonance, which is what the best linear approximation must show: two real poles,
// no pair, a positive static gain.
TEST(RealData, CascadedTanksAreTwoRealPoles) {
  const FitResult r = fit(load("cascaded_tanks/bla_two_records.csv"));
  ASSERT_TRUE(r.has_model()) << r.message;
  EXPECT_EQ(r.den_order, 2) << r.message;
  for (const Root& p : r.tf.poles) EXPECT_FALSE(p.pair) << r.message;
  EXPECT_GT(r.tf.gain, 0) << r.message;
}

// An impact-hammer accelerance (pyFRF's example, 3995 lines of 1 Hz, sigma from the coherence): no
// modal reference is published; the data show peaks at 900.0, 2640.3, 3669 and ~3690 Hz, the last
// two a close pair (PROVENANCE.md: an SDOF fit around each peak). Default options: the order search
// reaches its maximum (10) short of them, and the pole set (up to 40 poles) replaces it. Each peak
// has a pole pair within 0.2 % in frequency, and the fit's rms error is below 10 % of the data's
// rms.
TEST(RealData, ImpactHammerModesAreEachAPolePair) {
  constexpr double kFreqTol = 2e-3, kRmsTol = 0.10;
  const auto pts = load("pyfrf_impact_hammer/h1_accelerance.csv");
  const FitResult r = fit(pts);
  ASSERT_TRUE(r.has_model()) << r.message;
  for (double f : {900.0, 2640.3, 3669.0, 3690.0}) {
    double best = INFINITY;
    for (const Root& p : r.tf.poles)
      if (p.pair) best = std::min(best, std::abs(p.wn / (2 * std::numbers::pi) / f - 1));
    EXPECT_LT(best, kFreqTol) << f << " Hz: " << r.message;
  }
  double v = 0;
  for (const FrdPoint& p : pts) v += std::norm(p.value());
  EXPECT_LT(rms_error(r.tf, pts), kRmsTol * std::sqrt(v / double(pts.size()))) << r.message;
}

// The 190 GHz two-port's four responses with one pole set (`fralab fit --common-poles`), at most
// 12 poles as scikit-rf's test allows (`--max-poles 12`): sqrt of the summed mean-square errors
// below scikit-rf's threshold, 0.02. With the default (100) more poles are taken, the error lower.
TEST(RealData, SkrfTwoPortCommonPoles) {
  constexpr double kSkrfRms = 0.02;
  std::vector<Frd> curves;
  std::vector<std::string> names;
  for (const char* s : {"S11", "S12", "S21", "S22"}) {
    names.push_back(std::string("skrf_vna_measured/190ghz_tx_measured_") + s + ".csv");
    curves.push_back(read_frd_csv(source_path("tests/data/realdata/" + names.back())));
  }
  CommonPoleOptions o;
  o.fit.max_poles = 12;
  const CommonPoleResult r12 = fit_common_poles(curves, names, o);
  EXPECT_LE(r12.fit.order, 12) << r12.fit.message;
  EXPECT_LT(r12.rms_total, kSkrfRms) << r12.fit.message;
  const CommonPoleResult r = fit_common_poles(curves, names);
  EXPECT_LE(r.rms_total, r12.rms_total) << r.fit.message;
}

// Agilent E5071B 4-port, 16 responses on 206 points: scikit-rf's documentation reports an rms error
// below 0.01 over the 16 with 53 poles, from an unweighted fit. Unweighted too (`--unweighted`),
// at most 53 poles: below 0.01.
TEST(RealData, SkrfFourPortCommonPoles) {
  constexpr double kRms = 0.01;
  std::vector<Frd> curves;
  std::vector<std::string> names;
  for (int a = 1; a <= 4; ++a) {
    for (int b = 1; b <= 4; ++b) {
      names.push_back("skrf_vna_measured/Agilent_E5071B_S" + std::to_string(a) + std::to_string(b) +
                      ".csv");
      curves.push_back(read_frd_csv(source_path("tests/data/realdata/" + names.back())));
    }
  }
  CommonPoleOptions o;
  o.fit.max_poles = 53;
  o.unweighted = true;
  const CommonPoleResult r = fit_common_poles(curves, names, o);
  EXPECT_LE(r.fit.order, 53) << r.fit.message;
  EXPECT_LT(r.rms_total, kRms) << r.fit.message;
}

// F-16 ground vibration test, level 1 (f16_gvt/PROVENANCE.md): three accelerometers over the
// shaker's force on 267 lines in 2-15 Hz, measured far better (sigma about 0.1 % of |G|) than a
// linear model fits them (the full-grid multisine's nonlinear distortion is not in sigma). With
// the defaults one pole set fits the three to rms |ln(G_fit / G)| <= 0.05 over every point, and
// the stabilisation diagram marks physical the wing-torsion and wing-bending modes at the
// frequencies PROVENANCE.md's local single-mode fits give (7.318 and 5.188 Hz), within 0.3 %.
// The fit against sigma alone (no relative floor) leaves the small responses tens of percent off.
std::vector<Frd> f16_level(int level) {
  std::vector<Frd> out;
  for (int j = 1; j <= 3; ++j)
    out.push_back(read_frd_csv(source_path("tests/data/realdata/f16_gvt/L" + std::to_string(level) +
                                           "_force_acc" + std::to_string(j) + ".csv")));
  return out;
}

const std::vector<std::string> kF16Sources = {"L1_force_acc1.csv", "L1_force_acc2.csv",
                                              "L1_force_acc3.csv"};

TEST(RealData, F16GvtLevel1OnePoleSetReachesTheDatasLevelWithItsModesPhysical) {
  constexpr double kLogError = 0.05, kModeRel = 0.003;
  constexpr double kTorsionHz = 7.318, kBendingHz = 5.188;
  const CommonPoleResult r = fit_common_poles(f16_level(1), kF16Sources);
  EXPECT_LE(r.rms_log_total, kLogError) << r.fit.message;
  EXPECT_TRUE(r.floor_taken) << r.fit.message;
  ASSERT_TRUE(r.diagram.has_value());
  for (double f : {kTorsionHz, kBendingHz}) {
    bool found = false;
    for (size_t k = 0; k < r.fit.poles.size(); ++k) {
      const double fk = std::abs(r.fit.poles[k]) / (2 * std::numbers::pi);
      found = found || (r.physical[k] && std::abs(fk / f - 1) < kModeRel);
    }
    EXPECT_TRUE(found) << f << " Hz not a physical pole of " << r.fit.message;
  }
}

TEST(RealData, F16GvtLevel1AgainstSigmaAloneMissesTheSmallResponses) {
  constexpr double kLogErrorWithoutFloor = 0.1;
  CommonPoleOptions o;
  o.relative_floor = false;
  o.stabilisation = false;
  const CommonPoleResult r = fit_common_poles(f16_level(1), kF16Sources, o);
  EXPECT_GT(r.rms_log_total, kLogErrorWithoutFloor) << r.fit.message;
}

}  // namespace
}  // namespace fralab
