#include "fralab/acquire/campaign.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include "fralab/acquire/model_info.h"
#include "test_util.h"

using namespace fralab;

TEST(SteppedSine, StepsHoldWholeCyclesInWholeSamples) {
  SteppedSineOptions o;
  o.slowest_time_constant_s = 0.7;
  auto steps = plan_stepped_sine(o);
  ASSERT_EQ(steps.size(), 35u);  // 0.04-100 Hz, 10 per decade, both ends
  EXPECT_NEAR(steps.front().f_hz, 0.04, 1e-3);
  EXPECT_NEAR(steps.back().f_hz, 100.0, 0.2);
  for (const auto& s : steps) {
    EXPECT_GE(s.n_cycles, 8);
    EXPECT_DOUBLE_EQ(s.f_hz, s.n_cycles * 1000.0 / double(s.integrate_samples));
    EXPECT_GE(s.settle_samples, std::llround(5 * 0.7 * 1000) - 1);
    EXPECT_GE(s.integrate_samples / 1000.0, 4.0 - 1e-3);
  }
  // The report counts 0.5 h of engine time per actuator; ours is of that order.
  EXPECT_LT(plan_duration_s(steps, 1000.0), 1800.0);
  EXPECT_GT(plan_duration_s(steps, 1000.0), 600.0);
}

TEST(SteppedSine, BadOptionsNameTheProblem) {
  SteppedSineOptions o;
  o.f_hi_hz = 300;
  try {
    plan_stepped_sine(o);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("above fs/4"));
  }
  EXPECT_THROW(parse_band("100:0.04x"), InputError);
  EXPECT_EQ(parse_band("0.04:100"), std::make_pair(0.04, 100.0));
}

TEST(SteppedSine, CommandIsContinuousAndMatchesTheStatusReference) {
  Model m = load_model(fralab::testing::source_path("models/j85_95.json"));
  SteppedSineOptions o;
  o.f_lo_hz = 1;
  o.f_hi_hz = 10;
  o.points_per_decade = 3;
  SteppedSineCampaign c(campaign_inputs(m, 2.0), select_inputs(m, "Wf,A8"), plan_stepped_sine(o),
                        1000, "r");
  std::vector<std::vector<double>> cmd;
  std::vector<double> ph, fr;
  c.fill(0, int(c.total_samples()), cmd, ph, fr);
  const double amp = 0.02 * 3000;
  // At every integrate status, the command equals dc + A sin(status phase + 2 pi f k / fs).
  int integrates = 0;
  for (const auto& e : c.events()) {
    if (e.state != RunState::kIntegrate) continue;
    ++integrates;
    int in = e.amplitudes[0] > 0 ? 0 : 1;
    for (int64_t k = 0; k < e.n_samples; k += 37) {
      double phase = e.ref_phase_rad + 2 * std::numbers::pi * e.frequency_hz * k / 1000.0;
      double a = in == 0 ? amp : 0.02 * 200;
      ASSERT_NEAR(cmd[in][e.sample + k], m.dc(m.inputs[in].name) + a * std::sin(phase), 1e-9);
    }
  }
  EXPECT_EQ(integrates, 8);  // 4 frequencies x 2 inputs
  // No jumps in the command while Wf is tested: successive samples differ by at most A 2 pi f / fs.
  size_t wf_end = 0;
  for (const auto& e : c.events()) {
    if (e.amplitudes.size() > 1 && e.amplitudes[1] > 0) {
      wf_end = size_t(e.sample);
      break;
    }
  }
  ASSERT_GT(wf_end, 0u);
  for (size_t k = 1; k < wf_end; ++k)
    ASSERT_LE(std::abs(cmd[0][k] - cmd[0][k - 1]), amp * 2 * std::numbers::pi * 10 / 1000 * 1.01);
  EXPECT_EQ(c.events().back().state, RunState::kDone);
  EXPECT_EQ(c.events().back().sample, c.total_samples());
}

