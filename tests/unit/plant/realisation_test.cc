// A model's linear part as one state model (plant/realisation.h): the responses against the
// model's to one part in a billion, the delays split where they are common, a simulation given as
// state space keeping its states, and the fralab-ss/1 document read back as the same model.
#include "fralab/plant/realisation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fralab/core/error.h"
#include "test_util.h"

namespace fralab {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using testing::source_path;
using Cd = std::complex<double>;

constexpr double kAgree = 1e-9;  // relative: the state model's responses against the model's

// C (jwI - A)^-1 B + D for output i, input j, with its input, output and path delays.
Cd response(const StateSpace& ss, int i, int j, double w) {
  const double delay = ss.input_delay_s[size_t(j)] + ss.output_delay_s[size_t(i)] +
                       (ss.path_delay_s.size() ? ss.path_delay_s(i, j) : 0.0);
  return state_space_response(ss, Cd(0, w))(i, j) * std::exp(Cd(0, -w * delay));
}

// The largest relative difference from the model's position-to-output responses, 1e-3..1e4 rad/s.
double worst_disagreement(const Model& m, const StateSpace& ss) {
  double worst = 0;
  for (double w = 1e-3; w < 1e4; w *= 1.2)
    for (int i = 0; i < int(m.outputs.size()); ++i)
      for (int j = 0; j < int(m.inputs.size()); ++j) {
        const Cd want = m.position_to_output(i, j, w), got = response(ss, i, j, w);
        worst = std::max(worst,
                         want == Cd(0, 0) ? std::abs(got) : std::abs(got - want) / std::abs(want));
      }
  return worst;
}

TEST(Realisation, TheJ85SimulationsEveryPathIsItsStateModelsToOnePartInABillion) {
  const Model m = load_model(source_path("models/j85_95_sim.json"));
  const StateSpace ss = model_state_space(m);
  EXPECT_NO_THROW(ss.validate("j85_95_sim"));
  int order = 0;
  for (const ModelPath& p : m.paths) order += p.tf.den_order();
  EXPECT_EQ(ss.A.rows(), order);  // one state per pole: the paths share none
  EXPECT_LE(worst_disagreement(m, ss), kAgree);
  EXPECT_THAT(ss.states, Contains("Wf:N pole -2.86 rad/s"));
  EXPECT_THAT(ss.states, Contains("Wf:P3 mode 49.6 rad/s zeta 0.021 (2)"));
  EXPECT_EQ(ss.inputs, (std::vector<std::string>{"Wf", "A8", "BLD", "IGV"}));
}

// Two inputs, two outputs: a sensor with its own delay on one output, every path from `u1`
// delayed by 0.02 s, one path by 0.005 s more; a pair of zeros over two real poles.
Model delayed_model() {
  return parse_model(Json::parse(R"({
    "format": "fralab-model/1", "name": "delays",
    "inputs": [{"name": "u1", "units": "1", "full_scale": 1},
               {"name": "u2", "units": "1", "full_scale": 1}],
    "outputs": [{"name": "y1", "units": "1"},
                {"name": "y2", "units": "1",
                 "sensor": {"tf": {"gain": 1, "poles": [{"real": -7}], "delay_s": 0.001}}}],
    "paths": [
      {"output": "y1", "input": "u1", "tf": {"gain": 2, "poles": [{"real": -1}, {"real": -30}],
        "zeros": [{"wn": 12, "zeta": 0.3}], "delay_s": 0.02}},
      {"output": "y2", "input": "u1", "tf": {"gain": -0.5, "poles": [{"wn": 4, "zeta": 0.2}],
        "delay_s": 0.025}},
      {"output": "y1", "input": "u2", "tf": {"gain": 3, "poles": [{"real": -0.5}],
        "zeros": [{"real": 40}]}}
    ]})"),
                     "delays");
}

