// The diagnosis' data alternatives: a sign, a gain or a delay a recording fault explains as well,
// and two outputs exchanged, on known answers.
#include "fralab/diagnose/data_faults.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace fralab;
using ::testing::HasSubstr;

namespace {

// Input X; outputs A = 2 / (1 + s/3) and B = -0.5 / (1 + s/40): shapes and gains apart.
Model sim() {
  Json doc{
      {"format", "fralab-model/1"},
      {"name", "two outputs"},
      {"operating_point", {{"speed_pct", 0}, {"steady_state", Json::object()}}},
      {"inputs", {{{"name", "X"}, {"units", "-"}, {"full_scale", 1.0}}}},
      {"outputs", {{{"name", "A"}, {"units", "-"}}, {{"name", "B"}, {"units", "-"}}}},
      {"paths",
       {{{"output", "A"}, {"input", "X"}, {"tf", {{"gain", 2.0}, {"poles", {{{"real", -3.0}}}}}}},
        {{"output", "B"},
         {"input", "X"},
         {"tf", {{"gain", -0.5}, {"poles", {{{"real", -40.0}}}}}}}}}};
  return parse_model(doc, "sim.json");
}

// Measured X:A and X:B: the simulation's `read_as_a` and `read_as_b` at 30 frequencies, 1 % off.
std::vector<MeasuredPair> measured(const Model& m, const std::string& read_as_a,
                                   const std::string& read_as_b) {
  std::vector<MeasuredPair> out;
  for (const auto& [name, from] : {std::pair{"A", read_as_a}, std::pair{"B", read_as_b}}) {
    MeasuredPair mp;
    mp.pair = std::string("X:") + name;
    mp.frd.pair = mp.pair;
    for (int k = 0; k < 30; ++k) {
      FrdPoint p;
      p.w = 0.1 * std::pow(10.0, k / 10.0);
      const auto v = *model_pair_response(m, "X:" + from, p.w) * 1.01;
      p.mag = std::abs(v);
      p.phase_deg = std::arg(v) * 180 / std::numbers::pi;
      p.sigma = 0.01 * p.mag;
      mp.frd.points.push_back(p);
    }
    out.push_back(std::move(mp));
  }
  return out;
}

Finding at_output(CauseKind c, const std::string& o, Parameters params) {
  Finding f;
  f.cause = c;
  f.scope = Scope::kOutput;
  f.output = o;
  f.parameters = std::move(params);
  return f;
}

}  // namespace

TEST(DataAlternatives, ASignAtAnOutputMayBeItsWiring) {
  Diagnosis d;
  d.findings = {at_output(CauseKind::kSignError, "B", {{Param::kSign, -1.0}})};
  const auto a = data_alternatives(d, sim(), measured(sim(), "A", "B"));
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].kind, DataAlternative::Kind::kWiringSign);
  EXPECT_EQ(a[0].channel, "B");
  EXPECT_EQ(a[0].finding, 0);
}

TEST(DataAlternatives, AGainThatIsAUnitsFactorNamesTheUnits) {
  Diagnosis d;
  d.findings = {
      at_output(CauseKind::kGainMismatch, "A", {{Param::kGainDb, 20 * std::log10(6.894757)}}),
      at_output(CauseKind::kGainMismatch, "B", {{Param::kGainDb, 20 * std::log10(1.3)}}),
      at_output(CauseKind::kGainMismatch, "B", {{Param::kGainDb, -20 * std::log10(1.8)}})};
  const auto a = data_alternatives(d, sim(), measured(sim(), "A", "B"));
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].kind, DataAlternative::Kind::kUnits);
  EXPECT_EQ(a[0].finding, 0);
  EXPECT_NEAR(a[0].factor, 6.894757, 1e-9);
  EXPECT_THAT(a[0].text, HasSubstr("psi and kPa"));
  EXPECT_EQ(a[1].finding, 2) << "1/1.8: degF read as degC the other way";
  EXPECT_NEAR(a[1].factor, 1 / 1.8, 1e-9);
}

TEST(DataAlternatives, TwoOutputsExchangedAreNamedAndStraightOnesAreNot) {
  const Model m = sim();
  EXPECT_TRUE(data_alternatives({}, m, measured(m, "A", "B")).empty());
  const auto a = data_alternatives({}, m, measured(m, "B", "A"));
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].kind, DataAlternative::Kind::kSwap);
  EXPECT_EQ(a[0].channel, "A");
  EXPECT_EQ(a[0].other, "B");
  EXPECT_EQ(a[0].finding, -1);
  const Json j = data_alternatives_to_json(a);
  EXPECT_EQ(j[0]["kind"], "swap");
  EXPECT_TRUE(j[0]["finding"].is_null());
}

