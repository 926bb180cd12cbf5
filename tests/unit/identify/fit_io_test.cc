// The identifier's files (identify/fit_io.h, transfer_matrix.h): the --delay option, root
// deletion in the fit file, the tf/ and transfer-matrix files of a measurement, and common poles.
#include "fralab/identify/fit_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "test_util.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;

Tf lag2(double gain, double a, double b) {
  Tf t;
  t.gain = gain;
  t.poles = {Root::Real(-a), Root::Real(-b)};
  return t;
}

Frd curve(const std::string& pair, const Tf& t) {
  Frd f;
  f.pair = pair;
  f.points = fralab::testing::tf_points(t, 0.05, 50, 10, 0.0, 1);
  return f;
}

TEST(FitIo, DelayOptionWords) {
  FitOptions o;
  parse_delay_option("none", &o);
  EXPECT_EQ(o.delay, FitOptions::Delay::kNone);
  parse_delay_option("0.011", &o);
  EXPECT_EQ(o.delay, FitOptions::Delay::kFixed);
  EXPECT_EQ(o.delay_s, 0.011);
  parse_delay_option("auto", &o);
  EXPECT_EQ(o.delay, FitOptions::Delay::kAuto);
  parse_delay_option("0", &o);
  EXPECT_EQ(o.delay, FitOptions::Delay::kFixed);
  EXPECT_EQ(o.delay_s, 0.0);
  for (const char* bad : {"11ms", "-0.01", "nan", "inf", "", "0.01s", "fixed"}) {
    try {
      parse_delay_option(bad, &o);
      ADD_FAILURE() << "--delay \"" << bad << "\" was taken";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("must be auto, none or a delay in seconds >= 0")) << bad;
    }
  }
}

TEST(FitIo, DeletedRootsLeaveTheFileAndTheGainStays) {
  FitOptions o;
  const FitResult r =
      fit_tf(fralab::testing::tf_points(lag2(3.0, 2.0, 40.0), 0.05, 50, 10, 0, 1), o);
  ASSERT_EQ(r.tf.poles.size(), 2u);
  Tf kept;
  const Json j = fit_output_json(r, "u:y", {"P02"}, &kept);
  EXPECT_EQ(j["deleted"][0], "P02");
  ASSERT_EQ(j["poles"].size(), 1u);
  EXPECT_NEAR(-j["poles"][0]["real"].get<double>(), 2.0, 1e-6);  // the 40 rad/s pole is gone
  EXPECT_NEAR(kept.gain, 3.0, 1e-6);
  Tf none;
  const Json all = fit_output_json(r, "u:y", {}, &none);
  EXPECT_FALSE(all.contains("deleted"));
  EXPECT_EQ(all["poles"].size(), 2u);
}

TEST(FitIo, MeasurementFilesAndCommonPoles) {
  // u's two paths share the 5 rad/s pole (its actuator); y's two paths share 1 rad/s (its sensor).
  const std::vector<Frd> curves = {curve("u:y", lag2(2.0, 5.0, 1.0)),
                                   curve("u:z", lag2(-1.0, 5.0, 20.0)),
                                   curve("v:y", lag2(0.5, 0.3, 1.0))};
  const std::string dir = (std::filesystem::temp_directory_path() / "fit_io_test").string();
  std::filesystem::remove_all(dir);
  FitOptions o;
  parse_delay_option("none", &o);
  const auto fits = fit_and_write(curves, o, dir, "test matrix");
  ASSERT_EQ(fits.size(), 3u);
  for (const char* f : {"/tf/u_y.json", "/tf/u_z.json", "/tf/v_y.json", "/transfer_matrix.json",
                        "/transfer_matrix.md"})
    EXPECT_TRUE(std::filesystem::exists(dir + f)) << f;

  const TransferMatrix m =
      build_transfer_matrix({{"u", "y", fits[0]}, {"u", "z", fits[1]}, {"v", "y", fits[2]}});
  EXPECT_EQ(m.state_count, 4);  // 5 and 1 (shared), 20, 0.3
  int found = 0;
  for (const auto& c : m.clusters) {
    const double a = -c.mean.real;
    if (std::abs(a - 5.0) < 0.05) {
      ++found;
      EXPECT_EQ(c.scope, "input");
      EXPECT_EQ(c.where, "u");
    }
    if (std::abs(a - 1.0) < 0.01) {
      ++found;
      EXPECT_EQ(c.scope, "output");
      EXPECT_EQ(c.where, "y");
    }
  }
  EXPECT_EQ(found, 2);
  EXPECT_THAT(transfer_matrix_markdown(m, "T"), HasSubstr("T"));
  EXPECT_THAT(tf_to_text(lag2(2.0, 5.0, 1.0)), HasSubstr("s/5 + 1"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fralab
