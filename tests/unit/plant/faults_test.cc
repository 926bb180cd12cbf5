#include "fralab/plant/faults.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>

#include "fralab/plant/model.h"
#include "fralab/plant/simulator.h"

using namespace fralab;
using ::testing::HasSubstr;

namespace {

// One input X (no actuator, full scale 10) and outputs Y = 2 X (dc 100) and Z = X (dc 0), with
// the faults given as JSON arrays (null: none). Noise off unless `noise`.
Model plant(const Json& x_faults, const Json& y_faults, const Json& z_faults = nullptr,
            double noise = 0.0) {
  Json in{{"name", "X"}, {"units", "-"}, {"full_scale", 10.0}};
  Json y{{"name", "Y"}, {"units", "-"}, {"noise_rms", noise}};
  Json z{{"name", "Z"}, {"units", "-"}};
  if (!x_faults.is_null()) in["faults"] = x_faults;
  if (!y_faults.is_null()) y["faults"] = y_faults;
  if (!z_faults.is_null()) z["faults"] = z_faults;
  Json doc{{"format", "fralab-model/1"},
           {"name", "faulty"},
           {"operating_point", {{"speed_pct", 0}, {"steady_state", {{"Y", 100.0}}}}},
           {"inputs", {in}},
           {"outputs", {y, z}},
           {"paths",
            {{{"output", "Y"}, {"input", "X"}, {"tf", {{"gain", 2.0}}}},
             {{"output", "Z"}, {"input", "X"}, {"tf", {{"gain", 1.0}}}}}}};
  return parse_model(doc, "faulty.json");
}

constexpr double kRate = 1000.0, kH = 1.0 / kRate;

// Channels [X, Y, Z] per sample for the command u(k).
template <class U>
std::vector<std::array<double, 3>> run(const Model& m, U u, int64_t n, uint64_t seed = 1) {
  SimulatorOptions o;
  o.sample_rate_hz = kRate;
  o.seed = seed;
  Simulator sim(m, o);
  std::vector<std::array<double, 3>> out(static_cast<size_t>(n));
  for (int64_t k = 0; k < n; ++k) {
    const double c = u(k);
    sim.step(&c, out[size_t(k)].data());
  }
  return out;
}

double sine(int64_t k) { return 3.0 * std::sin(2 * std::numbers::pi * 1.0 * double(k) * kH); }

}  // namespace

TEST(ChannelFaults, ClipHoldsTheChannelInsideItsRangeForTheRightShareOfTime) {
  // Y = 100 + 6 sin(2 pi t) clipped at 103: above it for the share of a period where
  // sin > 1/2, i.e. 1/3.
  const auto r =
      run(plant(nullptr, Json::array({{{"kind", "clip"}, {"max", 103.0}}})), sine, 10000);
  int64_t at = 0;
  for (const auto& s : r) {
    EXPECT_LE(s[1], 103.0);
    at += s[1] == 103.0;
  }
  EXPECT_NEAR(double(at) / 10000, 1.0 / 3, 2e-3);
}

TEST(ChannelFaults, HumDriftSignAndScaleAddWhatTheyName) {
  const Json hum{
      {"kind", "hum"}, {"frequency_hz", 60.0}, {"amplitude", 0.5}, {"harmonics", {1, 3}}};
  const auto r =
      run(plant(nullptr, Json::array({hum, {{"kind", "drift"}, {"rate", 0.2}}}),
                Json::array({{{"kind", "sign"}}, {{"kind", "scale"}, {"factor", 6.894757}}})),
          sine, 3000);
  for (int64_t k : {0, 17, 1234, 2999}) {
    const double t = double(k) * kH, x = sine(k);
    const double hum_v =
        0.5 * (std::sin(2 * std::numbers::pi * 60 * t) + std::sin(2 * std::numbers::pi * 180 * t));
    EXPECT_NEAR(r[size_t(k)][1], 100 + 2 * x + hum_v + 0.2 * t, 1e-9) << k;
    EXPECT_NEAR(r[size_t(k)][2], -x * 6.894757, 1e-9) << k;
  }
}

TEST(ChannelFaults, AFastClockReadsTheSignalAtItsOwnTime) {
  // A ramp command: Y = 100 + 2 k h. With the clock 0.1 % fast and 5 ms late, sample k holds the
  // ramp at k h / 1.001 - 0.005 (linear interpolation is exact on a ramp).
  const Json clock{{"kind", "clock"}, {"rate_error", 1e-3}, {"offset_s", 0.005}};
  const auto r = run(
      plant(nullptr, Json::array({clock})), [](int64_t k) { return double(k) * kH; }, 20000);
  for (int64_t k : {int64_t(10), int64_t(5000), int64_t(19999)}) {
    const double t = std::max(0.0, double(k) * kH / 1.001 - 0.005);
    EXPECT_NEAR(r[size_t(k)][1], 100 + 2 * t, 1e-9) << k;
    EXPECT_NEAR(r[size_t(k)][2], double(k) * kH, 1e-12) << "Z keeps the true clock";
  }
}

