// The engine time bound on known answers: a delay measured by a stepped sine at two frequencies,
// a gain by multisines of the orthogonal and the zippered design; the refusals.
#include "fralab/diagnose/engine_time_bound.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace fralab;
using ::testing::HasSubstr;

namespace {

constexpr double kPi = std::numbers::pi;
// Central differences of smooth factors at a relative step of 1e-5: 1e-9 relative and better.
constexpr double kRel = 1e-7;

// Inputs X and Y, output O, each path a gain of 1.
Model sim() {
  Json doc{{"format", "fralab-model/1"},
           {"name", "two gains"},
           {"operating_point", {{"speed_pct", 0}, {"steady_state", Json::object()}}},
           {"inputs",
            {{{"name", "X"}, {"units", "-"}, {"full_scale", 1.0}},
             {{"name", "Y"}, {"units", "-"}, {"full_scale", 1.0}}}},
           {"outputs", {{{"name", "O"}, {"units", "-"}}}},
           {"paths",
            {{{"output", "O"}, {"input", "X"}, {"tf", {{"gain", 1.0}}}},
             {{"output", "O"}, {"input", "Y"}, {"tf", {{"gain", 1.0}}}}}}};
  return parse_model(doc, "sim.json");
}

Finding finding(CauseKind cause, Param p, double value) {
  Finding f;
  f.cause = cause;
  f.input = "X";
  f.output = "O";
  f.parameters[p] = value;
  f.intervals[p] = {value * 0.9, value * 1.1};
  return f;
}

FrdPoint point(double w, std::complex<double> g, double sigma) {
  FrdPoint p;
  p.w = w;
  p.mag = std::abs(g);
  p.phase_deg = std::arg(g) * 180 / kPi;
  p.sigma = sigma;
  return p;
}

// A stepped sine's point: n cycles at w of amplitude A, its sigma that of output noise v
// (sigma^2 A^2 T = v, T the n cycles' seconds).
FrdPoint sine_point(double w, std::complex<double> g, double A, int n, double v) {
  const double T = n * 2 * kPi / w;
  FrdPoint p = point(w, g, std::sqrt(v / (A * A * T)));
  p.amplitude = A;
  p.n_cycles = n;
  return p;
}

MeasuredPair pair(const std::string& name, std::vector<FrdPoint> points) {
  MeasuredPair mp;
  mp.pair = mp.frd.pair = name;
  mp.frd.points = std::move(points);
  return mp;
}

}  // namespace

TEST(EngineTimeBound, ADelaysBestSineIsAtTheTopOfTheBandAndNeedsThePointsWeightedTime) {
  // |dH/dtau| = w: the information per second grows as w^2 under flat noise, so the best sine is
  // the highest measured frequency, and the two points' information, sum w_i^2 T_i A^2 / v, takes
  // it T_2 + T_1 (w_1 / w_2)^2 seconds.
  const double tau = 0.01, A = 2, v = 1e-4, w1 = 10, w2 = 100;
  const int n1 = 20, n2 = 50;
  auto g = [&](double w) { return std::polar(1.0, -w * tau); };
  const std::vector<MeasuredPair> data{
      pair("X:O", {sine_point(w1, g(w1), A, n1, v), sine_point(w2, g(w2), A, n2, v)})};
  const EngineTimeBound b = engine_time_bound(
      sim(), {finding(CauseKind::kTimeDelay, Param::kDelayS, tau)}, data, {}, 100.0);
  ASSERT_EQ(b.status, EngineTimeBound::Status::kOk) << b.message;
  ASSERT_EQ(b.parameters.size(), 1u);
  const ParameterBound& p = b.parameters[0];
  const double T1 = n1 * 2 * kPi / w1, T2 = n2 * 2 * kPi / w2;
  const double expected = T2 + T1 * (w1 / w2) * (w1 / w2);
  EXPECT_NEAR(p.bound_s, expected, kRel * expected);
  EXPECT_NEAR(p.information, (w1 * w1 * T1 + w2 * w2 * T2) * A * A / v, kRel * p.information);
  EXPECT_NEAR(p.sigma_data, 1 / std::sqrt(p.information), 1e-12);
  EXPECT_EQ(p.best_input, "X");
  EXPECT_NEAR(p.best_w_rad_s, w2, 1e-9 * w2);
  EXPECT_NEAR(p.best_amplitude, A, 1e-12);
  EXPECT_NEAR(b.bound_s, expected, kRel * expected);
  EXPECT_NEAR(b.ratio, 100.0 / expected, kRel * b.ratio);
}

