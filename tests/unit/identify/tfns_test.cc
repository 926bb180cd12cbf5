#include "fralab/identify/tfns.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include "fralab/plant/model.h"
#include "random_frd.h"
#include "test_util.h"

using namespace fralab;
using fralab::testing::source_path;
using fralab::testing::tf_points;
using fralab::testing::worst_root_error;

namespace {

// Every transfer function of the report (Tables 4-23 as in models/, delays true): actuators and
// paths.
std::vector<std::pair<std::string, Tf>> report_tfs() {
  std::vector<std::pair<std::string, Tf>> v;
  for (int op : {70, 85, 95}) {
    Model m = load_model(source_path("models/j85_" + std::to_string(op) + ".json"));
    for (const auto& in : m.inputs)
      v.push_back({std::to_string(op) + " u_" + in.name + ":" + in.name, *in.actuator});
    for (const auto& p : m.paths)
      v.push_back({std::to_string(op) + " " + p.input + ":" + p.output, p.tf});
  }
  return v;
}

// Each true root inside the data band has a fitted root of the same kind within
// max(tol, 3 sigma) relative distance, sigma being the fit's own standard deviation of that root
// (from the refinement's covariance); the same for the DC gain. Also counts how many are within
// tol. Misses beyond 3 sigma are counted in *beyond (and printed), not failed here: the caller
// decides.
void check_roots(const std::string& name, const std::vector<Root>& truth,
                 const std::vector<Root>& fit, const std::vector<RootInfo>& info, double lo,
                 double hi, double tol, int* within, int* total, int* beyond) {
  for (const Root& t : truth) {
    const double wt = t.pair ? t.wn : std::abs(t.real);
    if (wt < lo || wt > hi) continue;
    std::complex<double> lt = t.locations()[0];
    if (lt.imag() < 0) lt = std::conj(lt);
    double best = INFINITY, sig = 0;
    for (size_t k = 0; k < fit.size();
         ++k) {  // any kind: a zeta ~ 1 pair may come out as two reals
      std::complex<double> lf = fit[k].locations()[0];
      if (lf.imag() < 0) lf = std::conj(lf);
      const double e = std::abs(lf - lt) / std::abs(lt);
      if (e < best) best = e, sig = k < info.size() ? info[k].rel_sigma : 0;
    }
    if (!(best < std::max(tol, 3 * sig))) {
      ++*beyond;
      std::printf("beyond 3 sigma: %s root %s: error %.3g, sigma %.3g\n", name.c_str(),
                  t.str().c_str(), best, sig);
    }
    ++*total;
    *within += best < tol;
  }
}

// max_beyond: the fraction of in-band roots allowed outside max(root_tol, 3 sigma). (Two close
// real roots that come back as one pair near zeta = 1, P5/Wf 85 % at 5 % noise, are covered by the
// pair's sigma since it includes the split into two reals.)
// The gains: with sigmas that are the fit's scatter a gain lies beyond 3 of its sigma in 0.27 % of
// fits, so one of the 57 at some noise level is a 14 % event and two a 1 % one: at most
// kMaxGainsBeyond (measured: one, Wf:T5 at 85 %, whose T5 pole sits below the band and whose gain
// is extrapolated: 3.07, 3.3 and 4.0 of its sigma at 1, 2 and 5 % noise of one draw).
constexpr int kMaxGainsBeyond = 1;

void check_recovery(double noise, double root_tol, uint64_t seed, double max_beyond = 0.0) {
  int n = 0, within = 0, total = 0, beyond = 0, gains_beyond = 0;
  for (const auto& [name, tf] : report_tfs()) {
    auto pts = tf_points(tf, 0.05, 100, 10, noise, seed);  // 0.05-100 Hz, 10 points per decade
    FitOptions o;
    if (noise == 0) o.c_n = 1e-10;  // noise-free: demand an exact fit
    FitResult r = fit_tf(pts, o);
    ASSERT_EQ(r.status, FitResult::Status::kConverged) << name << ": " << r.message;
    const double lo = pts.front().w, hi = pts.back().w;  // roots inside the data band
    check_roots(name, tf.poles, r.tf.poles, r.pole_info, lo, hi, root_tol, &within, &total,
                &beyond);
    check_roots(name, tf.zeros, r.tf.zeros, r.zero_info, lo, hi, root_tol, &within, &total,
                &beyond);
    EXPECT_NEAR(r.tf.delay_s, tf.delay_s, 0.5e-3) << name;
    if (!(std::abs(r.tf.gain / tf.gain - 1.0) < std::max(root_tol, 3 * r.gain_rel_sigma))) {
      ++gains_beyond;
      std::printf("gain beyond 3 sigma: %s: error %.3g, sigma %.3g\n", name.c_str(),
                  std::abs(r.tf.gain / tf.gain - 1.0), r.gain_rel_sigma);
    }
    for (const Root& p : r.tf.poles) EXPECT_TRUE(p.stable()) << name;
    ++n;
  }
  EXPECT_EQ(n, 57);
  EXPECT_LE(gains_beyond, kMaxGainsBeyond);
  EXPECT_LE(beyond, max_beyond * total)
      << beyond << " of " << total << " roots beyond max(tol, 3 sigma)";
  std::printf("noise %.0f %%: %d of %d in-band roots within %.1f %% (%.0f %%), %d beyond 3 sigma\n",
              100 * noise, within, total, 100 * root_tol, 100.0 * within / total, beyond);
  // Most roots meet the tolerance outright; the rest are within their own 3-sigma (reported).
  // Measured: 1 % noise: 93 % of in-band roots within 2 %; 2 % noise: 82 %; 5 %: 52 %
  // (docs/validation.md).
  const double min_within = noise == 0 ? 1.0 : noise <= 0.01 ? 0.9 : noise <= 0.02 ? 0.8 : 0.45;
  EXPECT_GE(double(within) / total, min_within) << within << " of " << total;
}

// A draw of the random benchmark (tests/util/random_frd.h, sigma given), fitted by fit_tf, and its
// truth refined on the same data (the oracle; its delay free when the truth has one, as the fit's).
struct Draw {
  int index;
  double noise;
  uint64_t seed;
};
struct DrawFit {
  fralab::testing::RandomFrdCase c;
  FitResult fit, oracle;
  std::string name;  // for the test's messages
};
DrawFit fit_draw(const Draw& k) {
  DrawFit f{fralab::testing::random_frd_case(k.index, k.noise, true, k.seed), {}, {}, {}};
  FitOptions oracle;
  oracle.delay = f.c.truth.delay_s > 0 ? FitOptions::Delay::kAuto : FitOptions::Delay::kNone;
  f.oracle = refine_tf(f.c.points, f.c.truth, oracle);
  f.fit = fit_tf(f.c.points, FitOptions{});
  f.name = f.c.category + " " + std::to_string(k.index) + ": " + f.fit.message;
  return f;
}

}  // namespace