TEST(ChannelFaults, DropoutsHoldOrLoseTheirShareOfSamples) {
  // 2 dropouts a second of 10 samples: 2 % of the samples, each run a whole dropout.
  const Json held{{"kind", "dropouts"}, {"rate_hz", 2.0}, {"length", 10}, {"mode", "held"}};
  const Json lost{{"kind", "dropouts"}, {"rate_hz", 2.0}, {"length", 10}, {"mode", "lost"}};
  const int64_t n = 200000;
  const auto r = run(plant(nullptr, Json::array({held}), Json::array({lost}), 0.01), sine, n);
  int64_t repeated = 0, nan = 0;
  for (int64_t k = 1; k < n; ++k) {
    repeated += r[size_t(k)][1] == r[size_t(k - 1)][1];
    nan += std::isnan(r[size_t(k)][2]);
  }
  // Expected share 2 * 10 / 1000 / (1 + 2 * 10 / 1000) (no new dropout starts inside one); the
  // count of dropouts is Poisson (about 392): 4 sigma is 20 % of it.
  const double share = 0.02 / 1.02;
  EXPECT_NEAR(double(repeated) / double(n), share, 0.2 * share);
  EXPECT_NEAR(double(nan) / double(n), share, 0.2 * share);
  EXPECT_EQ(run(plant(nullptr, Json::array({held})), sine, 5000, 7)[4000][1],
            run(plant(nullptr, Json::array({held})), sine, 5000, 7)[4000][1])
      << "deterministic by seed";
}

TEST(ChannelFaults, DeadSwapAndStuckActWhereAndWhenListed) {
  const Json dead{{"kind", "dead"}, {"from_s", 1.0}};
  auto r = run(plant(nullptr, Json::array({dead})), sine, 2000);
  EXPECT_NE(r[999][1], 100.0);
  EXPECT_EQ(r[1000][1], 100.0);
  EXPECT_EQ(r[1999][1], 100.0);

  r = run(plant(nullptr, Json::array({{{"kind", "swap"}, {"with", "Z"}}})), sine, 500);
  EXPECT_NEAR(r[250][1], sine(250), 1e-12);
  EXPECT_NEAR(r[250][2], 100 + 2 * sine(250), 1e-12);

  const Json stuck{{"kind", "stuck"}, {"from_s", 0.1}, {"for_s", 0.2}};
  r = run(plant(Json::array({stuck}), nullptr), sine, 1000);
  for (int64_t k = 100; k < 300; ++k) EXPECT_EQ(r[size_t(k)][0], sine(99)) << k;
  EXPECT_NEAR(r[300][0], sine(300), 1e-12);
  EXPECT_NEAR(r[200][1], 100 + 2 * sine(99), 1e-12) << "the paths see the stuck position";
}

TEST(ChannelFaults, ModelFileRoundTripsItsFaults) {
  const Json faults =
      Json::array({{{"kind", "clip"}, {"min", 90.0}},
                   {{"kind", "dropouts"}, {"rate_hz", 1.5}, {"length", 4}, {"mode", "lost"}},
                   {{"kind", "clock"}, {"rate_error", 5e-4}},
                   {{"kind", "swap"}, {"with", "Z"}}});
  const Model m =
      plant(Json::array({{{"kind", "stuck"}, {"from_s", 2.0}, {"for_s", 1.0}}}), faults);
  const Model back = parse_model(model_to_json(m), "back.json");
  EXPECT_EQ(channel_faults_to_json(back.outputs[0].faults),
            channel_faults_to_json(m.outputs[0].faults));
  EXPECT_EQ(channel_faults_to_json(back.inputs[0].faults),
            channel_faults_to_json(m.inputs[0].faults));
  EXPECT_EQ(back.outputs[0].faults.size(), 4u);
}

TEST(ChannelFaults, BadFaultsAreRefusedNamingWhere) {
  auto refused = [](const Json& x, const Json& y) {
    try {
      plant(x, y);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_THAT(refused(nullptr, Json::array({{{"kind", "hiss"}}})),
              HasSubstr("/outputs/0/faults/0/kind: unknown fault kind \"hiss\""));
  EXPECT_THAT(refused(nullptr, Json::array({{{"kind", "clip"}}})), HasSubstr("needs min, max"));
  EXPECT_THAT(refused(nullptr, Json::array({{{"kind", "stuck"}, {"for_s", 1.0}}})),
              HasSubstr("list it on an input"));
  EXPECT_THAT(refused(nullptr, Json::array({{{"kind", "swap"}, {"with", "Q"}}})),
              HasSubstr("/outputs/0/faults/0/with: no other channel named \"Q\""));
  EXPECT_THAT(refused(nullptr, Json::array({{{"kind", "clock"}, {"rate_error", 0.2}}})),
              HasSubstr("rate_error must be in [0, 0.01]"));
  EXPECT_THAT(refused(nullptr, Json::array({{{"kind", "clock"}, {"rate_error", 1e-4}},
                                            {{"kind", "clock"}, {"rate_error", 1e-4}}})),
              HasSubstr("a second clock fault"));
  EXPECT_THAT(refused(nullptr, Json::array({{{"kind", "dropouts"}, {"mode", "gone"}}})),
              HasSubstr("mode must be \"held\" or \"lost\""));
}

TEST(ChannelFaults, EveryKindTogetherRunsAsTheFuzzSeedHasThem) {
  // The fuzz corpus' model: one fault of each kind; it reads, runs, and each shows.
  const Model m = load_model(FRALAB_SOURCE_DIR "/tests/fuzz/corpus/model/seed_faults.json");
  SimulatorOptions o;
  o.sample_rate_hz = 100;
  Simulator sim(m, o);
  std::vector<double> u{m.dc("Wf")}, y(sim.n_channels());
  int lost = 0;
  for (int k = 0; k < 300; ++k) {
    u[0] = m.dc("Wf") + 10 * std::sin(0.3 * k);
    sim.step(u.data(), y.data());
    // Swapped: channel 1 (P3) records N's signal and channel 2 N's the faulty P3.
    lost += std::isnan(y[2]);
    if (k >= 100 && !std::isnan(y[1])) {
      EXPECT_NEAR(y[1], 15000, 5) << "N dead from 1 s (its noise left), recorded as P3: " << k;
    }
  }
  EXPECT_GT(lost, 0) << "P3's lost dropouts";
}
