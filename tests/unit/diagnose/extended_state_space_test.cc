// The extended model as a state model (diagnose/extended_state_space.h): a simulation given as
// state space (tests/data/state_space/ss.json) against a truth whose nozzle has a lag the
// simulation lacks, or whose state T4 is slower, measured in-process as diagnose_states_test
// does. The extended model's state model keeps the simulation's states (T4's entry moved), adds
// the lag's state named after its finding, and responds as the extended model to a part in a
// billion; the J85's paths, diagnosed against a lag the data show on one path, name the added state
// there.
#include "fralab/diagnose/extended_state_space.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "exact_measurement.h"
#include "fralab/plant/realisation.h"
#include "test_util.h"

namespace fralab {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using C = std::complex<double>;
constexpr double kRelSigma = 0.002;
constexpr double kAgree = 1e-9;  // relative: the state model's responses against the model's

std::vector<MeasuredPair> measure(const Model& truth, uint64_t seed) {
  std::vector<double> w;
  for (double lw = -2; lw <= 2 + 1e-9; lw += 0.125) w.push_back(std::pow(10.0, lw));
  return testing::exact_measurement(truth, w, seed, kRelSigma);
}

// The largest relative difference from the model's position-to-output responses, with delays.
double worst_disagreement(const Model& m, const StateSpace& ss) {
  double worst = 0;
  for (double w = 1e-3; w < 1e4; w *= 1.2)
    for (int i = 0; i < int(m.outputs.size()); ++i)
      for (int j = 0; j < int(m.inputs.size()); ++j) {
        const double delay =
            ss.input_delay_s[size_t(j)] + ss.output_delay_s[size_t(i)] + ss.path_delay_s(i, j);
        const C want = m.position_to_output(i, j, w),
                got = state_space_response(ss, C(0, w))(i, j) * std::exp(C(0, -w * delay));
        worst = std::max(worst, want == C(0, 0) ? std::abs(got) : std::abs(got / want - 1.0));
      }
  return worst;
}

TEST(ExtendedStateSpace, AStateModelKeepsItsStatesAndNamesTheStateAFindingAdds) {
  const Json doc = json_load_file(testing::source_path("tests/data/state_space/ss.json"));
  const Model sim = parse_model(doc, "ss.json");
  // A lag before the nozzle: on every path from it.
  Model truth = sim;
  truth.state_space.reset();
  Tf lag;
  lag.poles = {Root::Real(-6)};
  for (ModelPath& p : truth.paths)
    if (p.input == "nozzle") p.tf = p.tf * lag;
  const Diagnosis d = diagnose(sim, measure(truth, 3));
  const std::string json = diagnosis_to_json(d).dump(1);
  ASSERT_EQ(d.findings.size(), 1u) << json;
  ASSERT_EQ(d.findings[0].cause, CauseKind::kMissingLag) << json;
  ASSERT_EQ(d.findings[0].scope, Scope::kInput) << json;
  const StateSpace ss = extended_state_space(sim, d);
  EXPECT_LE(worst_disagreement(d.extended, ss), kAgree);
  ASSERT_EQ(ss.A.rows(), 5);  // the four states and the lag's
  EXPECT_EQ(ss.A.bottomRightCorner(4, 4), sim.state_space->A);
  for (const char* s : {"N", "T4", "P3", "Wf"}) EXPECT_THAT(ss.states, Contains(s));
  EXPECT_THAT(ss.states, Contains(::testing::MatchesRegex("nozzle input pole -[56][0-9.]* rad/s "
                                                          "\\(missing_lag\\)")));
  EXPECT_DOUBLE_EQ(ss.input_delay_s[0], 0.01);  // fuel's delay, as the simulation has it
}

// T4 slower (A(2,2) -1/3 -> -1/4.5): the state model is the simulation's with that entry moved.
TEST(ExtendedStateSpace, AMovedStateEntryIsTheStateModelsOwn) {
  const Json doc = json_load_file(testing::source_path("tests/data/state_space/ss.json"));
  const Model sim = parse_model(doc, "ss.json");
  Json truth_doc = doc;
  truth_doc["A"][1][1] = -1 / 4.5;
  const Diagnosis d = diagnose(sim, measure(parse_model(truth_doc, "truth"), 7));
  const std::string json = diagnosis_to_json(d).dump(1);
  ASSERT_EQ(d.findings.size(), 1u) << json;
  const StateSpace ss = extended_state_space(sim, d);
  EXPECT_LE(worst_disagreement(d.extended, ss), kAgree);
  EXPECT_EQ(ss.states, sim.state_space->states);
  EXPECT_NEAR(ss.A(1, 1) * 4.5, -1, 0.02);
  EXPECT_EQ(ss.B, sim.state_space->B);
}

TEST(ExtendedStateSpace, APathsAddedStateIsNamedAfterItsFinding) {
  const Model sim = load_model(testing::source_path("models/j85_95_sim.json"));
  Model truth = sim;
  Tf lag;
  lag.poles = {Root::Real(-40)};
  truth.path("N", "Wf")->tf = truth.path("N", "Wf")->tf * lag;
  const Diagnosis d = diagnose(sim, measure(truth, 4));
  const std::string json = diagnosis_to_json(d).dump(1);
  ASSERT_EQ(d.findings.size(), 1u) << json;
  const StateSpace ss = extended_state_space(sim, d);
  EXPECT_LE(worst_disagreement(d.extended, ss), kAgree);
  EXPECT_THAT(ss.states, Contains(::testing::MatchesRegex("Wf:N pole -[34][0-9.]* rad/s "
                                                          "\\(missing_lag\\)")));
  int named = 0;
  for (const std::string& s : ss.states) named += s.find("(missing_lag)") != std::string::npos;
  EXPECT_EQ(named, 1);
}

}  // namespace
}  // namespace fralab
