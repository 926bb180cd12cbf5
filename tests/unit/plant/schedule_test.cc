// Models across operating points (plant/schedule.h) on known answers: the set a SET names, the
// model at a member's own point (the member itself), between two points (time constants, natural
// frequencies and gains geometrically, delays linearly: the geometric means at the midpoint), a
// root one point lacks fading out (the response continuous at both ends), and the refusals: a
// channel at one point only, nonlinearities of other types, a point outside the range, a
// malformed spec.
#include "fralab/plant/schedule.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "fralab/core/error.h"
#include "fralab/plant/embedded_models.h"
#include "fralab/plant/simulator.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;

constexpr double kRel = 1e-12;  // arithmetic only: the interpolation's formulas, exactly

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

// A one-path plant: N <- Wf with a DC gain, one real pole, a delay and an actuator pair.
Model plant(double speed, double gain, double tau, double delay, double act_wn,
            const std::string& nonlinearity = "hysteresis") {
  Json j = {{"format", "fralab-model/1"},
            {"name", "p" + std::to_string(int(speed))},
            {"operating_point", {{"speed_pct", speed}, {"steady_state", {{"N", speed * 100}}}}},
            {"inputs",
             {{{"name", "Wf"},
               {"units", "lb/hr"},
               {"full_scale", 3000},
               {"actuator",
                {{"tf", {{"gain", 1.0}, {"poles", {{{"wn", act_wn}, {"zeta", 0.5}}}}}},
                 {"nonlinearity", {{{"type", nonlinearity}, {"width", speed / 10}}}}}}}}},
            {"outputs", {{{"name", "N"}, {"units", "rpm"}, {"noise_rms", 1.0}}}},
            {"paths",
             {{{"output", "N"},
               {"input", "Wf"},
               {"tf", {{"gain", gain}, {"poles", {{{"real", -1 / tau}}}}, {"delay_s", delay}}}}}}};
  return parse_model(j, "p" + std::to_string(int(speed)));
}

SetModel member(double x, Model m) { return {m.source, x, std::move(m)}; }

TEST(Schedule, BetweenTwoPointsRootsAndGainsMoveGeometricallyAndDelaysLinearly) {
  const SetModel lo = member(70, plant(70, 2, 0.5, 0.010, 30));
  const SetModel hi = member(90, plant(90, 8, 0.125, 0.030, 120));
  const Model m = interpolate_models(lo, hi, 80);
  ASSERT_EQ(m.paths.size(), 1u);
  const Tf& tf = m.paths[0].tf;
  EXPECT_NEAR(tf.gain, 4, 4 * kRel);  // sqrt(2 * 8)
  ASSERT_EQ(tf.poles.size(), 1u);
  EXPECT_NEAR(-1 / tf.poles[0].real, 0.25, 0.25 * kRel);  // sqrt(0.5 * 0.125) s
  EXPECT_NEAR(tf.delay_s, 0.020, 1e-15);
  ASSERT_TRUE(m.inputs[0].actuator.has_value());
  EXPECT_NEAR(m.inputs[0].actuator->poles[0].wn, 60, 60 * kRel);  // sqrt(30 * 120) rad/s
  EXPECT_NEAR(m.inputs[0].nonlinearity[0].width, 8, 1e-12);       // 7 .. 9 linearly
  EXPECT_NEAR(m.dc("N"), 8000, 1e-9);
  EXPECT_EQ(m.speed_pct, 80);
  // At a quarter of the way: x^(3/4) y^(1/4).
  const Model q = interpolate_models(lo, hi, 75);
  EXPECT_NEAR(-1 / q.paths[0].tf.poles[0].real, std::pow(0.5, 0.75) * std::pow(0.125, 0.25), kRel);
}

TEST(Schedule, ARootOnePointLacksFadesAndTheResponseIsContinuousAtBothEnds) {
  Model a = plant(70, 2, 0.5, 0, 30), b = plant(90, 2, 0.5, 0, 30);
  a.paths[0].tf.poles.push_back(Root::Real(-40));  // a lag only the low point has
  const SetModel lo = member(70, a), hi = member(90, b);
  const Model mid = interpolate_models(lo, hi, 80);
  ASSERT_EQ(mid.paths[0].tf.poles.size(), 2u);
  EXPECT_NEAR(mid.paths[0].tf.poles[1].real, -80, 80 * kRel);  // -40 / (1 - 1/2)
  // Near either end the response is that end's (the faded lag's factor tends to 1).
  for (double w : {1.0, 10.0, 100.0}) {
    const Model near_lo = interpolate_models(lo, hi, 70 + 1e-6);
    const Model near_hi = interpolate_models(lo, hi, 90 - 1e-6);
    EXPECT_LT(std::abs(near_lo.path_response(0, 0, w) - a.path_response(0, 0, w)),
              1e-6 * std::abs(a.path_response(0, 0, w)));
    EXPECT_LT(std::abs(near_hi.path_response(0, 0, w) - b.path_response(0, 0, w)),
              1e-5 * std::abs(b.path_response(0, 0, w)));
  }
}

