#include "fralab/analyze/pair_analyzer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <set>

#include "fralab/acquire/acquisition.h"
#include "fralab/plant/lti.h"
#include "fralab/plant/nonlinearity.h"
#include "test_util.h"

using namespace fralab;
using fralab::testing::simulate_tape;
using fralab::testing::source_path;

namespace {

std::vector<FrdPoint> analyse(const fralab::testing::TapeRun& run, const std::string& pair,
                              const std::vector<size_t>& order = {},
                              const std::set<int64_t>& drop = {}) {
  PairAnalyzer a(pair);
  for (const auto& e : run.events) a.on_status(e);
  if (order.empty()) {
    for (const auto& b : run.blocks)
      if (!drop.count(b.seq)) a.on_block(b);
  } else {
    for (size_t i : order)
      if (!drop.count(run.blocks[i].seq)) a.on_block(run.blocks[i]);
  }
  a.flush();
  return a.frd().points;
}

Complex pt(const FrdPoint& p) { return p.value(); }

// The middle sample of the run's k-th integration window.
int64_t window_middle(const fralab::testing::TapeRun& run, int k) {
  int i = 0;
  for (const auto& e : run.events)
    if (e.state == RunState::kIntegrate && i++ == k) return e.sample + e.n_samples / 2;
  return -1;
}

// The exact sampled response of the plant's channel to its input's command (lti.h).
Complex sampled(const Model& m, const std::string& input, const std::string& ch, double w) {
  auto tf = m.command_chain(input, ch);
  if (ch == "u_" + input) return 1.0;
  return foh_sampled_response(*tf, w, 1000.0);
}

SteppedSineOptions band(double lo, double hi, int ppd) {
  SteppedSineOptions o;
  o.f_lo_hz = lo;
  o.f_hi_hz = hi;
  o.points_per_decade = ppd;
  o.slowest_time_constant_s = 1.0;
  o.min_integrate_s = 2.0;
  return o;
}

// A 2x2 plant for the multisine tests: actuators a, b (40 rad/s lags), outputs y, z, four lags.
Model two_by_two() {
  Model m;
  m.source = "test";
  for (const char* n : {"a", "b"}) {
    ModelInput in;
    in.name = n;
    in.units = "1";
    in.full_scale = 1.0;
    Tf act;
    act.poles = {Root::Real(-40.0)};
    in.actuator = act;
    m.inputs.push_back(in);
  }
  for (const char* n : {"y", "z"}) {
    ModelOutput out;
    out.name = n;
    out.units = "1";
    m.outputs.push_back(out);
  }
  auto lag = [](double g, double a) {
    Tf t;
    t.gain = g;
    t.poles = {Root::Real(-a)};
    return t;
  };
  m.paths = {{"y", "a", lag(2, 3), Json::object()},
             {"z", "a", lag(-1, 8), Json::object()},
             {"y", "b", lag(0.5, 1), Json::object()},
             {"z", "b", lag(3, 20), Json::object()}};
  return m;
}

}  // namespace

// The analyser's accuracy: noise off, every pair within 1e-4 relative and 0.01 degree of the
// plant's exact response over 0.1-100 Hz (the plant's deviation from continuous H(jw) is the
// FOH's, lti.h).
TEST(PairAnalyzer, NoiseFreeAccuracyAgainstThePlant) {
  Model m = load_model(source_path("models/j85_95.json"));
  auto run = simulate_tape(m, {"Wf"}, band(0.1, 100, 4), false, 1);
  for (const std::string pair : {"Wf:P3", "Wf:N", "Wf:T5", "u_Wf:Wf", "u_Wf:P3", "P3:P5"}) {
    auto [e1, e2] = split_pair(pair);
    auto pts = analyse(run, pair);
    ASSERT_EQ(pts.size(), 13u) << pair;
    for (const auto& p : pts) {
      ASSERT_TRUE(p.valid) << p.note;
      Complex want = sampled(m, "Wf", e2, p.w) / sampled(m, "Wf", e1, p.w);
      EXPECT_NEAR(std::abs(pt(p)) / std::abs(want), 1.0, 1e-4) << pair << " " << p.w;
      EXPECT_NEAR(std::arg(pt(p) / want) * 180 / std::numbers::pi, 0.0, 0.01) << pair << " " << p.w;
    }
  }
}