TEST(Tfns, NoiseFreeRecoversEveryReportTransferFunctionTo0_1Percent) {
  check_recovery(0.0, 1e-3, 1);
}
TEST(Tfns, OnePercentNoiseRecoversRootsWithin2Percent) { check_recovery(0.01, 0.02, 3); }
TEST(Tfns, TwoPercentNoiseRecoversRootsWithin2Percent) { check_recovery(0.02, 0.02, 3); }
TEST(Tfns, FivePercentNoiseRecoversRootsWithinTheirSigma) { check_recovery(0.05, 0.02, 3); }

TEST(Tfns, LowestAdequateOrderIsChosenByTheNoise) {
  // A third-order truth whose third pole is far above the band is not identifiable with 2 %
  // noise: the fit must stop at the order the data support (chi2/dof ~ 1), not chase the noise.
  Tf t;
  t.gain = 3.0;
  t.poles = {Root::Real(-2.0), Root::Pair(20.0, 0.3)};
  auto pts = tf_points(t, 0.05, 10, 10, 0.02, 11);
  FitResult r = fit_tf(pts, FitOptions{});
  EXPECT_EQ(r.den_order, 3) << r.message;
  EXPECT_EQ(r.num_order, 0) << r.message;
  EXPECT_GT(r.chi2_per_dof, 0.5);
  EXPECT_LT(r.chi2_per_dof, 1.5);
}

TEST(Tfns, PadeSetsAreRecognisedAndReportedAsADelay) {
  // Table 9 with its Pade factors as data (70 and 95 %).
  auto R = [](double a) { return Root::Real(-a); };
  auto P = [](double w, double z) { return Root::Pair(w, z); };
  struct Case {
    Tf tf;
    double report;
  };
  Tf a;
  a.gain = 0.0533;
  a.zeros = {R(6.37), P(34.3, .017), P(313, -.804), P(469, -.310)};
  a.poles = {R(.8), P(34, .041), P(274, .892), P(479, .328)};
  Tf c;
  c.gain = 0.0308;
  c.zeros = {R(10.8), P(50.1, .013), P(282, -.754), P(528, -.056)};
  c.poles = {R(2.83), P(49.6, .021), P(290, .853), P(542, .039)};
  for (const Case& k : {Case{a, 0.015}, Case{c, 0.011}}) {
    auto pts = tf_points(k.tf, 0.05, 100, 10, 0.0, 1);
    FitOptions o;
    o.c_n = 1e-10;
    FitResult r = fit_tf(pts, o);
    ASSERT_EQ(r.pade.size(), 2u) << fit_to_json(r, "").dump();
    // The equivalent delay is the sets' low-frequency group delay, sum 2 |zeta| / wn.
    double gd = 0;
    for (const Root& z : k.tf.zeros)
      if (z.pair && z.zeta < 0) gd += -2 * z.zeta / z.wn;
    for (const Root& p : k.tf.poles)
      if (p.pair && p.wn > 200) gd += 2 * p.zeta / p.wn;
    EXPECT_NEAR(r.pade_delay_s, gd, 1e-5);
    EXPECT_NEAR(r.pade_delay_s, k.report,
                0.75e-3);  // the report rounded: 14.3 -> 15, 11.6 -> 11 ms
  }
}

TEST(Tfns, PolesAreAlwaysStable) {
  // Data of an unstable system (a right-half-plane pole pair): the fit stays stable.
  Tf t;
  t.poles = {Root::Pair(5.0, 0.2)};
  auto pts = tf_points(t, 0.1, 10, 10, 0.0, 1);
  for (auto& p : pts)
    p.phase_deg = -p.phase_deg;  // mirror: the response of (s^2/25 - 0.08 s + 1)^-1
  FitResult r = fit_tf(pts, FitOptions{});
  for (const Root& p : r.tf.poles) EXPECT_TRUE(p.stable()) << fit_to_json(r, "").dump();
  // A stable model cannot reproduce that phase: the fit says so instead of returning an unstable
  // pole.
  EXPECT_NE(r.status, FitResult::Status::kConverged) << r.message;
  EXPECT_TRUE(r.has_model()) << r.message;
}

TEST(Tfns, FailurePathsSayWhy) {
  auto two = tf_points(Tf{}, 1, 10, 1, 0, 1);
  ASSERT_EQ(two.size(), 2u);
  FitResult r = fit_tf(two, FitOptions{});
  EXPECT_EQ(r.status, FitResult::Status::kFailed);
  EXPECT_THAT(r.message, ::testing::HasSubstr("need at least 3 valid points, have 2")) << r.message;
  FitOptions bad;
  bad.num_order_start = 3;
  bad.den_order_start = 2;
  try {
    fit_tf(tf_points(Tf{}, 1, 10, 5, 0, 1), bad);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()),
                ::testing::HasSubstr("numerator starting order must be <= denominator"));
  }
}