TEST(Realisation, DelaysAreSplitIntoTheInputsTheOutputsAndThePathsOwn) {
  const Model m = delayed_model();
  const StateSpace ss = model_state_space(m);
  EXPECT_LE(worst_disagreement(m, ss), kAgree);
  EXPECT_DOUBLE_EQ(ss.input_delay_s[0], 0.02);  // the least over u1's paths
  EXPECT_DOUBLE_EQ(ss.input_delay_s[1], 0.0);
  EXPECT_DOUBLE_EQ(ss.output_delay_s[0], 0.0);      // y1 <- u2 has none
  EXPECT_NEAR(ss.output_delay_s[1], 0.006, 1e-15);  // y2's only path: 0.025 + 0.001 - 0.02
  EXPECT_EQ(ss.path_delay_s.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(ss.A.rows(), 2 + 2 + 1 + 1);  // two reals sharing a section, a pair, a pole, the sensor
  EXPECT_THAT(ss.states, Contains("y2 output pole -7 rad/s"));
}

TEST(Realisation, ASimulationGivenAsStateSpaceKeepsItsStatesAndNamesWhatIsAdded) {
  Model m = parse_model(json_load_file(source_path("tests/data/state_space/ss.json")), "ss.json");
  ASSERT_TRUE(m.state_space);
  // A lag before the nozzle (every path from it) and a sensor on `temp`.
  Tf lag;
  lag.poles = {Root::Real(-25)};
  lag.gain = 1.1;
  for (ModelPath& p : m.paths)
    if (p.input == "nozzle") p.tf = p.tf * lag;
  Tf sensor;
  sensor.poles = {Root::Real(-3)};
  m.outputs[1].sensor = sensor;
  const StateNamer namer = [](const StatePlace& place, const Root& pole) {
    return default_state_name(place, pole) + " (added)";
  };
  const StateSpace ss = model_state_space(m, namer);
  EXPECT_LE(worst_disagreement(m, ss), kAgree);
  ASSERT_EQ(ss.A.rows(), 4 + 1 + 1);
  for (const char* s : {"N", "T4", "P3", "Wf"}) EXPECT_THAT(ss.states, Contains(s));
  EXPECT_THAT(ss.states, Contains("nozzle input pole -25 rad/s (added)"));
  EXPECT_THAT(ss.states, Contains("temp output pole -3 rad/s (added)"));
  EXPECT_DOUBLE_EQ(ss.input_delay_s[0], 0.01);
  EXPECT_DOUBLE_EQ(ss.output_delay_s[1], 0.002);

  // A root of the state model moved on one path only: no factor before an input or after an
  // output explains it, so every path is a block of its own.
  Model moved = m;
  moved.path("speed", "fuel")->tf.poles[0].real *= 1.2;
  const StateSpace per_path = model_state_space(moved);
  EXPECT_LE(worst_disagreement(moved, per_path), kAgree);
  EXPECT_THAT(per_path.states, Contains(HasSubstr("fuel:speed")));
}

TEST(Realisation, TheDocumentReadsBackAsAModelWithTheSameResponsesAndActuators) {
  const Model m = load_model(source_path("models/j85_95_sim.json"));
  const StateSpace ss = model_state_space(m);
  const Json doc = model_state_space_document(m, ss);
  EXPECT_EQ(doc["format"], kStateSpaceFormat);
  const Model back = parse_state_space_model(doc, "back");
  ASSERT_TRUE(back.state_space);
  EXPECT_EQ(back.state_space->states, ss.states);
  double worst = 0;
  for (double w = 1e-2; w < 1e3; w *= 1.3)
    for (int i = 0; i < int(m.outputs.size()); ++i)
      for (int j = 0; j < int(m.inputs.size()); ++j) {
        const Cd want = m.position_to_output(i, j, w), got = back.position_to_output(i, j, w);
        worst = std::max(worst, std::abs(got - want) / std::max(std::abs(want), 1e-300));
        EXPECT_EQ(std::abs(want) == 0, std::abs(got) == 0) << i << " " << j;
      }
  // Read back, each path is factored again from the state model (eigenvalues and generalised
  // eigenvalues of 36 states): agreement to a part in a million, as state_space_path checks.
  EXPECT_LE(worst, 1e-6);
  for (size_t j = 0; j < m.inputs.size(); ++j) {
    ASSERT_EQ(bool(back.inputs[j].actuator), bool(m.inputs[j].actuator));
    if (m.inputs[j].actuator) {
      EXPECT_EQ(back.inputs[j].actuator->at(7.0), m.inputs[j].actuator->at(7.0));
    }
  }
}

TEST(Realisation, APathWithoutDynamicsAloneIsRefusedNamingTheModel) {
  const Model m = parse_model(Json::parse(R"({
    "format": "fralab-model/1", "name": "static",
    "inputs": [{"name": "u", "units": "1", "full_scale": 1}],
    "outputs": [{"name": "y", "units": "1"}],
    "paths": [{"output": "y", "input": "u", "tf": {"gain": 2}}]})"),
                              "static.json");
  try {
    model_state_space(m);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("static.json"));
    EXPECT_THAT(e.what(), HasSubstr("no path has dynamics"));
  }
}

}  // namespace
}  // namespace fralab