// A sign slip cannot pass: a pure delay gives -w tau, a lag lags, against the analytic model.
TEST(PairAnalyzer, PhaseConventionOnAnalyticPlants) {
  Tf delay;
  delay.delay_s = 0.0113;
  Tf lag;
  lag.poles = {Root::Real(-20.0)};
  for (const Tf& t : {delay, lag}) {
    Model m = fralab::testing::siso_model(t);
    auto run = simulate_tape(m, {"u"}, band(0.5, 20, 3), false, 1);
    for (const auto& p : analyse(run, "u:y")) {
      const double expect = t.delay_s > 0 ? -p.w * 0.0113 : -std::atan(p.w / 20.0);
      EXPECT_NEAR(
          std::remainder(p.phase_deg * std::numbers::pi / 180 - expect, 2 * std::numbers::pi), 0.0,
          2e-4)
          << p.w;
      EXPECT_LT(p.phase_deg, 0.0);
    }
  }
}

// Noise off, sigma is nothing: each block's phasors, from which sigma is taken, are fitted by
// least squares. With the filter's plain sums, a block that splits a cycle (20 cycles in 8 blocks
// of 2.5) leaked the negative-frequency image by an amount turning with its starting phase,
// differently in the two channels: sigma up to 1e-3 of |G| where the window's estimate was exact.
TEST(PairAnalyzer, NoiseFreeSigmaIsNothingWhereCyclesDoNotDivideIntoTheBlocks) {
  constexpr double kNothing = 1e-9;  // relative to |G|: rounding, against the leak's 1e-3
  Tf t;
  t.gain = 2.0;
  t.poles = {Root::Real(-5.0)};
  Model m = fralab::testing::siso_model(t, nullptr, nullptr, 0.5);
  auto run = simulate_tape(m, {"u"}, band(0.3, 30, 4), false, 1);
  int split = 0;
  for (const auto& p : analyse(run, "u:y")) {
    ASSERT_TRUE(p.valid) << p.note;
    split += p.n_cycles % 8 != 0;
    EXPECT_LT(p.sigma / p.mag, kNothing) << p.w << " rad/s, " << p.n_cycles << " cycles";
  }
  EXPECT_GT(split, 0) << "no point whose cycles the blocks would split";
}

TEST(PairAnalyzer, SigmaCoversTheErrorAsOftenAsItClaims) {
  // Complex Gaussian error with standard deviation sigma: P(|err| < sigma) = 1 - 1/e = 0.632,
  // P(|err| < 2 sigma) = 0.982 (sigma itself estimated from 8 blocks: slightly lower coverage).
  Tf t;
  t.gain = 2.0;
  t.poles = {Root::Real(-5.0)};
  Model m = fralab::testing::siso_model(t, nullptr, nullptr, 0.5);
  int n = 0, in1 = 0, in2 = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    auto run = simulate_tape(m, {"u"}, band(0.3, 30, 4), true, seed, 100, 1.0);
    for (const auto& p : analyse(run, "u:y")) {
      double err = std::abs(pt(p) - t.at(p.w) * std::pow(std::sin(p.w / 2000) / (p.w / 2000), 2));
      ++n;
      in1 += err < p.sigma;
      in2 += err < 2 * p.sigma;
    }
  }
  ASSERT_EQ(n, 40 * 9);
  EXPECT_NEAR(double(in1) / n, 0.632, 0.08);
  EXPECT_GT(double(in2) / n, 0.93);
}

TEST(PairAnalyzer, LostBlockInvalidatesOnlyItsPointAndSaysSo) {
  Model m = load_model(source_path("models/j85_95.json"));
  auto run = simulate_tape(m, {"Wf"}, band(1, 10, 3), false, 1);
  auto full = analyse(run, "Wf:P3");
  // Drop a block inside the second integration window.
  const int64_t seq = window_middle(run, 1) / 100;
  auto lossy = analyse(run, "Wf:P3", {}, {seq});
  ASSERT_EQ(lossy.size(), full.size());
  int invalid = 0;
  for (size_t i = 0; i < full.size(); ++i) {
    if (!lossy[i].valid) {
      ++invalid;
      EXPECT_THAT(lossy[i].note, ::testing::HasSubstr("seq " + std::to_string(seq) + " missing"))
          << lossy[i].note;
    } else {
      EXPECT_EQ(lossy[i].mag, full[i].mag);
      EXPECT_EQ(lossy[i].phase_deg, full[i].phase_deg);
    }
  }
  EXPECT_EQ(invalid, 1);
}

