// `fralab bound` on a folder as `fralab diagnose` leaves it: the measurement's engine time from its
// run.json against the bound, the table and fralab-bound/1 JSON; the folders it refuses, by name.
#include "fralab/lab/bound_command.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "fralab/core/error.h"
#include "fralab/core/json_util.h"

using namespace fralab;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {

constexpr double kPi = std::numbers::pi;

// DIR/sim.json (X -> O, a gain of 1), DIR/diagnosis.json (a 10 ms delay on X:O),
// DIR/measure/run.json (engine time 40 s) and its X:O: one stepped-sine point at 50 rad/s,
// 20 cycles of amplitude 2, sigma 0.01.
std::string folder(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("fralab_bound_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d / "measure" / "frd");
  json_save_file((d / "sim.json").string(),
                 Json{{"format", "fralab-model/1"},
                      {"name", "one gain"},
                      {"operating_point", {{"speed_pct", 0}, {"steady_state", Json::object()}}},
                      {"inputs", {{{"name", "X"}, {"units", "-"}, {"full_scale", 1.0}}}},
                      {"outputs", {{{"name", "O"}, {"units", "-"}}}},
                      {"paths", {{{"output", "O"}, {"input", "X"}, {"tf", {{"gain", 1.0}}}}}}});
  json_save_file((d / "diagnosis.json").string(),
                 Json{{"format", "fralab-diagnosis/1"},
                      {"findings",
                       {{{"cause", "time_delay"},
                         {"scope", "path"},
                         {"input", "X"},
                         {"output", "O"},
                         {"parameters", {{"delay_s", 0.01}}},
                         {"intervals", {{"delay_s", {0.0099, 0.0101}}}},
                         {"pairs", {"X:O"}}}}}});
  json_save_file((d / "measure" / "run.json").string(), Json{{"engine_time_s", 40.0}});
  FrdPoint p;
  p.w = 50;
  p.mag = 1;
  p.phase_deg = -50 * 0.01 * 180 / kPi;
  p.sigma = 0.01;
  p.amplitude = 2;
  p.n_cycles = 20;
  save_frd((d / "measure" / "frd" / "X_O.json").string(), Frd{"X:O", {p}, ""});
  return d.string();
}

}  // namespace

TEST(BoundCommand, TheMeasurementsEngineTimeIsSetAgainstTheBestSinesAndWritten) {
  // One point: the best sine is that point's own (its frequency, amplitude and noise), so it
  // needs exactly the point's 20 cycles at 50 rad/s.
  const std::string d = folder("ok");
  const BoundResult r = run_bound({d + "/sim.json", d, "", d + "/bound.json"});
  const double cycles_s = 20 * 2 * kPi / 50;
  ASSERT_EQ(r.bound.status, EngineTimeBound::Status::kOk) << r.bound.message;
  EXPECT_EQ(r.bound.campaign_s, 40.0);
  EXPECT_NEAR(r.bound.bound_s, cycles_s, 1e-7 * cycles_s);
  EXPECT_THAT(r.table, HasSubstr("time_delay [path X O]"));
  const Json j = json_load_file(d + "/bound.json");
  EXPECT_EQ(j.at("format"), "fralab-bound/1");
  EXPECT_NEAR(j.at("ratio").get<double>(), 40.0 / cycles_s, 1e-7 * 40.0 / cycles_s);
  EXPECT_EQ(j.at("parameters").at(0).at("parameter"), "delay_s");
  fs::remove_all(d);
}

TEST(BoundCommand, AFolderWithoutWhatTheBoundNeedsIsRefusedNamingTheFile) {
  const std::string d = folder("refused");
  fs::remove(d + "/measure/run.json");
  EXPECT_THAT(
      [&] {
        run_bound({d + "/sim.json", d, "", ""});
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("measure/run.json")));
  Json dj = json_load_file(d + "/diagnosis.json");
  dj["baseline"] = {{"folder", "L1"}};
  json_save_file(d + "/diagnosis.json", dj);
  EXPECT_THAT(
      [&] {
        run_bound({d + "/sim.json", d, "", ""});
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("baseline")));
  EXPECT_THAT(
      [&] {
        run_bound({d + "/sim.json", d + "/none", "", ""});
      },
      ::testing::ThrowsMessage<InputError>(HasSubstr("none/diagnosis.json")));
  fs::remove_all(d);
}
