// A simulation given as state space (plant/state_space.h, docs/formats.md §2b): the transfer
// functions it implies against C (sI - A)^-1 B + D, and bad files refused naming what is wrong.
#include "fralab/plant/state_space.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fralab/core/error.h"
#include "test_util.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;
using testing::source_path;
using Cd = std::complex<double>;

constexpr double kAgree = 1e-9;  // relative: the paths' responses against the state model's

Json four_state_doc() { return json_load_file(source_path("tests/data/state_space/ss.json")); }

// C (sI - A)^-1 B + D at s = j w for output i, input j, with the delays.
Cd direct(const StateSpace& ss, int i, int j, double w) {
  const Eigen::Index n = ss.A.rows();
  const Eigen::MatrixXcd M = Cd(0, w) * Eigen::MatrixXcd::Identity(n, n) - ss.A.cast<Cd>();
  const Eigen::VectorXcd x = M.partialPivLu().solve(ss.B.col(j).cast<Cd>());
  const double delay = ss.input_delay_s[size_t(j)] + ss.output_delay_s[size_t(i)];
  return ((ss.C.row(i).cast<Cd>() * x)(0) + ss.D(i, j)) * std::exp(Cd(0, -w * delay));
}

TEST(StateSpace, EveryPathsResponseIsTheStateModelsToOnePartInABillion) {
  const Json doc = four_state_doc();
  const StateSpace ss = state_space_from_json(doc, "ss.json");
  const Model m = parse_model(doc, "ss.json");
  ASSERT_EQ(m.inputs.size(), 2u);
  ASSERT_EQ(m.outputs.size(), 3u);
  int paths = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j) {
      const ModelPath* p = m.path(ss.outputs[size_t(i)], ss.inputs[size_t(j)]);
      // fuel reaches every output; nozzle enters at T4 and Wf, which every output sees too.
      ASSERT_NE(p, nullptr) << ss.outputs[size_t(i)] << " <- " << ss.inputs[size_t(j)];
      ++paths;
      for (double w = 1e-3; w < 1e4; w *= 1.3) {
        const Cd want = direct(ss, i, j, w), got = p->tf.at(w);
        EXPECT_LT(std::abs(got - want), kAgree * std::abs(want))
            << p->input << " -> " << p->output << " at " << w << " rad/s";
      }
    }
  EXPECT_EQ(paths, 6);
}

// A mode an input does not reach is no pole of its paths; an output no state feeds is no path.
TEST(StateSpace, AModeAnInputDoesNotReachIsCancelledAndAZeroPathIsNone) {
  StateSpace ss;
  ss.A = Eigen::MatrixXd{{-1, 0, 0}, {0, -5, 0}, {0, 0, -30}};
  ss.B = Eigen::MatrixXd{{1, 0}, {0, 1}, {1, 0}};
  ss.C = Eigen::MatrixXd{{1, 1, 0}, {0, 0, 0}};
  ss.D = Eigen::MatrixXd::Zero(2, 2);
  ss.states = {"a", "b", "c"};
  ss.inputs = {"u", "v"};
  ss.outputs = {"y", "z"};
  ss.validate("inline");
  const auto yu = state_space_path(ss, 0, 0, "inline");
  ASSERT_TRUE(yu.has_value());
  ASSERT_EQ(yu->poles.size(), 1u);  // b is not reached from u, c not seen at y
  EXPECT_NEAR(yu->poles[0].real, -1, 1e-12);
  EXPECT_NEAR(yu->gain, 1, 1e-12);
  const auto yv = state_space_path(ss, 0, 1, "inline");
  ASSERT_TRUE(yv.has_value());
  ASSERT_EQ(yv->poles.size(), 1u);
  EXPECT_NEAR(yv->poles[0].real, -5, 1e-12);
  EXPECT_FALSE(state_space_path(ss, 1, 0, "inline").has_value());  // z: C's row is zero
}

// A light mode is a (wn, zeta) pair of the path.
TEST(StateSpace, ALightlyDampedModeIsOnePairWithItsDamping) {
  constexpr double wn = 12.0, zeta = 0.01;
  StateSpace ss;
  ss.A = Eigen::MatrixXd{{0, 1}, {-wn * wn, -2 * zeta * wn}};
  ss.B = Eigen::MatrixXd{{0}, {wn * wn}};
  ss.C = Eigen::MatrixXd{{1, 0}};
  ss.D = Eigen::MatrixXd::Zero(1, 1);
  ss.states = {"x", "v"};
  ss.inputs = {"f"};
  ss.outputs = {"y"};
  const auto tf = state_space_path(ss, 0, 0, "inline");
  ASSERT_TRUE(tf.has_value());
  ASSERT_EQ(tf->poles.size(), 1u);
  ASSERT_TRUE(tf->poles[0].pair);
  EXPECT_NEAR(tf->poles[0].wn, wn, 1e-10);
  EXPECT_NEAR(tf->poles[0].zeta, zeta, 1e-10);
  EXPECT_NEAR(tf->gain, 1, 1e-12);
  EXPECT_TRUE(tf->zeros.empty());
}

// Participation factors: a mode of one state is that state's; a symmetric coupling shares it.
TEST(StateSpace, AModesParticipationFactorsNameTheStatesInIt) {
  StateSpace ss;
  ss.states = {"a", "b"};
  ss.A = Eigen::MatrixXd{{-1, 1}, {0, -5}};
  auto one = mode_participation(ss, {-1.0005, 0});
  ASSERT_TRUE(one.has_value());
  EXPECT_NEAR(one->eigenvalue.real(), -1, 1e-12);
  EXPECT_EQ(one->states[0].first, "a");
  EXPECT_NEAR(one->states[0].second, 1, 1e-12);
  EXPECT_FALSE(mode_participation(ss, {-2, 0}).has_value());  // no mode of A there
  ss.A = Eigen::MatrixXd{{-2, 1}, {1, -2}};
  auto shared = mode_participation(ss, {-3, 0});
  ASSERT_TRUE(shared.has_value());
  EXPECT_NEAR(shared->states[0].second, 0.5, 1e-12);
  EXPECT_NEAR(shared->states[1].second, 0.5, 1e-12);
}