// A free-running plant's held samples (tape channel "underrun" 1) inside a window make that point
// invalid, naming the samples; an "underrun" channel of zeros changes nothing.
TEST(PairAnalyzer, HeldSamplesOfAFreeRunningPlantInvalidateTheirWindow) {
  Model m = load_model(source_path("models/j85_95.json"));
  auto run = simulate_tape(m, {"Wf"}, band(1, 10, 3), false, 1);
  auto full = analyse(run, "Wf:P3");
  const int64_t mid = window_middle(run, 2);
  for (auto& b : run.blocks) {
    b.channels.push_back(kUnderrunChannel);
    for (int i = 0; i < b.n_samples; ++i)
      b.samples.push_back(b.start_sample + i >= mid && b.start_sample + i < mid + 5 ? 1.0 : 0.0);
  }
  auto held = analyse(run, "Wf:P3");
  ASSERT_EQ(held.size(), full.size());
  int invalid = 0;
  for (size_t i = 0; i < full.size(); ++i) {
    if (!held[i].valid) {
      ++invalid;
      EXPECT_THAT(
          held[i].note,
          ::testing::HasSubstr("command buffer ran dry in the step (samples " +
                               std::to_string(mid) + "-" + std::to_string(mid + 4) + " held)"));
      EXPECT_EQ(held[i].step, full[i].step);
    } else {
      EXPECT_EQ(held[i].mag, full[i].mag);
    }
  }
  EXPECT_EQ(invalid, 1);

  // Held in the settle before the window (the transient may reach into it): refused as well.
  auto run2 = simulate_tape(m, {"Wf"}, band(1, 10, 3), false, 1);
  int64_t settle = -1;
  int k = 0;
  for (const auto& e : run2.events)
    if (e.state == RunState::kSettle && k++ == 1) settle = e.sample + 3;
  ASSERT_GE(settle, 0);
  for (auto& b : run2.blocks) {
    b.channels.push_back(kUnderrunChannel);
    for (int i = 0; i < b.n_samples; ++i)
      b.samples.push_back(b.start_sample + i == settle ? 1.0 : 0.0);
  }
  auto held2 = analyse(run2, "Wf:P3");
  ASSERT_EQ(held2.size(), full.size());
  EXPECT_FALSE(held2[1].valid);
  EXPECT_THAT(held2[1].note, ::testing::HasSubstr("(samples " + std::to_string(settle) + "-" +
                                                  std::to_string(settle) + " held)"));
  EXPECT_TRUE(held2[0].valid);
  EXPECT_TRUE(held2[2].valid);
}

TEST(PairAnalyzer, ArrivalOrderAndDuplicatesDoNotChangeTheNumbers) {
  Model m = load_model(source_path("models/j85_95.json"));
  auto run = simulate_tape(m, {"Wf"}, band(1, 10, 3), true, 7);
  auto a = analyse(run, "Wf:N");
  std::vector<size_t> order(run.blocks.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  for (size_t i = 0; i + 3 < order.size(); i += 4) std::swap(order[i], order[i + 3]);  // reordered
  order.insert(order.begin() + 50, 10);  // and a duplicate
  auto b = analyse(run, "Wf:N", order);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].mag, b[i].mag);
    EXPECT_EQ(a[i].phase_deg, b[i].phase_deg);
    EXPECT_EQ(a[i].sigma, b[i].sigma);
  }
}

TEST(PairAnalyzer, HarmonicsRevealANonlinearity) {
  // Backlash in the actuator: odd harmonics appear in the position channel, none without it.
  Tf unit;
  Model m = fralab::testing::siso_model(unit, &unit);
  auto clean = analyse(simulate_tape(m, {"u"}, band(1, 2, 1), false, 1), "u_u:u");
  m.inputs[0].nonlinearity.push_back({NonlinearityKind::kHysteresis, 0.01});
  auto hyst = analyse(simulate_tape(m, {"u"}, band(1, 2, 1), false, 1), "u_u:u");
  EXPECT_LT(clean[0].h3_rel, 1e-9);
  EXPECT_GT(hyst[0].h3_rel, 0.05);
}

TEST(PairAnalyzer, MissingChannelIsAnErrorNamingIt) {
  PairAnalyzer a("Wf:P9");
  Block b;
  b.channels = {"Wf", "P3"};
  b.n_samples = 1;
  b.samples = {1, 2};
  try {
    a.on_block(b);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("no channel P9"));
  }
  EXPECT_THROW(PairAnalyzer("WfP3"), InputError);
}

// The continuous sweep, analysed against the recorded reference phase: on a smooth plant (a lag
// and a delay) the slow sweep's bias is small; near sharp resonances it is not
// (docs/method/analyser.md).
TEST(PairAnalyzer, SweepMeasuresASmoothPlant) {
  Tf t;
  t.gain = 2.0;
  t.poles = {Root::Real(-5.0)};
  t.delay_s = 0.004;
  Model m = fralab::testing::siso_model(t);
  SteppedSineOptions o = band(0.2, 20, 10);
  o.min_cycles = 40;
  auto run = simulate_tape(m, {"u"}, o, false, 1, 100, 2.0, "sweep");
  auto pts = analyse(run, "u:y");
  ASSERT_EQ(pts.size(), 21u);
  for (const auto& p : pts) {
    ASSERT_TRUE(p.valid) << p.note;
    Complex want = t.at(p.w);
    EXPECT_NEAR(std::abs(pt(p)) / std::abs(want), 1.0, 0.01) << p.w;
    EXPECT_NEAR(std::arg(pt(p) / want) * 180 / std::numbers::pi, 0.0, 0.5) << p.w;
  }
}