// Octave's invfreqs on the same data (every transfer function of the report, 2 % noise), where
// installed: our fit's relative error sum |G - G_a|^2 / |G|^2 is never worse. invfreqs gets our
// fit's orders; it has no delay, so on the delayed paths it is at a disadvantage the comparison
// keeps (the report's point: a rational in raw powers of s is what breaks).
TEST(Tfns, NeverWorseThanOctaveInvfreqs) {
  if (std::system("command -v octave-cli >/dev/null 2>&1 && octave-cli --eval 'pkg load signal' "
                  ">/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "octave-cli with the signal package is not installed";
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("fralab_invfreqs_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  struct Case {
    std::string name;
    std::vector<FrdPoint> pts;
    double ours;
  };
  std::vector<Case> cases;
  std::ofstream script(dir / "run.m");
  script << "pkg load signal; warning('off', 'all');\n";
  for (const auto& [name, tf] : report_tfs()) {
    Case c{name, tf_points(tf, 0.05, 100, 10, 0.02, 5), 0};
    FitResult r = fit_tf(c.pts, FitOptions{});
    for (const auto& p : c.pts)
      c.ours += std::norm(p.value() - r.tf.at(p.w)) / std::norm(p.value());
    const std::string file = (dir / ("d" + std::to_string(cases.size()) + ".txt")).string();
    std::ofstream f(file);
    f.precision(17);
    for (const auto& p : c.pts)
      f << p.w << " " << p.value().real() << " " << p.value().imag() << "\n";
    script << "d = load('" << file << "'); w = d(:,1); h = d(:,2) + 1i*d(:,3); "
           << "[b,a] = invfreqs(h, w, " << r.num_order << ", " << r.den_order
           << "); e = h - freqs(b, a, w); "
           << "printf('%.17g\\n', sum(abs(e).^2 ./ abs(h).^2));\n";
    cases.push_back(std::move(c));
  }
  script.close();
  const std::string cmd = "octave-cli --no-gui -q " + (dir / "run.m").string() + " > " +
                          (dir / "e.txt").string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream in(dir / "e.txt");
  int worse_for_octave = 0, octave_broke = 0;
  std::vector<double> ratio;  // invfreqs error / ours
  for (const Case& c : cases) {
    std::string tok;
    ASSERT_TRUE(in >> tok) << "octave printed no error for " << c.name;
    const double octave_err = std::strtod(tok.c_str(), nullptr);  // NaN/Inf when invfreqs broke
    if (!std::isfinite(octave_err)) {
      ++octave_broke;
      continue;
    }
    EXPECT_LE(c.ours, octave_err * (1 + 1e-9)) << c.name;
    worse_for_octave += c.ours < octave_err;
    ratio.push_back(octave_err / c.ours);
  }
  std::sort(ratio.begin(), ratio.end());
  std::printf(
      "invfreqs: %zu transfer functions; ours better on %d (error ratio invfreqs/ours: min %.3g, "
      "median %.3g), "
      "invfreqs gave no finite fit on %d\n",
      cases.size(), worse_for_octave, ratio.empty() ? 0.0 : ratio.front(),
      ratio.empty() ? 0.0 : ratio[ratio.size() / 2], octave_broke);
  std::filesystem::remove_all(dir);
}

TEST(Tfns, AZeroPathIsReportedAsNoResponse) {
  // Pure noise (a path the plant does not have): sigma as large as the "response".
  std::vector<FrdPoint> pts = tf_points(Tf{}, 0.1, 10, 10, 0.0, 1);
  std::mt19937 g(4);
  std::normal_distribution<double> n(0, 1);
  for (auto& p : pts) {
    p.mag = std::abs(std::complex<double>(n(g), n(g))) * 1e-3;
    p.sigma = 1e-3;
  }
  FitResult r = fit_tf(pts, FitOptions{});
  EXPECT_EQ(r.status, FitResult::Status::kNoResponse);
  EXPECT_EQ(r.status_str(), "no_response");
  EXPECT_THAT(r.message, ::testing::HasSubstr("no response above the noise")) << r.message;
}

// Without sigma the stop rule uses the noise level estimated from the data; noise-free
// data come back exact at the right orders, whatever the relative degree.
TEST(Tfns, NoiseFreeRelativeDegreeFiveWithoutSigmaIsExactAtTheRightOrders) {
  constexpr double kExact = 1e-9;  // rms relative error of an exact fit (noise floor 1e-9)
  Tf t;
  t.gain = 2.0;
  t.poles = {Root::Real(-1.5), Root::Pair(12.0, 0.3), Root::Pair(80.0, 0.5)};
  auto pts = tf_points(t, 0.05, 100, 10, 0.0, 1);
  FitResult r = fit_tf(pts, FitOptions{});
  EXPECT_EQ(r.status, FitResult::Status::kConverged) << r.message;
  EXPECT_EQ(r.den_order, 5) << r.message;
  EXPECT_EQ(r.num_order, 0) << r.message;
  EXPECT_LT(r.rms_rel_error, kExact) << r.message;
  EXPECT_LT(worst_root_error(t.poles, r.tf.poles, 0.3, 700), kExact);
}

// The noise estimate's over-fits (order 12-14 on a first-order truth) are degenerate: their
// polynomials' roots come in near-cancelling couples that root finding does not resolve, and the
// model built from those roots misfitted noise-free data by 537 % (85 % A8:P5), so the estimate
// let a 0/1 fit with 0.9 % error pass as converged. The over-fit's own error (of its polynomials)
// is used when rooting it loses more than kRootedSlack: noise-free data are estimated at the floor
// and come back exact at their orders.
TEST(Tfns, NoiseFreeEstimateIsNotSpoiledByRootingADegenerateOverfit) {
  int fitted = 0;
  for (const auto& [name, tf] : report_tfs()) {
    if (name != "85 A8:P5" && name != "70 A8:DPP3") continue;
    ++fitted;
    auto pts = tf_points(tf, 0.05, 100, 10, 0.0, 1);
    const FitResult r = fit_tf(pts, FitOptions{});
    EXPECT_EQ(r.noise_rel, FitOptions{}.noise_floor) << name << ": " << r.message;
    EXPECT_EQ(r.num_order, tf.num_order()) << name << ": " << r.message;
    EXPECT_EQ(r.den_order, tf.den_order()) << name << ": " << r.message;
    EXPECT_LT(r.rms_rel_error, 1e-9) << name << ": " << r.message;
  }
  EXPECT_EQ(fitted, 2);
}

TEST(Tfns, NoiseLevelWithoutSigmaIsEstimatedAndStopsAtTheRightOrder) {
  // 2 % noise, sigma withheld: the estimate is near 2 % and the order is that of the truth.
  constexpr double kNoise = 0.02;
  Tf t;
  t.gain = 0.7;
  t.zeros = {Root::Real(-30.0)};
  t.poles = {Root::Real(-2.0), Root::Pair(15.0, 0.25), Root::Real(-150.0)};
  auto pts = tf_points(t, 0.05, 100, 10, kNoise, 7);
  for (auto& p : pts) p.sigma = -1;
  FitResult r = fit_tf(pts, FitOptions{});
  EXPECT_EQ(r.status, FitResult::Status::kConverged) << r.message;
  EXPECT_GT(r.noise_rel, 0.6 * kNoise) << r.noise_rel;
  EXPECT_LT(r.noise_rel, 1.5 * kNoise) << r.noise_rel;
  EXPECT_EQ(r.den_order, 4) << r.message;
  EXPECT_EQ(r.num_order, 1) << r.message;
}

TEST(Tfns, WithoutSigmaTheStopRuleAndNumeratorOrdersAreOptions) {
  // `fralab fit --tolerance / --no-noise-estimate / --min-num-order`: the tolerance imposed is the
  // noise level used (and written to the JSON); without the estimate, TFNS's E_N rule (no level);
  // the numerator orders tried start at min_num_order.
  Tf t;
  t.gain = 0.7;
  t.zeros = {Root::Real(-30.0)};
  t.poles = {Root::Real(-2.0), Root::Pair(15.0, 0.25), Root::Real(-150.0)};
  auto pts = tf_points(t, 0.05, 100, 10, 0.02, 7);
  for (auto& p : pts) p.sigma = -1;
  FitOptions o;
  o.tolerance = 0.03;
  FitResult r = fit_tf(pts, o);
  EXPECT_EQ(r.status, FitResult::Status::kConverged) << r.message;
  EXPECT_DOUBLE_EQ(r.noise_rel, 0.03);
  EXPECT_DOUBLE_EQ(fit_to_json(r, "")["fit"]["noise_rel"].get<double>(), 0.03);
  o = FitOptions{};
  o.estimate_noise = false;
  r = fit_tf(pts, o);
  EXPECT_LT(r.noise_rel, 0.0);
  EXPECT_FALSE(fit_to_json(r, "")["fit"].contains("noise_rel"));
  o = FitOptions{};
  o.min_num_order = 2;
  r = fit_tf(pts, o);
  EXPECT_GE(r.num_order, 2) << r.message;
}

// A high relative degree with a delay (0/7, 25 ms, 28 points, 10 % noise: a draw of the random
// benchmark): the coarse delay grid's (2, 2) fits cannot tell 28 ms from 74 ms (minima within 1 %),
// and searching only around the best one the fit came back 9/9 without a delay, imitating it with
// right-half-plane zeros (criterion 103 against the truth's 68). The runner-up minimum is searched
// too: the true orders and delay come back.
TEST(Tfns, AFlatCoarseDelayGridSearchesItsRunnerUp) {
  constexpr double kDelayTol = 1e-3;  // s: the oracle's own delay is 25.2 ms
  const auto c = fralab::testing::random_frd_case(23, 0.10, true, 5);
  ASSERT_EQ(c.truth.den_order(), 7);
  ASSERT_EQ(c.truth.num_order(), 0);
  const FitResult r = fit_tf(c.points, FitOptions{});
  EXPECT_EQ(r.den_order, 7) << r.message;
  EXPECT_EQ(r.num_order, 0) << r.message;
  EXPECT_NEAR(r.tf.delay_s, c.truth.delay_s, kDelayTol) << r.message;
}

TEST(Tfns, DelayRangeIsAnOptionAndNeverExceeded) {
  constexpr double kDelayTol = 0.5e-3;  // s
  Tf t;
  t.gain = 1.0;
  t.poles = {Root::Real(-3.0), Root::Pair(40.0, 0.4)};
  t.delay_s = 0.12;  // beyond 50 ms (the second fit's range), inside the default 0.2 s
  auto pts = tf_points(t, 0.05, 50, 10, 0.0, 1);
  FitResult r = fit_tf(pts, FitOptions{});  // default range: [0, 0.2] s
  EXPECT_NEAR(r.tf.delay_s, t.delay_s, kDelayTol) << r.message;
  EXPECT_EQ(r.den_order, 3) << r.message;
  EXPECT_EQ(r.num_order, 0) << r.message;
  FitOptions o;
  o.max_delay_s = 0.05;  // the truth lies outside: the fit stays inside
  FitResult q = fit_tf(pts, o);
  EXPECT_LE(q.tf.delay_s, o.max_delay_s) << q.message;
  EXPECT_GE(q.tf.delay_s, 0.0) << q.message;
}

TEST(Tfns, AnUndampedDipoleIsNotAPadeDelay) {
  // A zero pair mirrored onto a pole pair, both undamped (zeta 1e-3, far below any Pade
  // approximant's): a spurious dipole, not a delay.
  Tf t;
  t.zeros = {Root::Pair(100.0, -1e-3)};
  t.poles = {Root::Real(-2.0), Root::Pair(100.5, 1e-3)};
  EXPECT_TRUE(find_pade_sets(t).empty());
  // The same set damped as a Pade approximant is one.
  t.zeros = {Root::Pair(100.0, -0.5)};
  t.poles = {Root::Real(-2.0), Root::Pair(100.5, 0.5)};
  EXPECT_EQ(find_pade_sets(t).size(), 1u);
}

// The identifier against an oracle told the true orders and delay (refine_tf from the truth) on the
// random generator's cases (tests/util/random_frd.h) it was not tuned on (seed 5), at 2 % noise
// with sigma and without:
// orders, model error and 3-sigma coverage of the in-band roots (bench/identify_random_bench.cc
// prints the same at every noise level).
TEST(Tfns, RandomCasesComeBackAtTheirOrdersWithTheOraclesError) {
  constexpr int kCases = 32;
  // Measured: orders 31 and 32 of 32, median ratio 1.000, 136 of 136 in-band roots within
  // max(2 %, 3 sigma). (Without refining the candidates when SK's fit already passes: 30 of 32,
  // 1.023, 96 %.)
  constexpr double kMinOrdersRight = 0.9, kMaxMedianRatio = 1.05, kMinCoverage = 0.98;
  for (const bool sigma : {true, false}) {
    int right = 0, total = 0, within = 0, beyond = 0;
    std::vector<double> ratio;
    for (int i = 0; i < kCases; ++i) {
      const auto c = fralab::testing::random_frd_case(i, 0.02, sigma, 5);
      const FitResult r = fit_tf(c.points, FitOptions{});
      FitOptions oracle;
      oracle.delay = FitOptions::Delay::kFixed;
      oracle.delay_s = c.truth.delay_s;
      const FitResult o = refine_tf(c.points, c.truth, oracle);
      right += r.num_order == c.truth.num_order() && r.den_order == c.truth.den_order();
      ratio.push_back(fralab::testing::model_error(r.tf, c.truth, c.w_lo, c.w_hi) /
                      fralab::testing::model_error(o.tf, c.truth, c.w_lo, c.w_hi));
      const std::string name = c.category + " " + std::to_string(i);
      check_roots(name, c.truth.poles, r.tf.poles, r.pole_info, c.w_lo, c.w_hi, 0.02, &within,
                  &total, &beyond);
      check_roots(name, c.truth.zeros, r.tf.zeros, r.zero_info, c.w_lo, c.w_hi, 0.02, &within,
                  &total, &beyond);
    }
    std::nth_element(ratio.begin(), ratio.begin() + kCases / 2, ratio.end());
    const double median = ratio[kCases / 2];
    std::printf("sigma %s: orders right %d of %d, median error ratio %.3f, %d of %d roots beyond\n",
                sigma ? "given" : "withheld", right, kCases, median, beyond, total);
    EXPECT_GE(right, kMinOrdersRight * kCases) << (sigma ? "with sigma" : "without sigma");
    EXPECT_LE(median, kMaxMedianRatio) << (sigma ? "with sigma" : "without sigma");
    EXPECT_GE(total - beyond, kMinCoverage * total) << (sigma ? "with sigma" : "without sigma");
  }
}

// The order search can end above the data's order with roots the data do not determine (the SK
// fit at that order needed them to pass); the pruning removes them. Two cases of the random
// benchmark that end above their orders without it: two close resonances (2/5, 2 % noise) at
// 7/10 with three pole-zero couples within 0.3 % of each other, and a path with a right-half-plane
// zero (5/5, 5 %) at 8/9 with out-of-band roots whose relative sigma exceeds 1. Both must come
// back at their true orders, at the oracle's optimum, and with no near-cancelling couple left.
TEST(Tfns, RootsTheDataDoNotDetermineArePruned) {
  // No pole-zero couple closer than this (relative) may remain: the pruned ones are within 0.3 %,
  // the first truth's own antiresonance lies 3 % from its poles.
  constexpr double kCoupleTol = 0.01;
  constexpr double kChi2Tol = 1e-3;  // relative: the oracle's optimum is reached
  for (const Draw k : {Draw{25, 0.02, 3}, Draw{10, 0.05, 2}}) {
    const auto [c, r, o, name] = fit_draw(k);
    EXPECT_EQ(r.num_order, c.truth.num_order()) << name;
    EXPECT_EQ(r.den_order, c.truth.den_order()) << name;
    EXPECT_LE(r.chi2_per_dof, o.chi2_per_dof * (1 + kChi2Tol)) << name;
    for (const Root& z : r.tf.zeros) {
      for (const Root& p : r.tf.poles) {
        if (z.pair != p.pair) continue;
        const auto lz = z.locations()[0], lp = p.locations()[0];
        EXPECT_GT(std::min(std::abs(lz - lp), std::abs(std::conj(lz) - lp)),
                  kCoupleTol * std::abs(lp))
            << name;
      }
    }
  }
}

// The true orders miss the search's adequacy test (chi^2/dof within 3 sigma of 1) by chance in
// ~0.5 % of fits: chi^2 is a sum of N exponentials. The search then goes on to an adequate higher
// order, but the criterion chooses: two draws of the random benchmark whose truth, refined, misses
// the test (a 2/5 the search alone ends at 4/7, a 1/3 + delay it ends at 2/4) must come back at
// their orders, converged, with the criterion's choice in the message.
TEST(Tfns, TheCriterionChoosesATruthThatMissesTheAdequacyTestByChance) {
  constexpr double kChi2Tol = 1e-3;  // relative: the oracle's optimum is reached
  for (const Draw k : {Draw{1, 0.02, 3}, Draw{14, 0.02, 3}}) {
    const auto [c, r, o, name] = fit_draw(k);
    // The premise: the truth at its optimum fails the 3-sigma test.
    ASSERT_GT(o.chi2_per_dof, 1 + 3 / std::sqrt(double(c.points.size()))) << o.message;
    EXPECT_EQ(r.num_order, c.truth.num_order()) << name;
    EXPECT_EQ(r.den_order, c.truth.den_order()) << name;
    EXPECT_EQ(r.status, FitResult::Status::kConverged) << name;
    EXPECT_THAT(r.message, ::testing::HasSubstr("chosen by the criterion")) << name;
    EXPECT_LE(r.chi2_per_dof, o.chi2_per_dof * (1 + kChi2Tol)) << name;
  }
}

// Past an adequate order the next one also starts nested in the adequate fit (a real pole far
// above the band, or a cancelling couple where the residual is largest): SK's and vector fitting's
// starts at that order can all refine into poorer basins than the lower order's optimum. Two draws
// of the random benchmark end one pole short without the nested start (4/5 as 4/4 at 10 % noise,
// criterion 86.2 against the truth's 83.4; 1/3 as 2/2 at 5 %); both must come back at their orders
// and the oracle's chi2.
TEST(Tfns, TheOrderAboveAnAdequateFitStartsNestedInIt) {
  constexpr double kChi2Tol = 1e-3;  // relative: the oracle's optimum is reached
  for (const Draw k : {Draw{3, 0.10, 3}, Draw{12, 0.05, 10}}) {
    const auto [c, r, o, name] = fit_draw(k);
    EXPECT_EQ(r.num_order, c.truth.num_order()) << name;
    EXPECT_EQ(r.den_order, c.truth.den_order()) << name;
    EXPECT_EQ(r.status, FitResult::Status::kConverged) << name;
    EXPECT_LE(r.chi2_per_dof, o.chi2_per_dof * (1 + kChi2Tol)) << name;
  }
}

// Data that scatter more than their sigma says (the random benchmark's cases at 2 % noise with
// sigma halved, as a multisine BLA's sigma below a weak path's scatter): no order is adequate, and
// chosen by the smallest error every fit goes to the highest order tried (0 of 32 at their orders).
// The order is chosen with sigma scaled by the scatter's level instead: the true orders come back,
// the status stays not adequate against the sigma given, and the scale is reported (the truth: 2).
TEST(Tfns, DataThatScatterMoreThanTheirSigmaAreFittedAtTheirOrders) {
  constexpr int kCases = 16;
  constexpr double kMinOrdersRight = 0.9;           // measured: 16 of 16
  constexpr double kScaleLo = 1.5, kScaleHi = 2.5;  // measured: 1.64-2.05
  int right = 0;
  for (int i = 0; i < kCases; ++i) {
    auto c = fralab::testing::random_frd_case(i, 0.02, true, 1);
    for (auto& p : c.points) p.sigma *= 0.5;
    const FitResult r = fit_tf(c.points, FitOptions{});
    const std::string name = c.category + " " + std::to_string(i) + ": " + r.message;
    right += r.num_order == c.truth.num_order() && r.den_order == c.truth.den_order();
    EXPECT_THAT(r.status, ::testing::AnyOf(FitResult::Status::kMaxOrderReached,
                                           FitResult::Status::kNotAdequate))
        << name;
    EXPECT_GT(r.sigma_scale, kScaleLo) << name;
    EXPECT_LT(r.sigma_scale, kScaleHi) << name;
    EXPECT_GT(r.chi2_per_dof, kScaleLo * kScaleLo) << name;  // against the sigma given
    EXPECT_DOUBLE_EQ(fit_to_json(r, "")["fit"].value("sigma_scale", -1.0), r.sigma_scale);
  }
  EXPECT_GE(right, kMinOrdersRight * kCases);
  // With the sigma the data carry, nothing is scaled.
  const auto c = fralab::testing::random_frd_case(0, 0.02, true, 1);
  const FitResult r = fit_tf(c.points, FitOptions{});
  EXPECT_EQ(r.sigma_scale, 1.0) << r.message;
  EXPECT_FALSE(fit_to_json(r, "")["fit"].contains("sigma_scale"));
}

// Two real poles where the data have a resonance: the refinement takes real roots of one sign in
// pairs (zeta >= 1 is two reals), so it can cross into the resonance; at the true orders (2/4,
// a pair at 0.158 rad/s near the band's lower edge, 10 % noise) the fit reaches the oracle's chi^2.
// (Refined as separate reals it stops at chi^2/dof 1.32 against 1.12.)
TEST(Tfns, RealPolesCanBecomeAResonanceInTheRefinement) {
  const auto c = fralab::testing::random_frd_case(27, 0.10, true, 1);
  ASSERT_EQ(c.truth.den_order(), 4);
  ASSERT_EQ(c.truth.num_order(), 2);
  FitOptions o;
  o.den_order_start = o.max_den_order = 4;
  o.num_order_start = o.min_num_order = 2;
  o.delay = FitOptions::Delay::kNone;
  const FitResult r = fit_tf(c.points, o);
  FitOptions oracle;
  oracle.delay = FitOptions::Delay::kNone;
  const FitResult best = refine_tf(c.points, c.truth, oracle);
  std::string poles;
  bool resonance = false;
  for (const Root& p : r.tf.poles) {
    poles += p.str() + "; ";
    resonance = resonance || (p.pair && p.zeta < 1 && p.wn < 0.3);
  }
  EXPECT_LT(r.chi2_per_dof, 1.02 * best.chi2_per_dof) << poles;
  EXPECT_TRUE(resonance) << poles;
}

// Measured data (the lab's J85 95 % auto campaign, `bash scripts/lab.sh`: the command u_Wf to P3,
// 34 points with sigma, a sharp resonance and antiresonance near 50 rad/s): adequate at 9/9. When
// SK's own fit is inadequate both its start and vector fitting's are refined: VF's start is the
// better SK fit here but refines to chi^2/dof 8.4 (max_order_reached at 8/8), SK's to 1.2.
TEST(Tfns, AMeasuredPathWithASharpResonanceIsFittedAdequately) {
  const Frd f = load_frd(source_path("tests/data/j85_95_auto_u_Wf_P3.frd.json"));
  const FitResult r = fit_tf(f.points, FitOptions{});
  EXPECT_EQ(r.status, FitResult::Status::kConverged) << r.message;
  EXPECT_LT(r.chi2_per_dof, 1.5) << r.message;
  EXPECT_NEAR(r.tf.delay_s, 0.011, 0.001) << r.message;  // the J85's Wf:P3 delay
}

// Two real poles 16 decades apart (a pole at 1e-8 rad/s: an integrator in a 0.1-100 rad/s band,
// and one at 1e8) are refined as one pair (zeta 5e7) and split back: the smaller root computed as
// -wn (zeta - sqrt(zeta^2 - 1)) cancels to -7.45e-9 or to 0 (a model the data's frequencies
// cannot evaluate); it must come back as the root it was, and the model finite.
TEST(Tfns, AnOverdampedPairSplitsBackIntoItsRealPolesExactly) {
  Tf truth;
  truth.gain = 1e8;
  truth.poles = {Root::Real(-1e-8), Root::Real(-1e8), Root::Pair(20.0, 0.3)};
  const auto pts = tf_points(truth, 0.1 / (2 * M_PI), 100 / (2 * M_PI), 10, 0.0, 1);
  FitOptions o;
  o.delay = FitOptions::Delay::kNone;
  const FitResult r = refine_tf(pts, truth, o);
  std::vector<double> reals;
  for (const Root& p : r.tf.poles)
    if (!p.pair) reals.push_back(p.real);
  ASSERT_EQ(reals.size(), 2u) << r.message;
  std::sort(reals.begin(), reals.end());
  EXPECT_NEAR(reals[0] / -1e8, 1.0, 1e-6);
  EXPECT_NEAR(reals[1] / -1e-8, 1.0, 1e-6);  // the cancelling form gave 0.745 or 0
  for (const FrdPoint& p : pts) EXPECT_TRUE(std::isfinite(std::abs(r.tf.at(p.w))));
}

// A real right-half-plane zero above the band imitates there the lag of a pole at its frequency
// (the same phase, magnitudes (w/z)^2 / 2 apart). Draws of the random benchmark whose pole lies
// 2-10x above the band fit such a zero instead when nothing prefers the lag, each at a criterion
// within 0.4 of the truth's: they must come back at their orders and the oracle's chi^2, and the
// message says what was replaced. A zero the data do support is kept: at w_max / z = 0.63 (18 % of
// magnitude at the top of the band, 1 % noise) the lag does not fit; at w_max / z = 0.25 (3 %, 2 %
// noise) the lag is adequate but the zero's criterion is lower by 5.1 (measured), beyond the 1 the
// rule asks.
TEST(Tfns, AnRhpZeroAboveTheBandIsTheLagItImitatesUnlessTheDataSayOtherwise) {
  constexpr double kChi2Tol = 1e-3;  // relative: the oracle's optimum is reached
  for (const Draw k : {Draw{12, 0.10, 1}, Draw{4, 0.05, 2}, Draw{20, 0.05, 2}, Draw{28, 0.05, 3},
                       Draw{12, 0.05, 4}}) {
    const auto [c, r, o, name] = fit_draw(k);
    ASSERT_EQ(c.category, "pole outside");
    EXPECT_EQ(r.num_order, c.truth.num_order()) << name;
    EXPECT_EQ(r.den_order, c.truth.den_order()) << name;
    EXPECT_LE(r.chi2_per_dof, o.chi2_per_dof * (1 + kChi2Tol)) << name;
    EXPECT_THAT(r.message, ::testing::HasSubstr("is the lag it imitates")) << name;
  }
  struct Supported {
    double z, noise;
    uint64_t seed;
  };
  for (const Supported k : {Supported{1000, 0.01, 3}, Supported{2500, 0.02, 2}}) {
    Tf t;
    t.gain = 2.0;
    t.poles = {Root::Real(-3.0), Root::Pair(60.0, 0.4)};
    t.zeros = {Root::Real(k.z)};  // the band's top: 2 pi 100 = 628 rad/s
    const FitResult r = fit_tf(tf_points(t, 0.05, 100, 10, k.noise, k.seed), FitOptions{});
    const std::string name = "zero at " + std::to_string(k.z) + ": " + r.message;
    EXPECT_EQ(r.num_order, 1) << name;
    EXPECT_EQ(r.den_order, 3) << name;
    ASSERT_EQ(r.tf.zeros.size(), 1u) << name;
    EXPECT_NEAR(r.tf.zeros[0].real, k.z, 3 * r.zero_info[0].rel_sigma * k.z) << name;
    EXPECT_THAT(r.message, ::testing::Not(::testing::HasSubstr("lag it imitates"))) << name;
  }
}

// Lower numerator orders are abandoned once one misses clearly, but not on a failed fit: (n, m)
// holds every (n - 1, k <= m), so an error 10x above theirs says its starts missed. Three draws of
// the random benchmark end one order short or above if the loop stops at such a fit (a 1/7 at 10 %
// noise as 0/6: every start of (7, 6) refines to chi^2/dof 466; a 3/6 at 5 % as 4/4; a 1/6 at
// 0.5 % as 4/5): each must come back at its orders and the oracle's chi^2.
TEST(Tfns, AFailedFitDoesNotEndTheLowerNumeratorOrders) {
  constexpr double kChi2Tol = 1e-3;  // relative: the oracle's optimum is reached
  for (const Draw k : {Draw{0, 0.10, 6}, Draw{3, 0.05, 2}, Draw{19, 0.005, 8}}) {
    const auto [c, r, o, name] = fit_draw(k);
    EXPECT_EQ(r.num_order, c.truth.num_order()) << name;
    EXPECT_EQ(r.den_order, c.truth.den_order()) << name;
    EXPECT_EQ(r.status, FitResult::Status::kConverged) << name;
    EXPECT_LE(r.chi2_per_dof, o.chi2_per_dof * (1 + kChi2Tol)) << name;
  }
}

// Data without sigma whose noise is additive (a measured path's output noise: 0.5 % of the peak
// |G| at every point, so sigma / |G| grows where |G| falls), the random benchmark's draws of seed
// 2: the absolute part is found and the orders are those the same data give with their sigma.
// Measured on cases 0-15: 14 of 16 as with sigma (with the absolute part turned off, 1: the
// relative level reaches 30 % and the path is called no_response), found
// in 15, b 0.55-1.67x the level drawn (median 1.19: the over-fits are SK's, near the
// least-squares optimum, not at it).
TEST(Tfns, AdditiveNoiseWithoutSigmaIsFoundAndFittedAsWithItsSigma) {
  using fralab::testing::NoiseKind;
  constexpr int kCases = 16;
  constexpr double kNoise = 0.005;
  constexpr int kMinAsWithSigma = 13, kMinFound = 13;
  constexpr double kLevelLo = 0.5, kLevelHi = 1.8;  // b / the level drawn, where found
  int as_sigma = 0, found = 0;
  for (int i = 0; i < kCases; ++i) {
    const auto c = fralab::testing::random_frd_case(i, kNoise, false, 2, NoiseKind::kAdditive);
    const auto cs = fralab::testing::random_frd_case(i, kNoise, true, 2, NoiseKind::kAdditive);
    const FitResult r = fit_tf(c.points, FitOptions{});
    const FitResult rs = fit_tf(cs.points, FitOptions{});
    as_sigma += r.num_order == rs.num_order && r.den_order == rs.den_order;
    const double b = cs.points.front().sigma;  // the same at every point
    std::printf("  %2d %-20s with sigma %d/%d, without %d/%d; level %.3g / %.3g drawn\n", i,
                c.category.c_str(), rs.num_order, rs.den_order, r.num_order, r.den_order,
                r.noise_abs, b);
    if (r.noise_abs > 0) {
      ++found;
      EXPECT_THAT(r.message, ::testing::HasSubstr("noise estimated without sigma"));
      EXPECT_EQ(fit_to_json(r, "")["fit"]["noise_abs"].get<double>(), r.noise_abs);
      EXPECT_GT(r.noise_abs, kLevelLo * b) << i << ": " << r.message;
      EXPECT_LT(r.noise_abs, kLevelHi * b) << i << ": " << r.message;
    }
  }
  EXPECT_GE(as_sigma, kMinAsWithSigma);
  EXPECT_GE(found, kMinFound);
}

// A path that is noise (no response at any frequency), without sigma: no_response, as with its
// sigma, whether the noise estimated is relative (a level of ~100 %) or absolute; and relative
// noise keeps the relative model (no absolute part reported).
TEST(Tfns, APathThatIsNoiseWithoutSigmaIsNoResponse) {
  std::mt19937_64 g(7);
  std::normal_distribution<double> nd(0.0, std::sqrt(0.5));
  std::vector<FrdPoint> pts;
  for (int i = 0; i < 40; ++i) {
    FrdPoint p;
    p.w = 0.3 * std::pow(10.0, 3.5 * i / 39);
    const std::complex<double> v(1e-3 * nd(g), 1e-3 * nd(g));
    p.mag = std::abs(v);
    p.phase_deg = std::arg(v) * 180 / M_PI;
    pts.push_back(p);
  }
  const FitResult r = fit_tf(pts, FitOptions{});
  EXPECT_EQ(r.status, FitResult::Status::kNoResponse) << r.message;
  EXPECT_THAT(r.message, ::testing::HasSubstr("no response above the noise estimated"));
  // 2 % relative noise: the relative level alone.
  const auto c = fralab::testing::random_frd_case(3, 0.02, false, 2);
  const FitResult rr = fit_tf(c.points, FitOptions{});
  EXPECT_EQ(rr.status, FitResult::Status::kConverged) << rr.message;
  EXPECT_LT(rr.noise_abs, 0) << rr.noise_abs;
  EXPECT_FALSE(fit_to_json(rr, "")["fit"].contains("noise_abs"));
}

namespace {

// Points of tf on a uniform grid of n points over [w_lo, w_hi] rad/s with complex Gaussian noise of
// absolute standard deviation sigma (sigma given with each point when sigma > 0).
std::vector<FrdPoint> uniform_points(const Tf& tf, double w_lo, double w_hi, int n, double sigma,
                                     uint64_t seed) {
  std::mt19937_64 g(seed);
  std::normal_distribution<double> nd(0.0, std::sqrt(0.5));
  std::vector<FrdPoint> out;
  for (int i = 0; i < n; ++i) {
    FrdPoint p;
    p.w = w_lo + (w_hi - w_lo) * i / (n - 1);
    std::complex<double> v = tf.at(p.w);
    if (sigma > 0) v += std::complex<double>(nd(g), nd(g)) * sigma, p.sigma = sigma;
    p.mag = std::abs(v);
    p.phase_deg = std::arg(v) * 180 / std::numbers::pi;
    out.push_back(p);
  }
  return out;
}

// The lightest pole pair of a fit (nullptr: none).
const Root* lightest_pair(const Tf& t) {
  const Root* best = nullptr;
  for (const Root& p : t.poles)
    if (p.pair && (!best || p.zeta < best->zeta)) best = &p;
  return best;
}

}  // namespace

// A resonance of Q 50 000 (zeta 1e-5) seen only in a zoom band 0.03 % wide around it, over the
// background of a zero pair outside the band (a microwave resonator's sweep): the fit is the pole
// pair at its frequency and damping. A pair that light was refused whatever the data showed; it
// stands when the grid resolves it (points on its peak).
TEST(Tfns, ALightResonanceInAZoomBandIsFittedAsItIs) {
  constexpr double kZeta = 1e-5, kBand = 3e-4;  // half-power half-width 1e-5 of wn, band 3e-4
  constexpr double kWnTol = 1e-7;               // relative; the half-width is 1e-5
  constexpr double kZetaTol = 0.02;             // relative, at 1e-3 noise
  Tf truth;
  truth.gain = 0.5;
  truth.poles = {Root::Pair(1.0, kZeta)};
  truth.zeros = {Root::Pair(1.004, 0.01)};
  const auto pts = uniform_points(truth, 1 - kBand / 2, 1 + kBand / 2, 201, 1e-3, 3);
  FitOptions o;
  o.delay = FitOptions::Delay::kNone;
  const FitResult r = fit_tf(pts, o);
  ASSERT_EQ(r.status, FitResult::Status::kConverged) << r.message;
  const Root* p = lightest_pair(r.tf);
  ASSERT_NE(p, nullptr) << r.message;
  EXPECT_NEAR(p->wn, 1.0, kWnTol) << r.message;
  EXPECT_NEAR(p->zeta / kZeta, 1.0, kZetaTol) << r.message;
}

// The same zoom-band data on an axis multiplied by any power of ten from 1e-6 to 1e12 give the
// same fit, its roots scaled: nothing in the order search depends on where the band sits. (Without
// a delay: a delay's search bounds are in seconds, and over a band this narrow a delay and the
// rational's roots nearly trade, docs/method/identifier.md.)
TEST(Tfns, AZoomBandFitDoesNotDependOnWhereTheAxisSits) {
  constexpr double kRootTol = 1e-9;  // relative, against the fit at scale 1
  Tf truth;
  truth.gain = 0.5;
  truth.poles = {Root::Pair(1.0, 1e-4), Root::Real(-0.3)};
  truth.zeros = {Root::Pair(1.01, 0.02)};
  const auto base = uniform_points(truth, 1 - 2e-3, 1 + 2e-3, 201, 1e-3, 5);
  FitOptions o;
  o.delay = FitOptions::Delay::kNone;
  const FitResult r0 = fit_tf(base, o);
  ASSERT_EQ(r0.status, FitResult::Status::kConverged) << r0.message;
  const Root* p0 = lightest_pair(r0.tf);
  ASSERT_NE(p0, nullptr) << r0.message;
  EXPECT_NEAR(p0->wn, 1.0, 1e-6) << r0.message;
  for (int e = -6; e <= 12; e += 3) {
    const double k = std::pow(10.0, e);
    auto pts = base;
    for (FrdPoint& p : pts) p.w *= k;
    const FitResult r = fit_tf(pts, o);
    const std::string name = "axis x1e" + std::to_string(e) + ": " + r.message;
    EXPECT_EQ(r.status, r0.status) << name;
    ASSERT_EQ(r.num_order, r0.num_order) << name;
    ASSERT_EQ(r.den_order, r0.den_order) << name;
    const Root* p = lightest_pair(r.tf);
    ASSERT_NE(p, nullptr) << name;
    EXPECT_NEAR(p->wn / k / p0->wn, 1.0, kRootTol) << name;
    EXPECT_NEAR(p->zeta / p0->zeta, 1.0, 1e-6) << name;
    EXPECT_NEAR(r.tf.gain / r0.tf.gain, 1.0, 1e-6) << name;
  }
}

// The status says why the search stopped. Data that scatter ten times more than their sigma says
// are adequate at no order: with room to go (maximum 10) the error stops improving first and the
// status is not_adequate, naming the order it stopped at; with the maximum at 2 the search runs
// into it: max_order_reached. (Were light pairs between the log grid's points accepted, they would
// fit single noisy points and carry the search on to the maximum.)
TEST(Tfns, TheStatusSaysWhyTheSearchStopped) {
  Tf truth;
  truth.poles = {Root::Real(-1.0), Root::Real(-10.0)};
  auto pts = tf_points(truth, 0.01, 10, 10, 0.05, 21);
  for (FrdPoint& p : pts) p.sigma *= 0.1;
  const FitResult room = fit_tf(pts, FitOptions{});
  EXPECT_EQ(room.status, FitResult::Status::kNotAdequate) << room.message;
  EXPECT_THAT(room.message, ::testing::HasSubstr("the search stopped at order")) << room.message;
  EXPECT_TRUE(room.has_model());
  FitOptions capped;
  capped.max_den_order = 2;
  const FitResult at_max = fit_tf(pts, capped);
  EXPECT_EQ(at_max.status, FitResult::Status::kMaxOrderReached) << at_max.message;
  EXPECT_THAT(at_max.message, ::testing::HasSubstr("up to the maximum, 2")) << at_max.message;
  EXPECT_EQ(fit_to_json(room, "")["fit"]["status"], "not_adequate");
}

// On a uniform grid of spacing dw, delays tau and tau + 2 pi / dw are the same data: the delay is
// searched below that ambiguity and the fit finds the true one, not an alias (a VNA's S12 came back
// with 0.115 s on a 100 MHz grid).
TEST(Tfns, TheDelayIsSearchedOnlyWhereTheGridResolvesIt) {
  constexpr double kDelayTol = 1e-3;  // relative
  Tf truth;
  truth.poles = {Root::Real(-30.0)};
  truth.delay_s = 0.9;
  const double dw = 1.0;  // ambiguity 2 pi s
  const auto pts = uniform_points(truth, 1, 60, 60, 1e-4, 8);
  FitOptions o;
  o.max_delay_s = 100;
  const FitResult r = fit_tf(pts, o);
  ASSERT_EQ(r.status, FitResult::Status::kConverged) << r.message;
  EXPECT_NEAR(r.tf.delay_s, truth.delay_s, kDelayTol * truth.delay_s) << r.message;
  EXPECT_LT(r.tf.delay_s, 2 * std::numbers::pi / dw) << r.message;
  EXPECT_THAT(r.message, ::testing::HasSubstr("the grid's ambiguity")) << r.message;
}