TEST(Sweep, PhaseAndFrequencyAreContinuousAndWindowsTileTheSweep) {
  Model m = load_model(fralab::testing::source_path("models/j85_95.json"));
  SteppedSineOptions o;
  o.f_lo_hz = 0.5;
  o.f_hi_hz = 20;
  o.points_per_decade = 5;
  SweepCampaign c(campaign_inputs(m, 2.0), select_inputs(m, "Wf"), o, "r");
  std::vector<std::vector<double>> cmd;
  std::vector<double> ph, fr;
  c.fill(0, int(c.total_samples()), cmd, ph, fr);
  int integrates = 0;
  int64_t expect_start = -1;
  for (const auto& e : c.events()) {
    if (e.state != RunState::kIntegrate) continue;
    EXPECT_EQ(e.excitation, Excitation::kSweep);
    if (expect_start >= 0) {
      EXPECT_EQ(e.sample, expect_start);  // windows tile the sweep
    }
    expect_start = e.sample + e.n_samples;
    // The window holds its whole cycles (to within a sample's phase) and its centre frequency lies
    // inside it.
    const double cycles = (ph[e.sample + e.n_samples - 1] - ph[e.sample]) / (2 * std::numbers::pi);
    EXPECT_NEAR(cycles, e.n_cycles, 0.05) << e.step;
    EXPECT_LT(fr[e.sample], e.frequency_hz);
    EXPECT_GT(fr[e.sample + e.n_samples - 1], e.frequency_hz);
    ++integrates;
  }
  EXPECT_EQ(integrates, 9);
  const double amp = 0.02 * 3000;
  for (size_t k = 1; k < ph.size(); ++k) {
    // The phase advances by 2 pi f / fs each sample (continuous modulo 2 pi), the frequency has no
    // jumps, and neither has the command.
    const double d = std::remainder(ph[k] - ph[k - 1], 2 * std::numbers::pi);
    ASSERT_NEAR(d, 2 * std::numbers::pi * fr[k - 1] / 1000.0, 0.01 * d + 1e-9) << k;
    ASSERT_LE(std::abs(fr[k] - fr[k - 1]), 0.01 * fr[k - 1]) << k;
    ASSERT_LE(std::abs(cmd[0][k] - cmd[0][k - 1]),
              amp * 2 * std::numbers::pi * fr[k] / 1000.0 * 1.01)
        << k;
  }
}

TEST(Multisine, ZipperedIsPeriodicDisjointAndScaledToTheAmplitude) {
  Model m = load_model(fralab::testing::source_path("models/j85_95.json"));
  MultisineOptions o;
  o.design = MultisineOptions::Design::kZippered;
  o.level = "peak";
  o.f_lo_hz = 0.5;
  o.f_hi_hz = 50;
  o.points_per_decade = 8;
  o.odd_lines = true;
  o.slowest_time_constant_s = 0.5;
  auto ins = campaign_inputs(m, 2.0);
  MultisineCampaign c(ins, select_inputs(m, "Wf,A8"), o, "r");
  const int P = c.period_samples();
  EXPECT_EQ(P, 2000);
  const StatusEvent& in = c.events()[1];
  ASSERT_EQ(in.state, RunState::kIntegrate);
  EXPECT_EQ(in.excitation, Excitation::kMultisine);
  EXPECT_EQ(in.n_samples, int64_t(o.periods) * P);
  std::set<int> seen;
  for (size_t j = 0; j < in.lines.size(); ++j) {
    EXPECT_EQ(in.lines[j] % 2, 1);                    // odd lines only
    EXPECT_TRUE(seen.insert(in.lines[j]).second);     // each line once: inputs orthogonal
    EXPECT_EQ(in.line_input[j], j % 2 == 0 ? 0 : 1);  // dealt to Wf, A8 in turn
  }
  std::vector<std::vector<double>> cmd;
  std::vector<double> ph, fr;
  c.fill(0, int(c.total_samples()), cmd, ph, fr);
  for (int i : {0, 1}) {
    double peak = 0;
    for (int64_t n = 0; n + P < c.total_samples(); ++n) {
      ASSERT_DOUBLE_EQ(cmd[i][n + P], cmd[i][n]);  // exactly periodic
      peak = std::max(peak, std::abs(cmd[i][n] - ins[i].dc));
    }
    EXPECT_NEAR(peak, ins[i].amplitude, 1e-9 * ins[i].amplitude);
  }
  EXPECT_DOUBLE_EQ(cmd[2][123], ins[2].dc);  // BLD not excited: held at its operating point
}