// Zippered multisines: both inputs of a 2x2 plant at once on disjoint lines; every input-to-output
// pair measured at its input's lines to 1e-4 / 0.01 degree of the plant's exact sampled response,
// and no distortion on the non-excited lines of a linear plant; a backlash shows there.
// A one-input multisine of two periods: a line's own spread over the periods is one complex
// degree of freedom, so its sigma alone is an exponential variable (|err| / sigma beyond 2 for 20 %
// of the points, beyond 3 for 10 %: a weak path's chi2 out of all proportion). Pooled with the
// nearest non-excited line each side (the same noise, three times the degrees of freedom), the
// fractions are 8 % and 1.6 % (|err|^2 / sigma^2 ~ F(2, 6)); checked over 40 seeds and every line.
TEST(PairAnalyzer, AOneInputMultisinesSigmaPoolsTheLinesNextToIt) {
  Tf t;
  t.gain = 2.0;
  t.poles = {Root::Real(-5.0)};
  const Model m = fralab::testing::siso_model(t, nullptr, nullptr, 0.02);
  SteppedSineOptions o = band(0.2, 20, 5);
  o.min_cycles = 2;
  int n = 0, beyond2 = 0, beyond3 = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    auto run = simulate_tape(m, {"u"}, o, true, seed, 100, 2.0, "multisine");
    for (const auto& p : analyse(run, "u:y")) {
      ASSERT_TRUE(p.valid) << p.note;
      EXPECT_EQ(p.n_cycles, 2);
      const double err = std::abs(pt(p) - sampled(m, "u", "y", p.w));
      ++n;
      beyond2 += err > 2 * p.sigma;
      beyond3 += err > 3 * p.sigma;
    }
  }
  ASSERT_GT(n, 300);
  EXPECT_LT(double(beyond2) / n, 0.13) << beyond2 << " of " << n;
  EXPECT_LT(double(beyond3) / n, 0.04) << beyond3 << " of " << n;
}

TEST(PairAnalyzer, ZipperedMultisinesMeasureTheWholeMatrixInOneRun) {
  Model m = two_by_two();
  SteppedSineOptions o = band(0.1, 20, 6);
  o.slowest_time_constant_s = 1.0;
  auto run = simulate_tape(m, {"a", "b"}, o, false, 1, 100, 2.0, "multisine:zippered");
  std::set<double> wa, wb;
  for (const std::string pair : {"a:y", "a:z", "b:y", "b:z"}) {
    auto [e1, e2] = split_pair(pair);
    auto pts = analyse(run, pair);
    ASSERT_GE(pts.size(), 7u) << pair;  // 15 lines over 0.1-20 Hz, dealt to two inputs
    for (const auto& p : pts) {
      ASSERT_TRUE(p.valid) << p.note;
      EXPECT_EQ(p.input, e1);
      Complex want = sampled(m, e1, e2, p.w) / sampled(m, e1, e1, p.w);
      EXPECT_NEAR(std::abs(pt(p)) / std::abs(want), 1.0, 1e-4) << pair << " " << p.w;
      EXPECT_NEAR(std::arg(pt(p) / want) * 180 / std::numbers::pi, 0.0, 0.01) << pair << " " << p.w;
      // Linear: only the settle's decaying remainder reaches the other lines (backlash: > 1e-3).
      EXPECT_LT(p.nl_rel, 1e-4) << pair << " " << p.w;
      (e1 == "a" ? wa : wb).insert(p.w);
    }
  }
  for (double w : wa) EXPECT_EQ(wb.count(w), 0u);  // orthogonal: no line is shared
  m.inputs[1].nonlinearity.push_back({NonlinearityKind::kHysteresis, 0.004});
  auto nl = simulate_tape(m, {"a", "b"}, o, false, 1, 100, 2.0, "multisine:zippered");
  double worst = 0;
  for (const auto& p : analyse(nl, "b:z")) worst = std::max(worst, p.nl_rel);
  EXPECT_GT(worst, 1e-3);
}

