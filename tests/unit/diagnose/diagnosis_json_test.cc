// diagnosis.json's findings and the diagnosis' words (diagnosis_json.cc, names.cc): a finding's
// typed parameters written and read back, the words in the order diagnosis.json lists them, and
// a key that is no parameter refused naming where.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "fralab/core/json_util.h"
#include "fralab/diagnose/diagnose.h"
#include "fralab/diagnose/parameter.h"

using namespace fralab;
using ::testing::AllOf;
using ::testing::HasSubstr;

namespace {

constexpr int kParams = int(Param::kZeta) + 1;  // the last of the enum

// A moved pair of one path, as the pole-shift unit reports it, with a text parameter and an
// interval unbounded on one side.
Finding moved_pair() {
  Finding f;
  f.cause = CauseKind::kPoleShift;
  f.scope = Scope::kPath;
  f.input = "Wf";
  f.output = "N";
  f.parameters = {{Param::kFromRadS, 2.86},
                  {Param::kToRadS, 3.3},
                  {Param::kFromZeta, 0.3},
                  {Param::kToZeta, 0.25},
                  {Param::kZeta, 0.25}};
  f.text_parameters["form"] = "residue";
  f.intervals[Param::kToRadS] = {3.2, 3.4};
  f.intervals[Param::kToZeta] = {0.2, INFINITY};
  f.pairs = {"Wf:N"};
  return f;
}

Json findings_of(const Finding& f) {
  Diagnosis d;
  d.findings = {f};
  return diagnosis_to_json(d)["findings"];
}

}  // namespace

TEST(DiagnosisWords, EachParameterHasItsWordAndBack) {
  EXPECT_STREQ(to_string(Param::kToRadS), "to_rad_s");
  EXPECT_STREQ(to_string(Param::kTimeConstantFromS), "time_constant_from_s");
  for (int k = 0; k < kParams; ++k) {
    const Param p = Param(k);
    ASSERT_STRNE(to_string(p), "?") << k;
    EXPECT_EQ(param_from_string(to_string(p)), p) << to_string(p);
  }
  EXPECT_EQ(param_from_string("to_rad"), std::nullopt);
  EXPECT_EQ(param_from_string(""), std::nullopt);
}

// A Parameters map lists its entries in the enum's order; the texts the diagnosis writes (the
// report, the self-check's lines) list them as diagnosis.json does only if that is the words'.
TEST(DiagnosisWords, TheEnumsOrderIsItsWordsOrder) {
  for (int k = 0; k + 1 < kParams; ++k)
    EXPECT_LT(std::string(to_string(Param(k))), std::string(to_string(Param(k + 1))))
        << "between " << to_string(Param(k)) << " and " << to_string(Param(k + 1));
}

TEST(DiagnosisJson, AFindingReadsBackAsWritten) {
  const Finding f = moved_pair();
  const Json j = findings_of(f);
  EXPECT_DOUBLE_EQ(j[0]["parameters"]["to_rad_s"].get<double>(), 3.3);
  EXPECT_EQ(j[0]["parameters"]["form"], "residue");
  EXPECT_TRUE(j[0]["intervals"]["to_zeta"][1].is_null());
  const Finding g = finding_from_json(j[0], {"diagnosis.json", "/findings/0"});
  EXPECT_EQ(g.cause, f.cause);
  EXPECT_EQ(g.scope, f.scope);
  EXPECT_EQ(g.input, f.input);
  EXPECT_EQ(g.output, f.output);
  EXPECT_EQ(g.parameters, f.parameters);
  EXPECT_EQ(g.text_parameters, f.text_parameters);
  EXPECT_EQ(g.intervals, f.intervals);
  EXPECT_EQ(g.pairs, f.pairs);
}

TEST(DiagnosisJson, AKeyThatIsNoParameterIsRefusedNamingWhere) {
  Json j = findings_of(moved_pair());
  j[0]["parameters"]["to_rad"] = 3.3;
  try {
    finding_from_json(j[0], {"d.json", "/findings/0"});
    FAIL() << "accepted a parameter 'to_rad'";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("d.json"), HasSubstr("/findings/0/parameters/to_rad"),
                                HasSubstr("not a parameter")));
  }
  j = findings_of(moved_pair());
  j[0]["intervals"]["wn"] = {1.0, 2.0};
  EXPECT_THROW(finding_from_json(j[0], {"d.json", "/findings/0"}), InputError);
}
