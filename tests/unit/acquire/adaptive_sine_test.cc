// acquire/adaptive_sine.h: the adaptive stepped sine's rule, its campaign (extended while
// running, nothing before a decision moving) and its decisions on a simulated lab run
// (tests/util simulate_campaign: the same library code as fralab-acquire).
#include "fralab/acquire/adaptive_sine.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "fralab/acquire/acquisition.h"
#include "fralab/plant/lti.h"
#include "test_util.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;

AdaptiveSineOptions target(double t, int pilot = 4) {
  AdaptiveSineOptions o;
  o.sigma_target = t;
  o.pilot_cycles = pilot;
  return o;
}

int more(int n, std::vector<double> rel, int limit, AdaptiveSineOptions o = target(0.01)) {
  return decide_step(n, rel, limit, o).more;
}

TEST(AdaptiveSine, TheExtensionMeetsTheTargetWithinTheLimitInWholePilots) {
  // 4 cycles at twice the target: 16 cycles in all, 12 more.
  EXPECT_EQ(more(4, {0.02, 0.005}, 64), 12);
  // 4 cycles at 1.1 x: 4.84 in all, one more pilot (4).
  EXPECT_EQ(more(4, {0.011}, 64), 4);
  // The limit caps it, rounded down to whole pilots: room (10 - 4) / 4 = 1 pilot.
  EXPECT_EQ(more(4, {0.015}, 10), 4);
  EXPECT_EQ(more(8, {0.011}, 10), 0);
  // On target, or no usable point: the step ends.
  const StepDecision met = decide_step(4, {0.01, 0.002}, 64, target(0.01));
  EXPECT_EQ(met.more, 0);
  EXPECT_EQ(met.state, "met");
  EXPECT_EQ(met.worst, 0.01);
  EXPECT_EQ(decide_step(4, {}, 64, target(0.01)).state, "unusable");
  // A pilot of 6: 6 (0.03 / 0.01)^2 = 54 in all, 48 more = 8 pilots.
  EXPECT_EQ(more(6, {0.03}, 1000, target(0.01, 6)), 48);
}

TEST(AdaptiveSine, APairWithNoDetectableResponseDoesNotHoldTheStep) {
  // At the limit of 64 cycles a pair at 2.0 after 4 reaches 2.0 / 4 = 0.5 > 1/3: |G| under 3 sigma
  // even there, it does not count; the other (0.02) holds the step to 16 cycles.
  StepDecision d = decide_step(4, {2.0, 0.02}, 64, target(0.01));
  EXPECT_EQ(d.more, 12);
  EXPECT_EQ(d.undetectable, 1);
  EXPECT_EQ(d.worst, 0.02);
  EXPECT_EQ(d.worst_all, 2.0);
  // A noisy pair that becomes detectable at the limit (1.2 / 4 = 0.3) holds the step to it, as
  // the fixed plan would integrate it.
  EXPECT_EQ(more(4, {1.2, 0.02}, 64), 60);
  // No pair with a response: the step ends at once.
  d = decide_step(4, {2.0, 5.0}, 64, target(0.01));
  EXPECT_EQ(d.more, 0);
  EXPECT_EQ(d.state, "undetectable");
  EXPECT_EQ(d.undetectable, 2);
  // Short with less than a pilot left below the limit: "limit".
  for (double s : {0.0101, 0.05}) {
    d = decide_step(62, {s}, 64, target(0.01));
    EXPECT_EQ(d.more, 0);
    EXPECT_EQ(d.state, "limit");
  }
}

TEST(AdaptiveSine, DecisionsReadBackAsWritten) {
  const std::vector<std::pair<int, int>> d = {{0, 4}, {3, 12}, {3, 8}};
  EXPECT_EQ(format_decisions(d), "0*4,3*12,3*8");
  EXPECT_EQ(parse_decisions("0*4,3*12,3*8"), d);
  EXPECT_TRUE(parse_decisions("").empty());
  try {
    parse_decisions("0*4,3x12");
    ADD_FAILURE() << "a bad token was taken";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("\"3x12\""));
  }
  EXPECT_THROW(target(0.01, 1).validate(), InputError);
  EXPECT_THROW(target(-1).validate(), InputError);
  EXPECT_THROW(target(NAN).validate(), InputError);
}

Model noisy_plant(double noise_rms);