TEST(DataAlternatives, AFindingAtAClippedChannelMayBeTheClipping) {
  Diagnosis d;
  Finding lag = at_output(CauseKind::kMissingLag, "B", {{Param::kCornerRadS, 20.0}});
  lag.scope = Scope::kPath;
  lag.input = "X";
  d.findings = {at_output(CauseKind::kGainMismatch, "A", {{Param::kGainDb, -0.3}}), lag};
  const auto a = data_alternatives(d, sim(), measured(sim(), "A", "B"), {}, {{"B", 0.037}});
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].kind, DataAlternative::Kind::kClipping);
  EXPECT_EQ(a[0].finding, 1);
  EXPECT_EQ(a[0].channel, "B");
  EXPECT_THAT(a[0].text, HasSubstr("3.7 % of its samples"));
}

TEST(DataAlternatives, ADelayAClockBelowTheChecksWouldGiveNamesTheClock) {
  // B's recorder clock estimated 0.016 % fast +- 0.005 % over the campaign (3.2 sigma, unnamed);
  // the measured periods' mean time 17 s from the run's start: a delay of 2.7 ms there, and the
  // 2 sigma band 1.0-4.4 ms. A path delay of 2.67 ms at B and a lag of corner 370 rad/s (2.7 ms)
  // are within it; a delay of 9 ms, and any delay at A, are not.
  Diagnosis d;
  Finding delay = at_output(CauseKind::kTimeDelay, "B", {{Param::kDelayS, 0.00267}});
  delay.scope = Scope::kPath;
  delay.input = "X";
  Finding lag = at_output(CauseKind::kMissingLag, "B", {{Param::kCornerRadS, 370.0}});
  d.findings = {delay, lag, at_output(CauseKind::kTimeDelay, "B", {{Param::kDelayS, 0.009}}),
                at_output(CauseKind::kTimeDelay, "A", {{Param::kDelayS, 0.00267}})};
  const std::map<std::string, ClockEvidence> clocks{{"B", {1.6e-4, 0.5e-4, 17.0}}};
  const auto a = data_alternatives(d, sim(), measured(sim(), "A", "B"), {}, {}, {}, clocks);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].kind, DataAlternative::Kind::kClock);
  EXPECT_EQ(a[0].finding, 0);
  EXPECT_EQ(a[0].channel, "B");
  EXPECT_THAT(a[0].text, HasSubstr("0.016 % fast"));
  EXPECT_THAT(a[0].text, HasSubstr("2.72 ms"));
  EXPECT_EQ(a[1].finding, 1);
  // Under 2 sigma the estimate is no evidence.
  const std::map<std::string, ClockEvidence> weak{{"B", {1.6e-4, 0.9e-4, 17.0}}};
  EXPECT_TRUE(data_alternatives(d, sim(), measured(sim(), "A", "B"), {}, {}, {}, weak).empty());
}

namespace {

// X:B's points replaced by noise of standard deviation `sigma` (magnitudes 0.3-1.5 sigma, phases
// all round): a dead sensor.
void kill_b(std::vector<MeasuredPair>& data, double sigma) {
  for (MeasuredPair& mp : data) {
    if (mp.pair != "X:B") continue;
    for (size_t k = 0; k < mp.frd.points.size(); ++k) {
      FrdPoint& p = mp.frd.points[k];
      p.mag = sigma * (0.3 + 1.2 * double((k * 7) % 11) / 10.0);
      p.phase_deg = double((k * 137) % 360) - 180;
      p.sigma = sigma;
    }
  }
}

}  // namespace

TEST(SilentOutputs, AnOutputHoldingOnlyNoiseWhereTheSimulationExpectsMuchMoreIsDead) {
  // B's simulated |G| is 0.5 .. 0.2 over the points: 50-20 times a noise of 0.01.
  std::vector<MeasuredPair> data = measured(sim(), "A", "B");
  ASSERT_TRUE(silent_outputs(sim(), data).empty()) << "both outputs respond as simulated";
  kill_b(data, 0.01);
  const auto s = silent_outputs(sim(), data);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].output, "B");
  EXPECT_THAT(s[0].pairs, ::testing::ElementsAre("X:B"));
  EXPECT_THAT(s[0].inputs, ::testing::ElementsAre("X"));
  EXPECT_EQ(s[0].points, 30);
  EXPECT_EQ(s[0].above_noise, 0) << "no noise point reaches 3 sigma";
  EXPECT_EQ(s[0].expected, 30);
  EXPECT_THAT(s[0].text, HasSubstr("dead channel"));
  // A finding at B names the dead channel beside it.
  Diagnosis d;
  d.findings = {at_output(CauseKind::kGainMismatch, "B", {{Param::kGainDb, -30.0}})};
  const auto a = data_alternatives(d, sim(), data, {}, {}, s);
  ASSERT_EQ(a.size(), 1u);
  EXPECT_EQ(a[0].kind, DataAlternative::Kind::kDeadChannel);
  EXPECT_EQ(a[0].channel, "B");
  EXPECT_EQ(a[0].finding, 0);
}

TEST(SilentOutputs, AWeakOutputWhoseSimulationIsNearItsNoiseIsNotDead) {
  // The same noise at B, but a noise of 0.1: the simulation expects no more than 5 sigma.
  std::vector<MeasuredPair> data = measured(sim(), "A", "B");
  kill_b(data, 0.1);
  EXPECT_TRUE(silent_outputs(sim(), data).empty());
}
