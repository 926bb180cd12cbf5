// The acquisition's summary (acquire.json): the keys it has always had, every field back through
// JSON exactly, and a malformed file refused naming the key.
#include "fralab/acquire/acquisition_summary.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

using namespace fralab;
using ::testing::HasSubstr;

namespace {

AcquisitionSummary lockstep() {
  AcquisitionSummary s;
  s.run_id = "run-1";
  s.engine_time_s = 291.46;
  s.wall_time_s = 2.5;
  s.speedup = 291.46 / 2.5;
  s.blocks = 583;
  s.samples = 291460;
  s.excitation = Excitation::kMultisine;
  s.retransmissions = 2;
  s.items_retransmitted = 5;
  return s;
}

std::string refusal(const Json& j) {
  try {
    acquisition_summary_from_json(j, {"DIR/acquire.json", ""});
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(AcquisitionSummary, ALockstepRunWritesTheKeysAcquireJsonHasAlwaysHad) {
  EXPECT_EQ(acquisition_summary_to_json(lockstep()).dump(),
            R"({"blocks":583,"engine_time_s":291.46,"excitation":"multisine","first_block":0,)"
            R"("items_retransmitted":5,"plant_clock":"lockstep","retransmissions":2,)"
            R"("run_id":"run-1","samples":291460,"speedup":116.58399999999999,)"
            R"("wall_time_s":2.5})");
}

TEST(AcquisitionSummary, EveryFieldComesBackThroughJson) {
  AcquisitionSummary s = lockstep();
  EXPECT_EQ(acquisition_summary_from_json(acquisition_summary_to_json(s), {"f", ""}), s);
  s.first_block = 40;
  s.excitation = Excitation::kStepped;
  s.free_running = true;
  s.held_samples = 12;
  s.repeated_steps = {{3, 0.25, 1}, {3, 0.25, 2}, {7, 1.0 / 3.0, 1}};
  s.adaptive = Json{{"steps", Json::array({{{"input", "Wf"}, {"state", "met"}}})}, {"met", 1}};
  const Json j = acquisition_summary_to_json(s);
  EXPECT_EQ(j["plant_clock"], "free");
  EXPECT_EQ(j["repeated_steps"].size(), 3u);
  EXPECT_EQ(acquisition_summary_from_json(j, {"f", ""}), s);
}

TEST(AcquisitionSummary, AMalformedSummaryIsRefusedNamingTheKey) {
  Json j = acquisition_summary_to_json(lockstep());
  j.erase("samples");
  EXPECT_THAT(refusal(j), HasSubstr("DIR/acquire.json: /: missing required key \"samples\""));
  j = acquisition_summary_to_json(lockstep());
  j["plant_clock"] = "fast";
  EXPECT_THAT(refusal(j), HasSubstr("/plant_clock: \"fast\": free or lockstep"));
  j = acquisition_summary_to_json(lockstep());
  j["retransmissions"] = 1.5;
  EXPECT_THAT(refusal(j), HasSubstr("/retransmissions: expected an integer"));
  j = acquisition_summary_to_json(lockstep());
  j["repeated_steps"] = Json::array({{{"step", 3}, {"frequency_hz", 0.25}}});
  EXPECT_THAT(refusal(j), HasSubstr("/repeated_steps/0: missing required key \"round\""));
  j = acquisition_summary_to_json(lockstep());
  j["excitation"] = "chirp";
  EXPECT_THAT(refusal(j), HasSubstr("chirp"));
  EXPECT_THAT(refusal(Json::array()), HasSubstr("DIR/acquire.json: /: expected a JSON object"));
}
