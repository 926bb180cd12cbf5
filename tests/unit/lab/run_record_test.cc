// DIR/run.json as typed records (lab/run_record.h, docs/formats.md §13): the records of a real
// `fralab run` (tests/data/run_record: a measurement's and its auto campaign's) read and written
// back byte for byte; every optional key round-trips; keys this version does not know are kept
// where their object still is; a malformed record is refused naming the file and the key.
#include "fralab/lab/run_record.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "fralab/lab/measure.h"

namespace fralab {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

const std::string kData = std::string(FRALAB_SOURCE_DIR) + "/tests/data/run_record";

std::string slurp(const std::string& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The text json_save_file writes.
std::string saved_text(const Json& j) { return j.dump(2) + "\n"; }

TEST(RunRecord, ARealRunsRecordIsWrittenBackByteForByte) {
  const std::string file = kData + "/run.json";
  const AnyRunRecord any = load_any_run_record(file);
  ASSERT_TRUE(std::holds_alternative<RunRecord>(any));
  const RunRecord& r = std::get<RunRecord>(any);
  EXPECT_EQ(saved_text(run_record_to_json(r)), slurp(file));
  EXPECT_TRUE(r.unknown.empty());
  // The typed values.
  EXPECT_EQ(r.state, RunRecordState::kComplete);
  EXPECT_EQ(r.inputs, "Wf,A8,BLD,IGV");
  EXPECT_EQ(r.pairs.size(), 44u);
  EXPECT_EQ(r.options.seed, 1u);
  EXPECT_EQ(r.options.timeout_s, 3600.0);
  EXPECT_THAT(r.options.acquire_flags, ::testing::Contains("--excitation"));
  ASSERT_TRUE(r.measurement_chain);
  EXPECT_THAT(r.measurement_chain->reheld_inputs, ElementsAre("A8"));
  EXPECT_EQ(r.tape_blocks, 2915);
  EXPECT_EQ(r.retransmissions, 7);
  EXPECT_FALSE(r.failed_step || r.reason || r.resumed || r.adaptive);
}

TEST(RunRecord, ARealAutoCampaignsRecordIsWrittenBackByteForByte) {
  const std::string file = kData + "/auto_run.json";
  const AnyRunRecord any = load_any_run_record(file);
  ASSERT_TRUE(std::holds_alternative<AutoRunRecord>(any));
  const AutoRunRecord& r = std::get<AutoRunRecord>(any);
  EXPECT_EQ(saved_text(auto_run_record_to_json(r)), slurp(file));
  EXPECT_TRUE(r.unknown.empty());
  EXPECT_EQ(r.state, RunRecordState::kComplete);
  EXPECT_THAT(r.sine.inputs, ElementsAre("A8"));
  EXPECT_EQ(r.inputs.at("A8").measured_by, "sine");
  EXPECT_EQ(r.inputs.at("Wf").measured_by, "multisine");
  EXPECT_EQ(r.fit_delay, "auto");
  EXPECT_EQ(r.pairs.size(), 39u);
  // Each kind is refused where the other is wanted.
  EXPECT_THAT([&] { load_run_record(file); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("auto_run.json: an auto campaign's")));
  EXPECT_THROW(load_auto_run_record(kData + "/run.json"), InputError);
}

TEST(RunRecord, EveryOptionalKeyRoundTrips) {
  Json j = json_load_file(kData + "/run.json");
  j["state"] = "partial";
  j["reason"] = "the plant stopped";
  j["failed_step"] = {{"step", "identify"}, {"error", "identify was killed by signal 9"}};
  j["resumed"] = 2;
  j["options"]["hosts"] = {{"plant", "cell-3"}};
  j["options"]["fit"] = false;  // an auto campaign's run: it measures, the campaign fits
  j["adaptive"] = {{"steps", Json::array({{{"input", "Wf"}, {"step", 0}, {"state", "met"}}})},
                   {"met", 1}};
  j["zoom"] = Json::array({{{"wn_rad_s", 49.6},
                            {"zeta", 0.0044},
                            {"lines_in_band", 0},
                            {"lines_in_reach", 0},
                            {"resolution_hz", 0.04},
                            {"zoomed", false},
                            {"period_needed_s", 57.5}}});
  const RunRecord r = run_record_from_json(j, "run.json");
  EXPECT_EQ(run_record_to_json(r), j);
  ASSERT_EQ(r.zoom.size(), 1u);
  EXPECT_EQ(r.zoom[0].mode, (ZoomMode{49.6, 0.0044}));
  EXPECT_DOUBLE_EQ(r.zoom[0].period_needed_s, 57.5);
  EXPECT_EQ(r.failed_step, (FailedStep{"identify", "identify was killed by signal 9"}));
  EXPECT_EQ(r.resumed, 2);
  EXPECT_EQ(r.options.fit, false);
  // Keys a record of an earlier run lacks stay absent.
  for (const char* k : {"timeout_s", "stall_timeout_s", "hosts", "deputy_url", "fit"})
    j["options"].erase(k);
  for (const char* k : {"measurement_chain", "engine_time_s", "wall_time_s", "speedup",
                        "tape_blocks", "fit_time_s", "retransmissions", "items_retransmitted"})
    j.erase(k);
  EXPECT_EQ(run_record_to_json(run_record_from_json(j, "run.json")), j);

  Json a = json_load_file(kData + "/auto_run.json");
  a["state"] = "partial";
  a["failed_step"] = {{"step", "identify"}, {"error", "x"}};
  a["resumed"] = 1;
  EXPECT_EQ(auto_run_record_to_json(auto_run_record_from_json(a, "run.json")), a);
  a.erase("fit_delay");  // a campaign recorded before it was
  a.erase("measurement_chain");
  EXPECT_EQ(auto_run_record_to_json(auto_run_record_from_json(a, "run.json")), a);
}

// A newer fralab's keys survive a resume's rewrite: at the top, in options, in the chain. A
// member of an object the rewrite drops (failed_step, once the fit succeeds) goes with it.
TEST(RunRecord, UnknownKeysAreKeptWhereTheirObjectStays) {
  Json j = json_load_file(kData + "/run.json");
  j["state"] = "partial";
  j["failed_step"] = {{"step", "identify"}, {"error", "x"}, {"core_file", "core.1"}};
  j["operator"] = {{"name", "R. B. Beale"}};
  j["options"]["acquire"] = {{"band", "1:10"}};
  j["measurement_chain"]["anti_alias"] = true;
  RunRecord r = run_record_from_json(j, "run.json");
  EXPECT_EQ(run_record_to_json(r), j);
  MeasureResult res;
  record_fit_outcome(r, res, "");
  const Json back = run_record_to_json(r);
  EXPECT_EQ(back["state"], "complete");
  EXPECT_FALSE(back.contains("failed_step"));
  EXPECT_EQ(back["operator"], j["operator"]);
  EXPECT_EQ(back["options"]["acquire"], j["options"]["acquire"]);
  EXPECT_EQ(back["measurement_chain"]["anti_alias"], true);

  Json a = json_load_file(kData + "/auto_run.json");
  a["inputs"]["A8"]["thd"] = 0.1;
  a["validation"] = "measure/validation";
  EXPECT_EQ(auto_run_record_to_json(auto_run_record_from_json(a, "run.json")), a);
}

// The error for `j` read as a record of its kind.
std::string refusal(const Json& j) {
  try {
    if (j.contains("excitation"))
      auto_run_record_from_json(j, "DIR/run.json");
    else
      run_record_from_json(j, "DIR/run.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(RunRecord, AMalformedRecordIsRefusedNamingTheFileAndKey) {
  const Json run = json_load_file(kData + "/run.json");
  Json j = run;
  j.erase("run_id");
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /: missing required key \"run_id\""));
  j = run;
  j["options"]["seed"] = "1";
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /options/seed: expected an integer >= 0"));
  j = run;
  j["options"]["acquire_flags"][3] = 4;
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /options/acquire_flags/3: expected a string"));
  j = run;
  j["state"] = "done";
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /state: \"done\": running, complete"));
  j = run;
  j["format"] = "fralab-run/2";
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /format: \"fralab-run/2\""));
  j = run;
  j["tape_blocks"] = 29.5;
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /tape_blocks: expected an integer"));
  j = run;
  j["measurement_chain"]["hold"] = "third_order";
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /measurement_chain/hold"));
  j = run;
  j["failed_step"] = {{"step", "identify"}};
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /failed_step: missing required key \"error\""));
  EXPECT_THAT(refusal(Json::array()), HasSubstr("DIR/run.json: /: expected a JSON object"));
  j = run;
  j["zoom"] = Json::array({{{"wn_rad_s", 49.6}, {"zeta", 0.0044}}});
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /zoom/0: missing required key"));

  const Json campaign = json_load_file(kData + "/auto_run.json");
  j = campaign;
  j["sine"].erase("inputs");
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /sine: missing required key \"inputs\""));
  j = campaign;
  j["inputs"]["A8"]["nl_rel_median"] = nullptr;
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /inputs/A8/nl_rel_median: expected a number"));
  j = campaign;
  j["resumed"] = -1;
  EXPECT_THAT(refusal(j), HasSubstr("DIR/run.json: /resumed: expected a count"));
}

}  // namespace
}  // namespace fralab