// The orthogonal design puts every input on every line of a quasi-logarithmic grid with
// at least the requested lines per decade, in n_u experiments whose line phases differ by the DFT
// phase matrix exp(j 2 pi q e / n_u); each experiment's commands are periodic from its settle on
// and carry the sine test's power (rms = amplitude / sqrt 2), the peak the status states.
TEST(Multisine, OrthogonalExcitesEveryInputOnEveryLineOfADenseGrid) {
  Model m = load_model(fralab::testing::source_path("models/j85_95.json"));
  MultisineOptions o;
  o.f_lo_hz = 0.1;
  o.f_hi_hz = 50;
  o.points_per_decade = 10;
  o.periods = 2;
  o.phases = "random";
  o.slowest_time_constant_s = 0.5;
  auto ins = campaign_inputs(m, 2.0);
  const std::vector<int> ex = select_inputs(m, "Wf,BLD,IGV");
  MultisineCampaign c(ins, ex, o, "r");
  const int P = c.period_samples();
  ASSERT_EQ(P, 10000);
  // Grid: neighbours within r = 10^(1/10), so each decade of the band holds >= 10 lines.
  const std::vector<int> lines = multisine_lines(o, P);
  ASSERT_GE(lines.size(), 25u);
  EXPECT_EQ(lines.front(), 1);
  EXPECT_LE(lines.back() * 0.1, 50.0);
  for (size_t j = 1; j < lines.size(); ++j)
    EXPECT_LE(double(lines[j]) / lines[j - 1],
              std::max(std::pow(10.0, 0.1), 1.0 + 1.0 / lines[j - 1]) + 1e-12);
  // 1-10 Hz: >= 10 lines; 0.1-1 Hz holds only 9 harmonics (k = 1..9): >= 8 of them.
  for (double lo : {0.1, 1.0}) {
    int n = 0;
    for (int k : lines) n += k * 0.1 >= lo - 1e-9 && k * 0.1 < 10 * lo - 1e-9;
    EXPECT_GE(n, lo < 1 ? 8 : 10) << lo;
  }
  // Events: per experiment a settle and an integrate of `periods` periods; step = experiment.
  std::vector<StatusEvent> integ;
  for (const auto& e : c.events())
    if (e.state == RunState::kIntegrate) integ.push_back(e);
  ASSERT_EQ(integ.size(), 3u);
  for (int e = 0; e < 3; ++e) {
    EXPECT_EQ(integ[e].step, e);
    EXPECT_EQ(integ[e].n_steps, 3);
    EXPECT_EQ(integ[e].n_samples, 2 * P);
    EXPECT_EQ(integ[e].sample, int64_t(e) * (integ[0].sample + 2 * P) + integ[0].sample);
    ASSERT_EQ(integ[e].lines.size(), 3 * lines.size());  // every line, once per input
    for (size_t j = 0; j < integ[e].lines.size(); ++j) {
      EXPECT_EQ(integ[e].lines[j], lines[j / 3]);
      EXPECT_EQ(integ[e].line_input[j], ex[j % 3]);
    }
  }
  EXPECT_EQ(integ[0].sample, 2500);  // settle: max(5 x 0.5 s, P / 10)
  std::vector<std::vector<double>> cmd;
  std::vector<double> ph, fr;
  c.fill(0, int(c.total_samples()), cmd, ph, fr);
  auto line_phasor = [&](int i, int64_t from, int k) {  // DFT of one period at line k
    Complex s = 0;
    for (int n = 0; n < P; ++n)
      s += (cmd[i][from + n] - ins[i].dc) * std::polar(1.0, -2 * std::numbers::pi * k * n / P);
    return s;
  };
  for (int q = 0; q < 3; ++q) {
    const int i = ex[q];
    double peak = 0;
    for (int e = 0; e < 3; ++e) {
      const int64_t a = integ[e].sample - integ[0].sample, b = integ[e].sample + 2 * P;
      for (int64_t n = a; n + P < b; ++n) ASSERT_DOUBLE_EQ(cmd[i][n + P], cmd[i][n]);
      double ss = 0;
      for (int64_t n = a; n < b; ++n) peak = std::max(peak, std::abs(cmd[i][n] - ins[i].dc));
      for (int64_t n = integ[e].sample; n < b; ++n) ss += std::pow(cmd[i][n] - ins[i].dc, 2);
      EXPECT_NEAR(std::sqrt(ss / (2 * P)), ins[i].amplitude / std::sqrt(2.0),
                  1e-9 * ins[i].amplitude);
      for (int k : {lines[0], lines[7], lines.back()}) {
        const Complex ratio =
            line_phasor(i, integ[e].sample, k) / line_phasor(i, integ[0].sample, k);
        EXPECT_NEAR(std::abs(ratio - std::polar(1.0, 2 * std::numbers::pi * q * e / 3)), 0, 1e-9)
            << q << " " << e << " " << k;
      }
    }
    EXPECT_NEAR(peak, integ[0].amplitudes[i], 1e-9 * peak);
    EXPECT_GT(peak, 2 * ins[i].amplitude);  // crest factor > 2 sqrt 2
    EXPECT_LE(peak, 0.5 * ins[i].full_scale);
  }
  EXPECT_DOUBLE_EQ(cmd[1][123], ins[1].dc);  // A8 not excited: held at its operating point
  o.realisations = 2;
  o.phases = "schroeder";
  EXPECT_THROW(MultisineCampaign(ins, ex, o, "r"), InputError);
}

