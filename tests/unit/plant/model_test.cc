#include "fralab/plant/model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "fralab/plant/embedded_models.h"
#include "test_util.h"

using namespace fralab;
using fralab::testing::source_path;

namespace {

std::string error_of(const std::string& text) {
  try {
    parse_model(Json::parse(text), "bad.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

const char* kMinimal = R"({"format": "fralab-model/1", "name": "m",
  "operating_point": {"speed_pct": 95, "steady_state": {"Wf": 1504.0, "N": 15279.0}},
  "inputs": [{"name": "Wf", "units": "lb/hr", "full_scale": 3000.0,
              "actuator": {"tf": {"gain": 1.0, "poles": [{"wn": 134, "zeta": 0.172}]},
                           "nonlinearity": [{"type": "hysteresis", "width": 6.0}]}}],
  "outputs": [{"name": "N", "units": "rpm", "noise_rms": 1.5,
               "sensor": {"tf": {"gain": 1.0, "poles": [{"real": -0.6}]}}}],
  "paths": [{"output": "N", "input": "Wf",
             "tf": {"gain": 2.86, "zeros": [{"real": 192}], "poles": [{"real": -2.86}, {"real": -76.7}]}}]})";

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  s.replace(s.find(from), from.size(), to);
  return s;
}

}  // namespace

TEST(Model, ContractExampleLoadsWithEveryField) {
  Model m = parse_model(Json::parse(kMinimal), "contract.json");
  ASSERT_EQ(m.inputs.size(), 1u);
  EXPECT_EQ(m.inputs[0].nonlinearity.at(0).kind, NonlinearityKind::kHysteresis);
  EXPECT_STREQ(to_string(m.inputs[0].nonlinearity.at(0).kind), "hysteresis");
  EXPECT_DOUBLE_EQ(m.inputs[0].nonlinearity[0].width, 6.0);
  EXPECT_DOUBLE_EQ(m.outputs[0].noise_rms, 1.5);
  EXPECT_DOUBLE_EQ(m.dc("N"), 15279.0);
  EXPECT_TRUE(m.warnings.empty());
  // command -> output is sensor * path * actuator.
  const double w = 7.0;
  Complex expect = m.outputs[0].sensor->at(w) * m.paths[0].tf.at(w) * m.inputs[0].actuator->at(w);
  EXPECT_NEAR(std::abs(m.command_to_output(0, 0, w) - expect), 0.0, 1e-15);
}

TEST(Model, EveryShippedModelLoadsAndRoundTrips) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(source_path("models"))) {
    if (e.path().extension() != ".json") continue;
    Model m = load_model(e.path().string());
    EXPECT_TRUE(m.warnings.empty()) << e.path() << ": " << m.warnings.front();
    EXPECT_EQ(m.inputs.size(), 4u) << e.path();
    EXPECT_EQ(m.outputs.size(), 5u) << e.path();
    Model r = parse_model(model_to_json(m), "roundtrip");
    for (size_t o = 0; o < m.outputs.size(); ++o)
      for (size_t i = 0; i < m.inputs.size(); ++i)
        EXPECT_EQ(m.command_to_output(o, i, 3.3), r.command_to_output(o, i, 3.3));
    ++n;
  }
  EXPECT_EQ(n, 6);
  EXPECT_EQ(embedded_models().size(), 6u);
}

TEST(Model, J85EngineAndSimulationDifferAsTheReportSays) {
  Model eng = load_model(source_path("models/j85_95.json"));
  Model sim = load_model(source_path("models/j85_95_sim.json"));
  EXPECT_DOUBLE_EQ(eng.path("P3", "Wf")->tf.delay_s, 0.011);
  EXPECT_DOUBLE_EQ(sim.path("P3", "Wf")->tf.delay_s, 0.0);
  EXPECT_EQ(eng.path("N", "Wf")->tf.poles.size(), sim.path("N", "Wf")->tf.poles.size() + 1);
  EXPECT_EQ(eng.inputs[1].nonlinearity.size(), 1u);  // A8 hysteresis
  EXPECT_TRUE(sim.inputs[1].nonlinearity.empty());
  // The simulated exhaust actuator is a decade slower: at 2 Hz the engine's is still near 1.
  const double w = 2 * 3.14159 * 2;
  EXPECT_GT(std::abs(eng.actuator_response(1, w)), 0.9);
  EXPECT_LT(std::abs(sim.actuator_response(1, w)), 0.1);
}

TEST(Model, ErrorsNameFileAndJsonPath) {
  std::string k = kMinimal;
  EXPECT_THAT(error_of(replaced(k, "fralab-model/1", "fralab-model/2")),
              ::testing::HasSubstr("bad.json: /format"));
  EXPECT_THAT(error_of(replaced(k, "\"hysteresis\"", "\"backlash\"")),
              ::testing::HasSubstr(
                  "bad.json: /inputs/0/actuator/nonlinearity/0/type: unknown nonlinearity type "
                  "\"backlash\""));
  EXPECT_THAT(error_of(replaced(k, "{\"real\": -2.86}", "{\"real\": 2.86}")),
              ::testing::HasSubstr("bad.json: /paths/0/tf/poles/0: unstable pole"));
  EXPECT_THAT(
      error_of(replaced(k, "\"rpm\"", "\"psi\"")),
      ::testing::HasSubstr(
          "bad.json: /outputs/0/units: units \"psi\" are pressure, but N is a speed channel"));
  EXPECT_THAT(error_of(replaced(k, "\"output\": \"N\"", "\"output\": \"P9\"")),
              ::testing::HasSubstr("/paths/0/output: no output named \"P9\""));
  EXPECT_THAT(error_of(replaced(k, "\"full_scale\": 3000.0,", "")),
              ::testing::HasSubstr("/inputs/0: missing required key \"full_scale\""));
}

TEST(Model, MalformedFileIsAnErrorNamingTheFile) {
  auto p = std::filesystem::temp_directory_path() / "fralab_malformed_model.json";
  std::ofstream(p) << "{\"format\": \"fralab-model/1\", \"inputs\": [";
  try {
    load_model(p.string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr(p.string() + ": malformed JSON"))
        << e.what();
  }
  EXPECT_THROW(load_model("/nonexistent/model.json"), InputError);
}

TEST(Model, UnknownKeysAreKeptWithAWarning) {
  std::string k =
      replaced(kMinimal, "\"name\": \"m\",", "\"name\": \"m\", \"comment\": \"hello\",");
  Model m = parse_model(Json::parse(k), "x.json");
  ASSERT_EQ(m.warnings.size(), 1u);
  EXPECT_THAT(m.warnings[0], ::testing::HasSubstr("x.json: /comment: unknown key"));
  EXPECT_EQ(model_to_json(m)["comment"], "hello");
}

TEST(Model, EmbeddedLookupListsNamesWhenUnknown) {
  EXPECT_EQ(load_model_or_embedded("j85_95").inputs.size(), 4u);
  try {
    load_model_or_embedded("j99");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("j85_95_sim"));
  }
}