TEST(AdaptiveSine, OptionsThatCannotWorkAreRefusedByName) {
  auto refused = [](AcquireOptions o, const std::string& what) {
    try {
      o.validate();
      ADD_FAILURE() << "taken: " << what;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  AcquireOptions o;
  o.adaptive.sigma_target = 0.01;
  EXPECT_NO_THROW(o.validate());
  AcquireOptions bad = o;
  bad.excitation = Excitation::kMultisine;
  refused(bad, "--excitation stepped");
  bad = o;
  bad.free_running = true;
  bad.speed = 1;
  refused(bad, "--free-running");
  bad = o;
  bad.adaptive.pilot_cycles = 1;
  refused(bad, "--pilot-cycles");
  bad = o;
  bad.adaptive.sigma_target = NAN;
  refused(bad, "--sigma-target");
  bad = o;
  bad.adaptive_decided = "3*x";
  refused(bad, "\"3*x\"");
  bad = AcquireOptions();
  bad.adaptive_decided = "3*4";
  refused(bad, "without --sigma-target");
  // A decision the campaign cannot take (not whole pilots, no such step) is refused by name.
  o.adaptive_decided = "2*6";
  EXPECT_THROW(make_campaign(noisy_plant(0), o, "r"), InputError);
  o.adaptive_decided = "999*4";
  EXPECT_THROW(make_campaign(noisy_plant(0), o, "r"), InputError);
}

std::vector<CampaignInput> one_input() {
  CampaignInput in;
  in.name = "u";
  in.dc = 0.5;
  in.amplitude = 0.02;
  return {in};
}

SteppedSineOptions fixed_plan() {
  SteppedSineOptions so;
  so.f_lo_hz = 0.5;
  so.f_hi_hz = 20;
  so.points_per_decade = 3;
  so.min_integrate_s = 2.0;
  so.slowest_time_constant_s = 0.3;
  return so;
}

std::vector<double> commands(const Campaign& c, int64_t n) {
  std::vector<std::vector<double>> cmd;
  std::vector<double> ph, fr;
  c.fill(0, int(n), cmd, ph, fr);
  return cmd[0];
}

TEST(AdaptiveSine, AnExtensionMovesNothingBeforeItsDecision) {
  const int block = 100;
  AdaptiveSineCampaign c(one_input(), {0}, fixed_plan(), 4, block, "r");
  ASSERT_EQ(c.n_steps(), 6);
  for (int g = 0; g < c.n_steps(); ++g) {
    EXPECT_EQ(c.step_start(g) % block, 0) << g;  // every step starts on a block boundary
    EXPECT_EQ(c.cycles(g), 4);
    EXPECT_GE(c.limit(g), 8);  // the fixed plan's cycles: max(8, ceil(2 f))
  }
  const auto fixed = plan_stepped_sine(fixed_plan());
  for (int g = 0; g < c.n_steps(); ++g) EXPECT_EQ(c.limit(g), fixed[size_t(g)].n_cycles);
  EXPECT_GE(c.limit(5), 40);  // 20 Hz for 2 s
  const int g = 2;
  const int64_t E = c.window_end(g);
  const std::vector<double> before = commands(c, c.total_samples());
  const int64_t total_before = c.total_samples();
  c.extend(g, 8);
  const std::vector<double> after = commands(c, c.total_samples());
  // Every command up to the end of the block holding E - 1 is the same (the sine goes on).
  const int64_t kept = ((E - 1) / block + 1) * block;
  for (int64_t n = 0; n < kept; ++n) ASSERT_EQ(before[size_t(n)], after[size_t(n)]) << n;
  // The extension: 8 cycles at exactly the pilot's frequency, right at E, the same step.
  const SineStep& s = c.step(g);
  const int64_t L = s.integrate_samples * 2;
  EXPECT_EQ(c.window_end(g), E + L);
  EXPECT_EQ(c.cycles(g), 12);
  int windows = 0;
  for (const StatusEvent& e : c.events()) {
    if (e.state != RunState::kIntegrate || e.step != g) continue;
    EXPECT_NEAR(e.n_cycles * s.integrate_samples, double(e.n_samples) * s.n_cycles, 1e-9);
    EXPECT_DOUBLE_EQ(e.frequency_hz, s.f_hz);
    // Its reference phase is the command's: dc + A sin(phase) at its first sample.
    EXPECT_NEAR(after[size_t(e.sample)], 0.5 + 0.02 * std::sin(e.ref_phase_rad), 1e-12);
    ++windows;
  }
  EXPECT_EQ(windows, 2);
  // Later steps moved by whole blocks, and the sequence numbers stay 0, 1, ...
  EXPECT_EQ((c.total_samples() - total_before) % block, 0);
  for (size_t i = 0; i < c.events().size(); ++i) EXPECT_EQ(c.events()[i].seq, int64_t(i));
  // The decisions rebuild the same campaign (what a resumed acquisition is given).
  AdaptiveSineCampaign again(one_input(), {0}, fixed_plan(), 4, block, "r", c.decisions());
  EXPECT_EQ(commands(again, again.total_samples()), after);
  EXPECT_THROW(c.extend(g, 6), InputError);  // not whole pilots
  EXPECT_THROW(c.extend(9, 4), InputError);  // no such step
}

// A plant whose noise makes some steps quiet and others noisy: y = 2 / (s/5 + 1) u, white noise on
// y, behind a 40 rad/s actuator.
Model noisy_plant(double noise_rms) {
  Tf path, act;
  path.gain = 2.0;
  path.poles = {Root::Real(-5.0)};
  act.poles = {Root::Real(-40.0)};
  return fralab::testing::siso_model(path, &act, nullptr, noise_rms);
}

AcquireOptions adaptive_run(double sigma_target) {
  AcquireOptions o;
  o.band = "0.5:20";
  o.points_per_decade = 5;
  o.min_integrate_s = 4.0;
  o.slowest_time_constant_s = 0.3;
  o.amplitude_pct = 2.0;
  o.adaptive.sigma_target = sigma_target;
  o.block = 100;  // steps start on 0.1 s boundaries (the engine-time figures below count blocks)
  return o;
}

TEST(AdaptiveSine, EachStepStopsOnTargetOrAtItsLimitWithTheAnalysersNumbers) {
  const Model m = noisy_plant(0.002);
  const double t = 0.01;
  const auto run = fralab::testing::simulate_campaign(m, adaptive_run(t), true, 7);
  const auto curves = fralab::testing::analyse_run(run, {"u:y", "u_u:u"});
  ASSERT_EQ(run.adaptive.size(), 9u);  // 0.5-20 Hz at 5 a decade
  AcquireOptions fixed = adaptive_run(0);
  const auto fixed_camp = make_campaign(m, fixed, "f");
  const auto plan = plan_stepped_sine(stepped_sine_options(m, fixed));
  int met = 0, limit = 0, extended = 0;
  for (size_t g = 0; g < run.adaptive.size(); ++g) {
    const auto& r = run.adaptive[g];
    // The analysers' curve: one point per step, its windows merged; the decision's numbers are
    // exactly the analysers' (the same arithmetic on the same samples).
    double worst = -1;
    for (const Frd& f : curves) {
      ASSERT_EQ(f.points.size(), run.adaptive.size()) << f.pair;
      const FrdPoint& p = f.points[g];
      EXPECT_TRUE(p.valid) << p.note;
      EXPECT_EQ(p.n_cycles, r.cycles);
      worst = std::max(worst, p.sigma / p.mag);
    }
    EXPECT_EQ(worst, r.decision.worst_all) << g;
    if (r.decision.state == "met") {
      EXPECT_LE(r.decision.worst, t);
      EXPECT_EQ(r.decision.worst == worst, r.decision.undetectable == 0);
      ++met;
    } else {
      ASSERT_EQ(r.decision.state, "limit");
      EXPECT_GT(r.decision.worst, t);
      EXPECT_GT(r.cycles + 4, plan[g].n_cycles) << g;  // no whole pilot left under the limit
      ++limit;
    }
    EXPECT_LE(r.cycles, plan[g].n_cycles);
    extended += r.cycles > 4;
    std::printf("%d %.3f %d %s %.4f %.4f\n", r.step, r.f_hz, r.cycles, r.decision.state.c_str(),
                r.decision.worst, r.decision.worst_all);
  }
  // The run's record, computed from the curves alone (a resumed run's too), is the decisions'.
  std::vector<int> limits;
  for (const SineStep& s : plan) limits.push_back(s.n_cycles);
  const auto from_curves = adaptive_steps(curves, t, limits);
  ASSERT_EQ(from_curves.size(), run.adaptive.size());
  for (size_t g = 0; g < from_curves.size(); ++g) {
    EXPECT_EQ(from_curves[g].step, run.adaptive[g].step);
    EXPECT_EQ(from_curves[g].cycles, run.adaptive[g].cycles);
    EXPECT_EQ(from_curves[g].decision.worst, run.adaptive[g].decision.worst);
    EXPECT_EQ(from_curves[g].decision.worst_all, run.adaptive[g].decision.worst_all);
    EXPECT_EQ(from_curves[g].decision.state, run.adaptive[g].decision.state);
    EXPECT_NEAR(from_curves[g].f_hz, run.adaptive[g].f_hz, 1e-12 * run.adaptive[g].f_hz);
  }
  // The case covers all three outcomes: quiet steps done at the pilot, steps extended to meet the
  // target, steps at their limit.
  EXPECT_GE(met, 2);
  EXPECT_GE(limit, 2);
  EXPECT_GE(extended, 2);
  // Truth in, truth out: the merged points agree with the plant within 4 sigma.
  for (const FrdPoint& p : curves[0].points) {
    const auto truth = foh_sampled_response(m.paths[0].tf, p.w, 1000.0);
    EXPECT_LT(std::abs(p.value() - truth), 4 * p.sigma) << p.w;
  }
  // And it took less engine time than the fixed plan, whose limits it kept.
  EXPECT_LT(run.blocks.size() * 100, size_t(fixed_camp->total_samples()));
}

TEST(AdaptiveSine, TheSameTapeMakesTheSameDecisions) {
  const Model m = noisy_plant(0.002);
  const auto a = fralab::testing::simulate_campaign(m, adaptive_run(0.01), true, 7);
  const auto b = fralab::testing::simulate_campaign(m, adaptive_run(0.01), true, 7);
  ASSERT_EQ(a.adaptive.size(), b.adaptive.size());
  for (size_t g = 0; g < a.adaptive.size(); ++g)
    EXPECT_EQ(a.adaptive[g].cycles, b.adaptive[g].cycles);
  // Another noise seed decides differently somewhere (the decisions follow the data).
  const auto c = fralab::testing::simulate_campaign(m, adaptive_run(0.01), true, 8);
  bool differs = false;
  for (size_t g = 0; g < a.adaptive.size(); ++g)
    differs |= a.adaptive[g].cycles != c.adaptive[g].cycles;
  EXPECT_TRUE(differs);
}

// Stopping when the estimated sigma meets the target favours low estimates; the points must still
// be honest. Over 40 noise seeds of the 9-step run (360 points), the share of merged points within
// 3 sigma of the truth stays at least 0.97: a sigma estimated from the pilot's K = 4 blocks makes
// |error|^2 / sigma^2 an F(2, 6) variable, within 3 sigma with probability 1 - 4^-3 = 0.984, less
// two binomial standard deviations over 360 points (0.013); the fixed plan's K = 8 gives 0.997.
// And the adaptive runs take less engine time. Measured: fixed 0.989, adaptive (1 %) 0.989; 71 s
// and 51 s.
TEST(AdaptiveSine, StoppingOnTargetKeepsTheSigmasHonest) {
  const Model m = noisy_plant(0.002);
  auto measure = [&](double t, double* engine_s) {
    int n = 0, within = 0;
    for (uint64_t seed = 1; seed <= 40; ++seed) {
      const auto run = fralab::testing::simulate_campaign(m, adaptive_run(t), true, seed);
      *engine_s += double(run.blocks.size()) * 100 / 1000.0;
      const auto curves = fralab::testing::analyse_run(run, {"u:y"});
      for (const FrdPoint& p : curves[0].points) {
        const auto truth = foh_sampled_response(m.paths[0].tf, p.w, 1000.0);
        ++n;
        within += std::abs(p.value() - truth) < 3 * p.sigma;
      }
    }
    return double(within) / n;
  };
  double fixed_s = 0, adaptive_s = 0;
  const double fixed = measure(0, &fixed_s), adaptive = measure(0.01, &adaptive_s);
  EXPECT_GE(fixed, 0.97);
  EXPECT_GE(adaptive, 0.97);
  EXPECT_LT(adaptive_s, 0.85 * fixed_s);
}

}  // namespace
}  // namespace fralab
