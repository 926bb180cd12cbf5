// Where the lab keeps the data-quality sections and how the diagnosis gathers them: a measure
// folder's run.json, an auto campaign's runs, validation/, and the data_quality.json `fralab
// analyze` writes; a malformed section is refused naming its file.
#include "fralab/lab/data_check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "fralab/lab/diagnose_command.h"
#include "shell.h"

using namespace fralab;
namespace fs = std::filesystem;

namespace {

Json section(const std::string& channel, const std::string& kind) {
  return Json{{"checked", {channel}},
              {"faults",
               {{{"channel", channel},
                 {"kind", kind},
                 {"from_s", 0.0},
                 {"to_s", 10.0},
                 {"size", 0.1},
                 {"text", channel + " " + kind},
                 {"action", "done"}}}}};
}

}  // namespace

TEST(DataCheck, TheDiagnosisGathersEverySectionUnderAMeasureFolder) {
  const std::string d = fralab::testing::tmpdir("gather", "fralab_dq_");
  fs::create_directories(d + "/multisine");
  fs::create_directories(d + "/validation");
  json_save_file(d + "/multisine/run.json", Json{{"data_quality", section("P3", "hum")}});
  json_save_file(d + "/validation/run.json", Json{{"data_quality", section("T5", "clock")}});
  json_save_file(d + "/run.json", Json{{"excitation", "auto"}});
  DataNotes notes;
  const Json runs = recorded_data_quality(d, &notes);
  ASSERT_EQ(runs.size(), 2u) << runs.dump(1);
  EXPECT_EQ(runs[0]["folder"], d + "/multisine");
  EXPECT_EQ(runs[0]["faults"][0]["kind"], "hum");
  EXPECT_EQ(runs[1]["faults"][0]["channel"], "T5");
  EXPECT_TRUE(notes.checked);
  EXPECT_THAT(notes.faults, ::testing::ElementsAre(d + "/multisine: P3 hum; done.",
                                                   d + "/validation: T5 clock; done."));
  // A folder `fralab analyze` wrote holds the section beside its curves.
  const std::string a = fralab::testing::tmpdir("analysed", "fralab_dq_");
  json_save_file(a + "/data_quality.json", section("N", "clipping"));
  DataNotes an;
  EXPECT_EQ(recorded_data_quality(a, &an).at(0)["faults"][0]["kind"], "clipping");
  // Nothing recorded: not checked, and the report says so.
  DataNotes none;
  EXPECT_TRUE(recorded_data_quality(fralab::testing::tmpdir("none", "fralab_dq_"), &none).empty());
  EXPECT_FALSE(none.checked);
}

TEST(DataCheck, AMalformedSectionIsRefusedNamingItsFile) {
  const std::string d = fralab::testing::tmpdir("bad", "fralab_dq_");
  Json bad = section("P3", "gremlins");
  json_save_file(d + "/run.json", Json{{"data_quality", bad}});
  DataNotes notes;
  try {
    recorded_data_quality(d, &notes);
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr(d + "/run.json"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("unknown data fault kind \"gremlins\""));
  }
}

TEST(DataCheck, ATapeTheChecksCannotReadIsRefusedNamingIt) {
  try {
    check_tape("/nonexistent/tape.lcmlog", "", {"u:y"});
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("/nonexistent/tape.lcmlog: cannot be read"));
  }
}
