// Where the lab keeps the data-quality sections and how the diagnosis gathers them: a measure
// folder's run.json, an auto campaign's runs, validation/, and the data_quality.json `fralab
// analyze` writes; a malformed section is refused naming its file; a measurement checked again
// for a clock that a later run's estimate, pooled with its own, names.
#include "fralab/lab/data_check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "fralab/core/measure_dir.h"
#include "fralab/exchange/tape_series.h"
#include "fralab/lab/diagnose_command.h"
#include "fralab/lab/measure.h"
#include "fralab/lcm/tape_file.h"
#include "random_machine.h"
#include "shell.h"
#include "test_util.h"

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

TEST(DataCheck, AClockTheValidationPoolsIsMendedInTheMeasurementToo) {
  // A machine (random_machine.h, seed 4 case 51), Y1's clock 0.015 % fast, measured by the lab's
  // multisine twice (noise seeds 3 and 4): each run alone sees it at 5-6 sigma, below the 6 sigma
  // that names it; the second, pooled with the first, names it. The first run's folder, a plain
  // measurement as `fralab measure` leaves it (tape, frd, run.json), is checked again.
  ChannelFault clock;
  clock.kind = ChannelFaultKind::kClock;
  clock.rate_error = 1.5e-4;
  const fralab::testing::RandomCase c =
      fralab::testing::random_machine_case_with_fault(4, 51, "Y1", clock);
  const AcquireOptions o = fralab::testing::lab_multisine();
  const std::string d = fralab::testing::tmpdir("recheck", "fralab_dq_");
  const MeasureDir md(d);
  const fralab::testing::TapeRun first = fralab::testing::simulate_campaign(c.engine, o, true, 3);
  write_tape_file(md.tape(), first.blocks, first.events);
  RunRecord run;
  run.run_id = first.events.front().run_id;
  run.engine = c.engine.name;
  run.pairs = pairs_for_input("U0", {"Y0", "Y1", "Y2", "Y3"});
  const TimeSeries s = blocks_to_series(first.blocks, "test");
  const DataQuality own =
      check_data_quality(s, Schedule{s.sample_rate_hz, run.run_id, first.events});
  run.data_quality = own;
  save_run_record(md.run_json(), run);
  std::vector<Frd> curves = fralab::testing::analyse_run(first, run.pairs);
  save_curves(curves, d);
  const Frd before = load_frd(md.frd("U0:Y1")), untouched = load_frd(md.frd("U0:Y0"));
  ASSERT_TRUE(own.faults.empty()) << own.faults.front().text;
  std::vector<ClockEstimate> all;
  for (ClockEstimate e : own.clocks) all.push_back((e.run = d, e));
  EXPECT_TRUE(recheck_clocks(d, all).lines.empty()) << "its own estimates alone name nothing";

  const fralab::testing::TapeRun second = fralab::testing::simulate_campaign(c.engine, o, true, 4);
  const TimeSeries s2 = blocks_to_series(second.blocks, "test");
  DataQualityOptions pooled;
  pooled.other_runs = all;
  const DataQuality q2 =
      check_data_quality(s2, Schedule{s2.sample_rate_hz, run.run_id, second.events}, pooled);
  for (ClockEstimate e : q2.clocks) all.push_back((e.run = d + "/validation", e));
  ASSERT_THAT(pooled_clocks(all), ::testing::ElementsAre("Y1"));

  const ClockRecheck again = recheck_clocks(d, all);
  ASSERT_EQ(again.lines.size(), 1u);
  EXPECT_THAT(again.lines[0], ::testing::HasSubstr("Y1's phase walks"));
  const RunRecord after = load_run_record(md.run_json());
  ASSERT_TRUE(after.data_quality.has_value());
  ASSERT_EQ(after.data_quality->faults.size(), 1u);
  const DataFault& f = after.data_quality->faults[0];
  EXPECT_EQ(f.channel, "Y1");
  EXPECT_EQ(f.kind, DataFaultKind::kClock);
  EXPECT_TRUE(f.mended);
  EXPECT_NEAR(f.size, 1.5e-4, 3 * f.sigma);
  // The curves at Y1 (U0:Y1, u_U0:Y1) are returned replaced, the others as they were.
  EXPECT_EQ(again.replaced, 2);
  ASSERT_EQ(again.curves.size(), run.pairs.size());
  // Analysed again, U0:Y1's phase at its highest lines moves by the clock's delay at the
  // periods' mean time (about 2 ms at 20 Hz: 0.25 rad).
  const Frd mended = load_frd(md.frd("U0:Y1"));
  ASSERT_EQ(mended.points.size(), before.points.size());
  const FrdPoint& hb = before.points.back();
  const FrdPoint& hm = mended.points.back();
  EXPECT_GT(std::abs(std::arg(hm.value() / hb.value())), 0.05) << "at " << hb.w << " rad/s";
  EXPECT_EQ(frd_to_json(load_frd(md.frd("U0:Y0"))), frd_to_json(untouched));
  // Checked again once more, nothing is left to mend.
  EXPECT_TRUE(recheck_clocks(d, all).lines.empty());
}