// Orthogonal multisines: both inputs of the 2x2 plant on every line, two experiments
// (DFT phase matrix). Noise off: every pair at every line within 1e-4 / 0.01 degree of the exact
// response, commands (u_a:y) as positions (a:y). b's recorded position sees 0.3 y (a
// measurement coupling, like the J85's fuel flow and P3), so it moves with a's reference too: the
// pair b:z must still be what a stepped sine of b alone measures, z / (b + 0.3 y).
TEST(PairAnalyzer, OrthogonalMultisinesMeasureEveryPairOnEveryLine) {
  Model m = two_by_two();
  m.inputs[1].measurement_coupling.push_back({"y", 0.3});
  SteppedSineOptions o = band(0.1, 20, 6);
  o.min_cycles = 2;               // periods per experiment
  o.slowest_time_constant_s = 3;  // a settle of 15 s: y's transient at each change of experiment
                                  // (5 of y's time constants leave 7e-3 of it) below 1e-4
  auto run = simulate_tape(m, {"a", "b"}, o, false, 1, 100, 2.0, "multisine");
  auto channel = [&](const std::string& in, const std::string& ch, double w) {  // per command
    if (ch.rfind("u_", 0) == 0) return Complex(1.0);
    return sampled(m, in, ch, w) + (ch == "b" ? 0.3 * sampled(m, in, "y", w) : Complex(0.0));
  };
  auto want = [&](const std::string& in, const std::string& e1, const std::string& e2, double w) {
    return channel(in, e2, w) / channel(in, e1, w);
  };
  for (const std::string pair : {"a:y", "a:z", "b:y", "b:z", "u_a:y", "u_b:z", "u_b:b"}) {
    auto [e1, e2] = split_pair(pair);
    const std::string in = e1.rfind("u_", 0) == 0 ? e1.substr(2) : e1;
    auto pts = analyse(run, pair);
    ASSERT_GE(pts.size(), 14u) << pair;  // 0.1-20 Hz at >= 6 lines per decade, each input
    for (const auto& p : pts) {
      ASSERT_TRUE(p.valid) << p.note;
      EXPECT_EQ(p.input, in);
      const Complex w = want(in, e1, e2, p.w);
      EXPECT_NEAR(std::abs(pt(p)) / std::abs(w), 1.0, 1e-4) << pair << " " << p.w;
      EXPECT_NEAR(std::arg(pt(p) / w) * 180 / std::numbers::pi, 0.0, 0.01) << pair << " " << p.w;
      // Linear: only the settle's decaying remainder reaches the unexcited lines.
      EXPECT_LT(p.nl_rel, 3e-4) << pair << " " << p.w;
    }
  }
  // A lost block invalidates its experiment's realisation and says so; nothing else is lost.
  const int64_t seq = window_middle(run, 1) / 100;
  auto lossy = analyse(run, "a:y", {}, {seq});
  ASSERT_FALSE(lossy.empty());
  for (const auto& p : lossy) {
    EXPECT_FALSE(p.valid);
    EXPECT_THAT(p.note, ::testing::HasSubstr("experiment 2: incomplete window"));
    EXPECT_THAT(p.note, ::testing::HasSubstr("seq " + std::to_string(seq) + " missing"));
  }
}

namespace {

// How often the error of an orthogonal multisine's points is within 1 and 2 of their sigmas, over
// 20 seeds and every point of `pairs`, against truth(E1, E2, w).
struct Coverage {
  int n = 0, in1 = 0, in2 = 0;
};
Coverage multisine_coverage(
    const Model& m, const SteppedSineOptions& o, const std::vector<std::string>& pairs,
    const std::function<Complex(const std::string&, const std::string&, double)>& truth) {
  Coverage c;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    auto run = simulate_tape(m, {"a", "b"}, o, true, seed, 100, 2.0, "multisine");
    for (const std::string& pair : pairs) {
      auto [e1, e2] = split_pair(pair);
      for (const auto& p : analyse(run, pair)) {
        EXPECT_TRUE(p.valid) << p.note;
        const double err = std::abs(pt(p) - truth(e1, e2, p.w));
        ++c.n;
        c.in1 += err < p.sigma;
        c.in2 += err < 2 * p.sigma;
      }
    }
  }
  return c;
}

}  // namespace

// With noise: the propagated sigma covers the error as a complex Gaussian's should (1 sigma:
// 1 - 1/e = 0.632; 2 sigma: 0.982), over 20 seeds and every line of both inputs' pairs.
TEST(PairAnalyzer, OrthogonalMultisineSigmaCoversTheError) {
  Model m = two_by_two();
  for (auto& out : m.outputs) out.noise_rms = 0.02;
  SteppedSineOptions o = band(0.2, 20, 5);
  o.min_cycles = 8;
  const Coverage c = multisine_coverage(m, o, {"u_a:y", "u_b:z", "u_a:z"},
                                        [&](const std::string& e1, const std::string& e2,
                                            double w) { return sampled(m, e1.substr(2), e2, w); });
  ASSERT_GT(c.n, 600);
  EXPECT_NEAR(double(c.in1) / c.n, 0.632, 0.06);
  EXPECT_GT(double(c.in2) / c.n, 0.93);
}