TEST(EngineTimeBound, AMultisinesLineCountsEveryExperimentOfItsDesign) {
  // A gain (|dH/dg| the same at every line) measured by two lines of amplitude a each: the best
  // sine carries the power of both (amplitude a sqrt 2), so it needs exactly the seconds each
  // line's estimate averaged: M periods of 2 pi / w0 times the design's experiments (the
  // orthogonal design's 2 inputs on every line; the zippered design's one, each input on its
  // own lines) times the realisations.
  const double a = 0.5, sigma = 0.01, gain_db = 1;
  const int M = 3;
  const std::complex<double> g = std::pow(10.0, gain_db / 20);
  auto line = [&](double w, int realisations) {
    FrdPoint p = point(w, g, sigma);
    p.line_amplitude = a;
    p.n_cycles = M;
    p.realisations = realisations;
    p.input = "X";
    return p;
  };
  auto bound = [&](const std::vector<double>& x_lines, const std::vector<double>& y_lines,
                   int realisations) {
    std::vector<FrdPoint> xs, ys;
    for (double w : x_lines) xs.push_back(line(w, realisations));
    for (double w : y_lines) ys.push_back(line(w, realisations));
    return engine_time_bound(sim(), {finding(CauseKind::kGainMismatch, Param::kGainDb, gain_db)},
                             {pair("X:O", xs), pair("Y:O", ys)}, {}, 1000.0);
  };
  const double period = 2 * kPi;  // w0 = 1 rad/s
  const EngineTimeBound orthogonal = bound({1, 2}, {1, 2}, 0);
  ASSERT_EQ(orthogonal.status, EngineTimeBound::Status::kOk) << orthogonal.message;
  EXPECT_NEAR(orthogonal.bound_s, 2 * M * period, kRel * 2 * M * period);
  EXPECT_NEAR(orthogonal.input_amplitude.at("X"), a * std::sqrt(2.0), 1e-12);
  const EngineTimeBound zippered = bound({1, 3}, {2, 4}, 0);
  EXPECT_NEAR(zippered.bound_s, M * period, kRel * M * period);
  const EngineTimeBound realisations = bound({1, 3}, {2, 4}, 4);
  EXPECT_NEAR(realisations.bound_s, 4 * M * period, kRel * 4 * M * period);
}

TEST(EngineTimeBound, AOneInputMultisinesPositionPairsAreItsLinesToo) {
  // A one-input multisine's analyser sees the position, not the command, on X:O: its points carry
  // no line amplitude, only the multisine's peak. They are the lines of the input's multisine
  // (its actuator curve's): the bound is then M periods of 2 pi / w0, as for the lines themselves,
  // not M cycles at each line's frequency.
  const double a = 0.5, peak = 1.7, sigma = 0.01, gain_db = 1;
  const int M = 3;
  const std::complex<double> g = std::pow(10.0, gain_db / 20);
  std::vector<FrdPoint> actuator, path;
  for (double w : {1.0, 2.0}) {
    FrdPoint u = point(w, 1.0, 1e-4);
    u.line_amplitude = a;
    u.amplitude = peak;
    u.n_cycles = M;
    actuator.push_back(u);
    FrdPoint y = point(w, g, sigma);
    y.amplitude = peak;
    y.n_cycles = M;
    path.push_back(y);
  }
  const EngineTimeBound b =
      engine_time_bound(sim(), {finding(CauseKind::kGainMismatch, Param::kGainDb, gain_db)},
                        {pair("u_X:X", actuator), pair("X:O", path)}, {}, 100.0);
  ASSERT_EQ(b.status, EngineTimeBound::Status::kOk) << b.message;
  const double expected = M * 2 * kPi;
  EXPECT_NEAR(b.bound_s, expected, kRel * expected);
}

TEST(EngineTimeBound, FindingsWithoutAFittedParameterHaveNothingToBound) {
  Finding f = finding(CauseKind::kTimeDelay, Param::kDelayS, 0.01);
  f.intervals.clear();
  const std::vector<MeasuredPair> data{pair("X:O", {sine_point(10, 1.0, 1, 10, 1e-4)})};
  const EngineTimeBound b = engine_time_bound(sim(), {f}, data, {}, 10.0);
  EXPECT_EQ(b.status, EngineTimeBound::Status::kNoParameter);
  EXPECT_THAT(b.message, HasSubstr("nothing to bound"));
  EXPECT_EQ(b.ratio, 0.0);
}

TEST(EngineTimeBound, PointsThatDoNotSayHowTheyWereExcitedAreRefusedByName) {
  const std::vector<Finding> fs{finding(CauseKind::kTimeDelay, Param::kDelayS, 0.01)};
  FrdPoint no_cycles = sine_point(10, 1.0, 1, 10, 1e-4);
  no_cycles.n_cycles = 0;
  FrdPoint no_amplitude = sine_point(10, 1.0, 1, 10, 1e-4);
  no_amplitude.amplitude = 0;
  try {
    engine_time_bound(sim(), fs, {pair("X:O", {sine_point(5, 1.0, 1, 10, 1e-4), no_cycles})}, {},
                      10.0);
    FAIL() << "a point without n_cycles was taken";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("X:O point 1"));
    EXPECT_THAT(e.what(), HasSubstr("n_cycles"));
  }
  EXPECT_THROW(engine_time_bound(sim(), fs, {pair("X:O", {no_amplitude})}, {}, 10.0), InputError);
  EXPECT_THROW(
      engine_time_bound(sim(), fs, {pair("X:O", {sine_point(5, 1.0, 1, 10, 1e-4)})}, {}, NAN),
      InputError);
  EXPECT_THROW(engine_time_bound(sim(), fs, {}, {}, 10.0), InputError);
}