void expect_refused(const std::function<void(Json&)>& spoil, const std::string& what) {
  Json doc = four_state_doc();
  spoil(doc);
  try {
    parse_model(doc, "bad.json");
    ADD_FAILURE() << "accepted: " << what;
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad.json")) << what;
    EXPECT_THAT(e.what(), HasSubstr(what));
  }
}

// The four-state model with two named parameters (tests/data/state_space/parameters.json): N's
// inertia, the inverse of N's row of A and B, and T4's time constant, the inverse of A(2,2).
Json with_parameters(Json d) {
  d["parameters"] = json_load_file(source_path("tests/data/state_space/parameters.json"));
  return d;
}

TEST(StateSpace, ANamedParameterSetsItsEntriesAndReadsBack) {
  const StateSpace ss = state_space_from_json(with_parameters(four_state_doc()), "ss.json");
  ss.validate("ss.json");
  ASSERT_EQ(ss.parameters.size(), 2u);
  EXPECT_EQ(ss.parameters[0].name, "J_spool");
  EXPECT_EQ(ss.parameters[0].units, "kg m2");
  // J 2 -> 4: N's row of A and its B entry halve, nothing else moves.
  const StateSpace moved = with_parameter(ss, 0, 4.0);
  EXPECT_EQ(moved.parameters[0].value, 4.0);
  EXPECT_DOUBLE_EQ(moved.A(0, 0), ss.A(0, 0) / 2);
  EXPECT_DOUBLE_EQ(moved.A(0, 1), ss.A(0, 1) / 2);
  EXPECT_DOUBLE_EQ(moved.B(0, 0), ss.B(0, 0) / 2);
  EXPECT_EQ(moved.A.bottomRows(3), ss.A.bottomRows(3));
  EXPECT_EQ(moved.C, ss.C);
  // tau_T4 3 -> 4.5 s: A(2,2) -1/3 -> -1/4.5.
  EXPECT_DOUBLE_EQ(with_parameter(ss, 1, 4.5).A(1, 1), -1 / 4.5);
  // Written and read back: the same parameters.
  const StateSpace back = state_space_from_json(state_space_document(ss, "x"), "back.json");
  ASSERT_EQ(back.parameters.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(back.parameters[k].name, ss.parameters[k].name);
    EXPECT_EQ(back.parameters[k].units, ss.parameters[k].units);
    EXPECT_EQ(back.parameters[k].value, ss.parameters[k].value);
    ASSERT_EQ(back.parameters[k].entries.size(), ss.parameters[k].entries.size());
    for (size_t q = 0; q < ss.parameters[k].entries.size(); ++q) {
      EXPECT_EQ(back.parameters[k].entries[q].matrix, ss.parameters[k].entries[q].matrix);
      EXPECT_EQ(back.parameters[k].entries[q].row, ss.parameters[k].entries[q].row);
      EXPECT_EQ(back.parameters[k].entries[q].col, ss.parameters[k].entries[q].col);
      EXPECT_EQ(back.parameters[k].entries[q].inverse, ss.parameters[k].entries[q].inverse);
    }
  }
}

TEST(StateSpace, BadModelsAreRefusedNamingTheFileAndWhatIsWrong) {
  expect_refused([](Json& d) { d = with_parameters(d), d["parameters"][0]["value"] = 0; },
                 "parameter \"J_spool\": its value is zero");
  expect_refused(
      [](Json& d) { d = with_parameters(d), d["parameters"][1]["entries"][0]["row"] = 5; },
      "its entry A(5, 2) is outside A (4 x 4)");
  expect_refused(
      [](Json& d) { d = with_parameters(d), d["parameters"][1]["entries"][0]["col"] = 4; },
      "its entry A(2, 4) is 0");
  expect_refused(
      [](Json& d) { d = with_parameters(d), d["parameters"][1]["entries"][0]["form"] = "square"; },
      "/parameters/1/entries/0/form");
  expect_refused([](Json& d) { d = with_parameters(d), d["parameters"][1]["name"] = "J_spool"; },
                 "given twice");
  expect_refused(
      [](Json& d) {
        d = with_parameters(d), d["parameters"][0]["entries"][1] = d["parameters"][0]["entries"][0];
      },
      "its entry A(1, 1) is given twice");
  expect_refused([](Json& d) { d["B"].erase(0); }, "B is 3 x 2, expected 4 x 2");
  expect_refused([](Json& d) { d["C"][0].push_back(1); }, "/C/1");
  expect_refused([](Json& d) { d["A"][1][1] = 0.5; }, "not in the open left half plane");
  expect_refused([](Json& d) { d["outputs"][2]["name"] = "speed"; }, "given twice");
  expect_refused([](Json& d) { d["states"].erase(3); }, "3 state names for 4 states");
  expect_refused([](Json& d) { d.erase("A"); }, "/A");
  expect_refused([](Json& d) { d["inputs"][0]["delay_s"] = -1; }, "negative");
  StateSpace ss = state_space_from_json(four_state_doc(), "bad.json");
  ss.A(2, 2) = NAN;
  EXPECT_THROW(
      {
        try {
          ss.validate("bad.json");
        } catch (const InputError& e) {
          EXPECT_THAT(e.what(), HasSubstr("A(3, 3) is not a finite number"));
          throw;
        }
      },
      InputError);
}

}  // namespace
}  // namespace fralab