// Envelope clipping lowers the crest factor of every experiment of the orthogonal design: each is
// Re(exp(j theta) z), so its peak is at most max |z| (a sine's crest factor is sqrt 2 = 1.41). On
// the J85's quasi-logarithmic grid (34 lines over 3.4 decades, sparse at the top) it gains 15 %:
// the worst crest over four experiment phases from 4.15 (random phases) to 3.50.
TEST(Multisine, LowCrestPhasesBoundEveryExperimentsPeak) {
  MultisineOptions o;  // the J85 band: 0.04-100 Hz at 10 lines per decade, P = 25000
  const int P = 25000;
  const std::vector<int> lines = multisine_lines(o, P);
  ASSERT_EQ(lines.size(), 34u);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uni(0, 2 * std::numbers::pi);
  std::vector<double> start(lines.size());
  for (double& v : start) v = uni(rng);
  // Crest factor (peak / rms) of sum_j sin(2 pi k_j n / P + phi_j + theta), worst over theta.
  auto crest = [&](const std::vector<double>& ph) {
    double worst = 0;
    for (double theta : {0.0, 0.5 * std::numbers::pi, 0.25 * std::numbers::pi, 2.0}) {
      double peak = 0, ss = 0;
      for (int n = 0; n < P; ++n) {
        double x = 0;
        for (size_t j = 0; j < lines.size(); ++j)
          x += std::sin(2 * std::numbers::pi * double(int64_t(lines[j]) * n % P) / P + ph[j] +
                        theta);
        peak = std::max(peak, std::abs(x));
        ss += x * x;
      }
      worst = std::max(worst, peak / std::sqrt(ss / P));
    }
    return worst;
  };
  const double before = crest(start), after = crest(low_crest_phases(P, lines, start));
  RecordProperty("crest_random", std::to_string(before));
  RecordProperty("crest_low", std::to_string(after));
  EXPECT_GT(before, 3.8);
  EXPECT_LT(after, 0.9 * before);
}