// A backlash on b (width 0.01 at a 0.02 peak: the position distorts, median nl > 0.05) is not a
// linear function of the references: solved with the commands alone its distortion leaks into a's
// estimates. Pairs X:O are solved with b's measured position instead: noise off, a:y, a:z, b:y and
// b:z stay within 1e-4 / 0.01 degree of the plant's exact sampled linear paths (the paths after the
// position are linear: a's as in the tests above, b's driven from its held position samples, the
// first-order-hold equivalent of the path alone), while the commands' pair u_b:b shows the
// distortion.
TEST(PairAnalyzer, OrthogonalMultisineSolvesADistortingInputByItsPosition) {
  Model m = two_by_two();
  m.inputs[1].nonlinearity.push_back({NonlinearityKind::kHysteresis, 0.01});
  SteppedSineOptions o = band(0.1, 20, 6);
  o.min_cycles = 2;
  o.slowest_time_constant_s = 3;  // a settle of 15 s: b's small position leaves y's transient
                                  // at each change of experiment relatively larger
  auto run = simulate_tape(m, {"a", "b"}, o, false, 1, 100, 2.0, "multisine");
  for (const std::string pair : {"a:y", "a:z", "b:y", "b:z"}) {
    auto [e1, e2] = split_pair(pair);
    const auto pts = analyse(run, pair);
    ASSERT_GE(pts.size(), 14u) << pair;
    for (const auto& p : pts) {
      ASSERT_TRUE(p.valid) << p.note;
      const Complex w = e1 == "a" ? sampled(m, "a", e2, p.w) / sampled(m, "a", "a", p.w)
                                  : foh_sampled_response(m.path(e2, "b")->tf, p.w, 1000.0);
      EXPECT_NEAR(std::abs(pt(p)) / std::abs(w), 1.0, 1e-4) << pair << " " << p.w;
      EXPECT_NEAR(std::arg(pt(p) / w) * 180 / std::numbers::pi, 0.0, 0.01) << pair << " " << p.w;
    }
  }
  double worst = 0;
  for (const auto& p : analyse(run, "u_b:b")) worst = std::max(worst, p.nl_rel);
  EXPECT_GT(worst, 0.05);
}

// A distorting input solved by its measured position brings that position's sensor noise into
// every input's estimate (neither channel of a's pairs carries it): with b's position noisy (5 %
// of its amplitude) and b driving z strongly, a's pairs a:y and a:z still have a sigma that covers
// their error as a complex Gaussian's should (1 sigma: 0.632, 2 sigma: 0.982) over 20 seeds
// (sigma from the pair's channels alone: 0.39 and 0.71).
TEST(PairAnalyzer, OrthogonalMultisineSigmaCoversThePositionNoiseOfADistortingInput) {
  Model m = two_by_two();
  m.inputs[1].nonlinearity.push_back({NonlinearityKind::kHysteresis, 0.01});
  m.inputs[1].noise_rms = 0.001;
  for (auto& out : m.outputs) out.noise_rms = 0.001;
  SteppedSineOptions o = band(0.2, 20, 5);
  o.min_cycles = 4;
  const Coverage c = multisine_coverage(m, o, {"a:y", "a:z"},
                                        [&](const std::string&, const std::string& e2, double w) {
                                          return sampled(m, "a", e2, w) / sampled(m, "a", "a", w);
                                        });
  ASSERT_GT(c.n, 300);
  EXPECT_NEAR(double(c.in1) / c.n, 0.632, 0.07) << c.in1 << " of " << c.n;
  EXPECT_GT(double(c.in2) / c.n, 0.93) << c.in2 << " of " << c.n;
}