TEST(Schedule, TheJ85BetweenItsSpeedsIsAModelThePlantRuns) {
  const auto set = load_model_set("j85");
  ASSERT_EQ(set.size(), 3u);
  // At a member's own point: the member, unchanged.
  EXPECT_EQ(model_to_json(model_at(set, 95)), model_to_json(set[2].model));
  const Model m = load_model_or_embedded("j85@90");
  EXPECT_EQ(m.speed_pct, 90);
  EXPECT_EQ(m.inputs.size(), set[2].model.inputs.size());
  // The spool's time constant (N/Wf's slowest pole): the geometric mean of 85's and 95's.
  auto slowest = [](const Model& x) {
    double tau = 0;
    for (const Root& r : x.path("N", "Wf")->tf.poles)
      if (!r.pair) tau = std::max(tau, -1 / r.real);
    return tau;
  };
  EXPECT_NEAR(slowest(m), std::sqrt(slowest(set[1].model) * slowest(set[2].model)), 1e-9);
  for (const ModelPath& p : m.paths)
    for (const Root& r : p.tf.poles) EXPECT_TRUE(r.stable()) << p.output << "/" << p.input;
  SimulatorOptions so;
  EXPECT_NO_THROW(Simulator(m, so));
}

TEST(Schedule, APairThatSplitsIntoTwoRealRootsMovesAsOneQuadratic) {
  Model a = plant(70, 2, 0.5, 0, 30), b = plant(90, 2, 0.5, 0, 30);
  a.paths[0].tf.poles = {Root::Pair(10, 0.5)};              // s^2/100 + 0.1 s + 1
  b.paths[0].tf.poles = {Root::Real(-2), Root::Real(-50)};  // s^2/100 + 0.52 s + 1
  b.paths[0].tf.zeros = {Root::Real(-20)};                  // a zero only the high point has
  const Model m = interpolate_models(member(70, a), member(90, b), 80);
  const Tf& tf = m.paths[0].tf;
  // Halfway: s^2/100 + 0.31 s + 1, two real roots; the zero faded to -40.
  ASSERT_EQ(tf.poles.size(), 2u);
  const double r1 = tf.poles[0].real, r2 = tf.poles[1].real;
  EXPECT_NEAR(1 / (r1 * r2), 0.01, 1e-15);
  EXPECT_NEAR(-(1 / r1 + 1 / r2), 0.31, 1e-14);
  ASSERT_EQ(tf.zeros.size(), 1u);
  EXPECT_NEAR(tf.zeros[0].real, -40, 1e-12);
  EXPECT_LE(tf.num_order(), tf.den_order());
}

TEST(Schedule, AChannelAtOnePointOnlyIsRefusedByNameOrLeftOutAndSaid) {
  Model b = plant(90, 2, 0.5, 0, 30);
  b.outputs.push_back(b.outputs[0]);
  b.outputs.back().name = "N2";
  const SetModel lo = member(70, plant(70, 2, 0.5, 0, 30)), hi = member(90, b);
  EXPECT_THAT(error_of([&] { interpolate_models(lo, hi, 80); }),
              HasSubstr("output N2 of p90 (speed_pct 90) but not of p70"));
  InterpolationOptions o;
  o.common_channels_only = true;
  const Model m = interpolate_models(lo, hi, 80, o);
  EXPECT_EQ(m.output_index("N2"), -1);
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_THAT(m.warnings[0], HasSubstr("output N2"));
  // The J85 at 70 % has the IGV input but no IGV path: those paths fade in from 70 to 85 %.
  const Model j = load_model_or_embedded("j85@80");
  ASSERT_NE(j.path("N", "IGV"), nullptr);
  EXPECT_NEAR(j.path("N", "IGV")->tf.gain,
              load_model_or_embedded("j85_85").path("N", "IGV")->tf.gain * 2 / 3, 1e-12);
}

TEST(Schedule, OtherNonlinearitiesAPointOutsideTheRangeAndABadSpecAreRefusedByName) {
  const SetModel lo = member(70, plant(70, 2, 0.5, 0, 30, "hysteresis"));
  const SetModel hi = member(90, plant(90, 2, 0.5, 0, 30, "deadband"));
  EXPECT_THAT(error_of([&] { interpolate_models(lo, hi, 80); }),
              HasSubstr("input Wf: nonlinearities hysteresis in p70, deadband in p90"));
  EXPECT_THAT(error_of([] { load_model_or_embedded("j85@50"); }),
              HasSubstr("speed_pct 50: outside the models' range (70, 85, 95)"));
  EXPECT_THAT(error_of([] { load_model_or_embedded("j85@ninety"); }), HasSubstr("SET@X"));
  EXPECT_THAT(error_of([] { load_model_or_embedded("j99@90"); }), HasSubstr("j99: no such model"));
}

TEST(Schedule, ASetIsReadInItsSchedulingVariablesOrderAndNeedsItsKey) {
  EXPECT_THAT(error_of([] { load_model_set("j85", "altitude_m"); }),
              HasSubstr("no number operating_point.altitude_m"));
  const auto m = load_model_set("j85_sim");
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].spec, "j85_70_sim");
  EXPECT_EQ(m[2].x, 95);
  const auto at = parse_model_at("out/env/scheduled_model@altitude_m=3000.5");
  ASSERT_TRUE(at.has_value());
  EXPECT_EQ(at->set, "out/env/scheduled_model");
  EXPECT_EQ(at->schedule_by, "altitude_m");
  EXPECT_EQ(at->x, 3000.5);
  EXPECT_FALSE(parse_model_at("j85_95").has_value());
}

}  // namespace
}  // namespace fralab