// A rate-limited actuator (Wf at 2000 lb/hr per second here) gets a multisine whose slew stays
// within the limit, the level lowered for it (so it moves linearly), the others untouched.
TEST(Multisine, SlewRespectsTheActuatorsRateLimit) {
  Model m = load_model(fralab::testing::source_path("models/j85_95.json"));
  MultisineOptions o;
  o.f_lo_hz = 0.5;
  o.f_hi_hz = 100;
  o.periods = 2;
  o.slowest_time_constant_s = 0.5;
  auto free = campaign_inputs(m, 2.0);
  m.inputs[0].nonlinearity.push_back({NonlinearityKind::kRateLimit, 0, 2000.0});
  auto ins = campaign_inputs(m, 2.0);
  ASSERT_EQ(ins[0].max_rate, 2000.0);
  const auto ex = select_inputs(m, "Wf,BLD");
  MultisineCampaign limited(ins, ex, o, "r"), unlimited(free, ex, o, "r");
  std::vector<std::vector<double>> a, b;
  std::vector<double> ph, fr;
  limited.fill(0, int(limited.total_samples()), a, ph, fr);
  unlimited.fill(0, int(unlimited.total_samples()), b, ph, fr);
  // Over every measured window (a change of experiment jumps, inside the next one's settle).
  auto slew = [&](const std::vector<double>& x) {
    double s = 0;
    for (const auto& e : limited.events())
      if (e.state == RunState::kIntegrate)
        for (int64_t n = e.sample + 1; n < e.sample + e.n_samples; ++n)
          s = std::max(s, std::abs(x[size_t(n)] - x[size_t(n - 1)]));
    return s * 1000.0;
  };
  EXPECT_GT(slew(b[0]), 2000.0);  // without the limit it would be exceeded
  EXPECT_LE(slew(a[0]), 2000.0 * (1 + 1e-9));
  EXPECT_GT(slew(a[0]), 0.9 * 2000.0);  // and the level is lowered no more than needed
  EXPECT_LT(limited.events()[1].amplitudes[0], unlimited.events()[1].amplitudes[0]);
  EXPECT_EQ(limited.events()[1].amplitudes[2], unlimited.events()[1].amplitudes[2]);  // BLD
}