// A corrupt tape: experiment 2's status states other lines (or an input the run does not have).
// The realisation's points are invalid and say why; nothing is read out of range.
TEST(PairAnalyzer, OrthogonalMultisineRefusesExperimentsThatDisagree) {
  Model m = two_by_two();
  SteppedSineOptions o = band(0.1, 20, 6);
  o.min_cycles = 2;
  auto run = simulate_tape(m, {"a", "b"}, o, false, 1, 100, 2.0, "multisine");
  int seen = 0;
  for (auto& e : run.events)
    if (e.state == RunState::kIntegrate && seen++ == 1) {
      e.lines.pop_back();
      e.line_input.pop_back();
    }
  auto pts = analyse(run, "a:y");
  ASSERT_FALSE(pts.empty());
  for (const auto& p : pts) {
    EXPECT_FALSE(p.valid);
    EXPECT_THAT(p.note, ::testing::HasSubstr("experiment 2: its status states another design"));
  }
  for (int bad : {7, -1}) {  // no such input (a -1 must not index before the list)
    run = simulate_tape(m, {"a", "b"}, o, false, 1, 100, 2.0, "multisine");
    for (auto& e : run.events)
      if (e.state == RunState::kIntegrate) e.line_input.back() = bad;
    pts = analyse(run, "a:y");
    ASSERT_EQ(pts.size(), 2u);  // one per integrate status
    for (const auto& p : pts) {
      EXPECT_FALSE(p.valid);
      EXPECT_THAT(p.note, ::testing::HasSubstr("a line of no listed input"));
    }
  }
}

// The best linear approximation over realisations (analyze/bla.h), on a known answer. A static
// y = a + c a^3 + 0.5 b (a, b the commands) under R = 8 random-phase realisations of the orthogonal
// design: for a multisine of N lines of equal amplitude A and variance s^2 = N A^2 / 2 with
// independent uniform phases, the part of a^3 coherent with line k is (3 s^2 - 3 A^2 / 4) a_k, so
// the BLA of u_a:y is 1 + c s^2 (3 - 1.5 / N); what is left of a^3 at line k (products of three
// other lines) changes with the phases: the stochastic nonlinear distortion. Noise-free, the
// periods repeat exactly: sigma_noise ~ 0 and the whole spread is sigma_nl; the BLA covers the
// answer as its sigma claims. The distortion depends on a alone, the same in both experiments of
// a realisation: u_b:y is 0.5 with no nonlinear part. With c = 0 and noise on y instead, the
// spread is noise: sigma_nl is below sigma_noise on most lines.
TEST(PairAnalyzer, RealisationsGiveTheBestLinearApproximationWithTheNonlinearPartSeparated) {
  const Model m = two_by_two();
  // rms 0.0707 of a full scale of 1: peaks well inside it
  AcquireOptions o = fralab::testing::random_phase_multisine("0.1:20", 6, 10, 8);
  o.slowest_time_constant_s = 0.1;
  o.block = block_samples(m, o);
  const auto camp = make_campaign(m, o, "test");
  auto tape = [&](double c, double noise) {
    std::mt19937_64 g(5);
    std::normal_distribution<double> n(0.0, noise);
    std::vector<Block> out;
    for (int64_t seq = 0; seq < command_block_count(*camp, o.block); ++seq) {
      Block b = command_block(*camp, seq, o.block, o.sample_rate_hz, "test");
      const size_t L = size_t(b.n_samples);
      std::vector<double> a(b.samples.begin(), b.samples.begin() + L),
          bb(b.samples.begin() + L, b.samples.begin() + 2 * L), y(L);
      for (size_t k = 0; k < L; ++k)
        y[k] = a[k] + c * a[k] * a[k] * a[k] + 0.5 * bb[k] + (noise > 0 ? n(g) : 0.0);
      b.channels = {"u_a", "u_b", "a", "b", "y"};
      b.samples.clear();
      for (const auto* v : {&a, &bb, &a, &bb, &y})
        b.samples.insert(b.samples.end(), v->begin(), v->end());
      out.push_back(std::move(b));
    }
    return out;
  };
  auto analyse_blocks = [&](const std::vector<Block>& blocks, const std::string& pair) {
    PairAnalyzer an(pair);
    for (const auto& e : camp->events()) an.on_status(e);
    for (const auto& b : blocks) an.on_block(b);
    an.flush();
    return an.frd().points;
  };
  // s^2 and N from the commands: a's variance over the first measured period.
  const StatusEvent* first = nullptr;
  for (const auto& e : camp->events())
    if (e.state == RunState::kIntegrate && !first) first = &e;
  ASSERT_NE(first, nullptr);
  int N = 0;
  for (int i : first->line_input) N += i == 0;
  const double c = 20;
  const auto blocks = tape(c, 0);
  double s2 = 0;
  for (int64_t k = first->sample; k < first->sample + first->period_samples; ++k) {
    const Block& b = blocks[size_t(k / o.block)];
    const double a = b.samples[size_t(k % o.block)];
    s2 += a * a / first->period_samples;
  }
  const double bla = 1 + c * s2 * (3 - 1.5 / N);
  ASSERT_GT(c * s2, 0.05);  // a distortion well beyond rounding
  const auto pts = analyse_blocks(blocks, "u_a:y");
  ASSERT_EQ(pts.size(), size_t(N));
  int within = 0;
  for (const auto& p : pts) {
    ASSERT_TRUE(p.valid) << p.note;
    EXPECT_EQ(p.realisations, 8);
    EXPECT_GT(p.sigma_nl, 1e6 * p.sigma_noise) << p.w;
    EXPECT_NEAR(p.sigma * p.sigma, p.sigma_noise * p.sigma_noise + p.sigma_nl * p.sigma_nl,
                1e-12 * p.sigma * p.sigma);
    EXPECT_LT(std::abs(pt(p) - bla), 0.1 * bla) << p.w;  // and the single realisations' a^3 ...
    within += std::abs(pt(p) - bla) < 3 * p.sigma;
  }
  EXPECT_GE(double(within) / N, 0.9) << "BLA " << bla << " over " << N << " lines";
  for (const auto& p : analyse_blocks(blocks, "u_b:y")) {
    ASSERT_TRUE(p.valid) << p.note;
    EXPECT_NEAR(std::abs(pt(p) - 0.5), 0.0, 1e-9) << p.w;
    EXPECT_LT(p.sigma_nl, 1e-9) << p.w;
  }
  // Linear with noise: the spread is the noise's.
  int below = 0;
  const auto lin = analyse_blocks(tape(0, 1e-3), "u_a:y");
  for (const auto& p : lin) {
    ASSERT_TRUE(p.valid) << p.note;
    below += p.sigma_nl < p.sigma_noise;
    EXPECT_LT(std::abs(pt(p) - 1.0), 4 * p.sigma) << p.w;
  }
  EXPECT_GT(double(below) / double(lin.size()), 0.75);
}