// The zoom: a 2 % mode at 5.5 Hz on the lab's grid (0.1-20 Hz, 10 lines a decade: 5.0 and 6.2 Hz
// there) has no line in its half-power band 5.39-5.61 Hz. Four lines there need 0.055 Hz apart
// (18182 samples): at factor 1 the mode is left to the grid, at factor 4 the period grows and it
// gets them, lines out to +- 6 % (three half-widths) around it, the grid's lines kept.
TEST(Multisine, ZoomPutsLinesInsideALightModesHalfPowerBand) {
  MultisineOptions o;
  o.f_lo_hz = 0.1;
  o.f_hi_hz = 20;
  o.points_per_decade = 10;
  const double f = 5.5, zeta = 0.02;
  auto near_f = [&](const std::vector<int>& lines, int P, double half) {
    int n = 0;
    for (int k : lines) n += std::abs(k * 1000.0 / P - f) <= half * f + 1e-12;
    return n;
  };
  const int P0 = multisine_period_samples(o);
  ASSERT_EQ(P0, 10000);
  const std::vector<int> grid = multisine_lines(o, P0);
  EXPECT_EQ(near_f(grid, P0, zeta), 0);

  o.zoom = {{2 * std::numbers::pi * f, zeta}};
  EXPECT_EQ(multisine_period_samples(o), P0);
  EXPECT_EQ(multisine_lines(o, P0), grid);
  std::vector<ZoomPlacement> zp = zoom_placement(o, P0, grid);
  ASSERT_EQ(zp.size(), 1u);
  EXPECT_FALSE(zp[0].zoomed);
  EXPECT_DOUBLE_EQ(zp[0].period_needed_s, 18.182);
  EXPECT_EQ(zp[0].lines_in_band, 0);

  o.zoom_period_factor = 4;
  const int P = multisine_period_samples(o);
  EXPECT_EQ(P, 18182);
  const std::vector<int> fine = multisine_lines(o, P);
  EXPECT_GE(near_f(fine, P, zeta), kZoomLinesInBand);
  EXPECT_GE(near_f(fine, P, 3 * zeta), 2 * int(0.06 * f * P / 1000.0));  // every harmonic
  EXPECT_TRUE(std::is_sorted(fine.begin(), fine.end()));
  EXPECT_EQ(std::set<int>(fine.begin(), fine.end()).size(), fine.size());
  MultisineOptions no_zoom = o;
  no_zoom.zoom.clear();
  for (int k : multisine_lines(no_zoom, P))
    EXPECT_TRUE(std::count(fine.begin(), fine.end(), k)) << "grid line " << k << " kept";
  zp = zoom_placement(o, P, fine);
  ASSERT_EQ(zp.size(), 1u);
  EXPECT_TRUE(zp[0].zoomed);
  EXPECT_EQ(zp[0].lines_in_band, near_f(fine, P, zeta));
  EXPECT_EQ(zp[0].lines_in_reach, near_f(fine, P, 3 * zeta));
  EXPECT_DOUBLE_EQ(zp[0].resolution_hz, 1000.0 / P);

  // A 5 % mode needs no longer period (7273 samples): zoomed at factor 1, lines 0.1 Hz apart out
  // to +- 15 %.
  o.zoom_period_factor = 1;
  o.zoom = {{2 * std::numbers::pi * f, 0.05}};
  EXPECT_EQ(multisine_period_samples(o), P0);
  const std::vector<int> wide = multisine_lines(o, P0);
  EXPECT_EQ(near_f(wide, P0, 0.05), 5);   // 5.3 ... 5.7 Hz
  EXPECT_EQ(near_f(wide, P0, 0.15), 17);  // 4.7 ... 6.3 Hz
  // One mode lighter than the factor allows beside one it allows: the period is the second's.
  o.zoom_period_factor = 4;
  o.zoom = {{2 * std::numbers::pi * f, 0.001}, {2 * std::numbers::pi * f, zeta}};
  EXPECT_EQ(multisine_period_samples(o), 18182);
  // Outside the band: nothing changes.
  o.zoom = {{2 * std::numbers::pi * 40, 0.02}};
  EXPECT_EQ(multisine_period_samples(o), P0);
  EXPECT_EQ(multisine_lines(o, P0), grid);
  EXPECT_TRUE(zoom_placement(o, P0, grid).empty());
  o.zoom = {{-1, 0.02}};
  EXPECT_THROW(o.validate(), InputError);
  o.zoom = {{10, 1.5}};
  EXPECT_THROW(o.validate(), InputError);
  o.zoom = {{10, 0.02}};
  o.zoom_period_factor = 0.5;
  EXPECT_THROW(o.validate(), InputError);
  o.zoom_period_factor = 17;
  EXPECT_THROW(o.validate(), InputError);
}

// The light modes a simulation gives the zoom: pole pairs under zeta 0.1 in the band, pairs
// within 1 % one mode of the lightest damping; well damped and real poles are not modes.
TEST(ModelInfo, LightModesAreTheLightlyDampedPolePairsInTheBand) {
  Model m = load_model(fralab::testing::source_path("models/j85_95_sim.json"));
  // Wf:P3 has 49.6 rad/s at zeta 0.021, Wf:DPP3 49.7 at 0.0044: one mode.
  const std::vector<ZoomMode> modes = light_modes(m, 0.04, 100);
  ASSERT_EQ(modes.size(), 1u);
  EXPECT_DOUBLE_EQ(modes[0].wn_rad_s, 49.6);
  EXPECT_DOUBLE_EQ(modes[0].zeta, 0.0044);
  EXPECT_TRUE(light_modes(m, 10, 100).empty());  // 7.9 Hz is below the band
  EXPECT_TRUE(light_modes(m, 0.04, 100, 0.004).empty());
}