// What the diagnosis models a multisine-measured backlash with (plant/nonlinearity.h,
// multisine_bla) against what the analyser measures through the plant: b's actuator (a 40 rad/s
// lag, then a backlash of width 0.1 at a command rms of 0.07) under 6 random-phase realisations
// of the orthogonal 2-input design. Per line, the model is act(w) BLA(lines, line_amplitude
// |act|): the analyser's line_amplitude is the command's (the rms spread over N equal lines,
// amplitude / sqrt N); model and measurement agree within their combined sigma (the measured
// BLA's total and the model's own realisations' spread) on >= 90 % of the lines, while the
// describing function at the multisine's peak does not.
TEST(PairAnalyzer, TheMeasuredBlaOfABacklashIsTheModelsMultisineBla) {
  Model m = two_by_two();
  const NonlinearitySpec backlash{NonlinearityKind::kHysteresis, 0.1};
  m.inputs[1].nonlinearity.push_back(backlash);
  AcquireOptions o = fralab::testing::random_phase_multisine("0.1:20", 6, 10, 6);
  o.slowest_time_constant_s = 0.2;
  const auto run = fralab::testing::simulate_campaign(m, o, false, 1);
  const auto pts = fralab::testing::analyse_run(run, {"u_b:b"})[0].points;
  const StatusEvent& st = run.events[1];
  const double df = st.sample_rate_hz / st.period_samples;
  std::vector<int> lines;
  std::vector<double> amp;
  std::vector<Complex> act;
  for (const auto& p : pts) {
    ASSERT_TRUE(p.valid) << p.note;
    EXPECT_EQ(p.realisations, 6);
    EXPECT_NEAR(p.line_amplitude, 0.1 / std::sqrt(double(pts.size())), 1e-9);
    lines.push_back(int(std::lround(p.w / (2 * std::numbers::pi * df))));
    act.push_back(foh_sampled_response(*m.inputs[1].actuator, p.w, 1000.0));
    amp.push_back(p.line_amplitude * std::abs(act.back()));
  }
  const MultisineBla model = multisine_bla(backlash, lines, amp, 32);
  int agree = 0, df_agrees = 0;
  for (size_t j = 0; j < pts.size(); ++j) {
    const Complex want = act[j] * model.g[j];
    const double s =
        std::sqrt(pts[j].sigma * pts[j].sigma + std::norm(act[j]) * model.var_nl[j] / 32);
    agree += std::abs(pt(pts[j]) - want) < 3 * s;
    const Complex by_df =
        act[j] * backlash_describing_function(st.amplitudes[1] * std::abs(act[j]), backlash.width);
    df_agrees += std::abs(pt(pts[j]) - by_df) < 3 * s;
  }
  EXPECT_GE(double(agree) / pts.size(), 0.9) << agree << " of " << pts.size();
  EXPECT_LE(double(df_agrees) / pts.size(), 0.5) << df_agrees << " of " << pts.size();
}
