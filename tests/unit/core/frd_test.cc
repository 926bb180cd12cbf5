// fralab-frd/1 files (core/frd.h): every field round-trips, points come back sorted by w, and bad
// documents are refused with the file and JSON path named.
#include "fralab/core/frd.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

namespace fralab {
namespace {

using ::testing::HasSubstr;

FrdPoint point(double w) {
  FrdPoint p;
  p.w = w;
  p.mag = 0.5 * w;
  p.phase_deg = -10 * w;
  p.sigma = 0.01;
  p.coherence = 0.97;
  p.h2_rel = 0.002;
  p.h3_rel = 0.003;
  p.nl_rel = 1e-4;
  p.sigma_noise = 0.006;
  p.sigma_nl = 0.008;
  p.realisations = 4;
  p.line_amplitude = 0.7;
  p.n_cycles = 8;
  p.step = 3;
  p.input = "Wf";
  p.amplitude = 60;
  p.valid = w < 2;
  p.note = w < 2 ? "" : "missing seq 7";
  return p;
}

TEST(Frd, EveryFieldRoundTripsThroughAFile) {
  Frd f;
  f.pair = "Wf:P3";
  f.points = {point(3.0), point(1.0)};  // out of order on purpose
  const std::string file = (std::filesystem::temp_directory_path() / "frd_test.json").string();
  save_frd(file, f);
  const Frd g = load_frd(file);
  EXPECT_EQ(g.pair, "Wf:P3");
  EXPECT_EQ(g.source, file);
  ASSERT_EQ(g.points.size(), 2u);
  EXPECT_DOUBLE_EQ(g.points[0].w, 1.0);  // sorted by w
  for (size_t i = 0; i < 2; ++i) {
    const FrdPoint want = point(g.points[i].w), got = g.points[i];
    EXPECT_DOUBLE_EQ(got.mag, want.mag);
    EXPECT_DOUBLE_EQ(got.phase_deg, want.phase_deg);
    EXPECT_DOUBLE_EQ(got.sigma, want.sigma);
    EXPECT_DOUBLE_EQ(got.coherence, want.coherence);
    EXPECT_DOUBLE_EQ(got.h2_rel, want.h2_rel);
    EXPECT_DOUBLE_EQ(got.h3_rel, want.h3_rel);
    EXPECT_DOUBLE_EQ(got.nl_rel, want.nl_rel);
    EXPECT_DOUBLE_EQ(got.sigma_noise, want.sigma_noise);
    EXPECT_DOUBLE_EQ(got.sigma_nl, want.sigma_nl);
    EXPECT_EQ(got.realisations, want.realisations);
    EXPECT_DOUBLE_EQ(got.line_amplitude, want.line_amplitude);
    EXPECT_EQ(got.n_cycles, want.n_cycles);
    EXPECT_EQ(got.step, want.step);
    EXPECT_EQ(got.input, want.input);
    EXPECT_DOUBLE_EQ(got.amplitude, want.amplitude);
    EXPECT_EQ(got.valid, want.valid);
    EXPECT_EQ(got.note, want.note);
  }
  std::filesystem::remove(file);
}

TEST(Frd, UnknownValuesAreOptional) {
  const Frd f = frd_from_json(
      Json::parse(
          R"({"format":"fralab-frd/1","pair":"a:b","points":[{"w":1,"mag":2,"phase_deg":3}]})"),
      "x.json");
  ASSERT_EQ(f.points.size(), 1u);
  EXPECT_LT(f.points[0].sigma, 0);
  EXPECT_LT(f.points[0].coherence, 0);
  EXPECT_LT(f.points[0].sigma_noise, 0);
  EXPECT_LT(f.points[0].sigma_nl, 0);
  EXPECT_EQ(f.points[0].realisations, 0);
  EXPECT_TRUE(f.points[0].valid);
}

TEST(Frd, BadDocumentsNameFileAndPath) {
  auto err = [](const char* text) {
    try {
      frd_from_json(Json::parse(text), "m.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(err(R"({"format":"fralab-frd/2","pair":"a:b","points":[]})"),
              HasSubstr("m.json: /format"));
  EXPECT_THAT(
      err(R"({"format":"fralab-frd/1","pair":"a:b","points":[{"w":-1,"mag":1,"phase_deg":0}]})"),
      HasSubstr("m.json: /points/0/w"));
  EXPECT_THAT(
      err(R"({"format":"fralab-frd/1","pair":"a:b","points":[{"w":1,"mag":-3,"phase_deg":0}]})"),
      HasSubstr("/points/0/mag: mag is an amplitude ratio"));
  EXPECT_THAT(err(R"({"format":"fralab-frd/1","pair":"ab","points":[]})"), HasSubstr("ab"));
  EXPECT_THAT(
      err(R"({"format":"fralab-frd/1","pair":"a:b","points":[{"w":1,"mag":1,"phase_deg":0,"valid":1}]})"),
      HasSubstr("/points/0/valid"));
}

// Numeric nonsense is refused with the file and point named: sigma <= 0, coherence > 1, absurd or
// non-finite magnitudes (none may reach a fit).
TEST(Frd, NumericNonsenseIsRefusedNamingThePoint) {
  auto err = [](const std::string& point) {
    try {
      frd_from_json(Json::parse(R"({"format":"fralab-frd/1","pair":"a:b","points":[)" +
                                std::string(R"({"w":1,"mag":1,"phase_deg":0},)") + point + "]}"),
                    "m.json");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(err(R"({"w":2,"mag":1,"phase_deg":0,"sigma":0})"),
              HasSubstr("m.json: /points/1/sigma: sigma 0.000000 must be > 0"));
  EXPECT_THAT(err(R"({"w":2,"mag":1,"phase_deg":0,"sigma":-0.1})"), HasSubstr("/points/1/sigma"));
  EXPECT_THAT(err(R"({"w":2,"mag":1,"phase_deg":0,"coherence":2})"),
              HasSubstr("/points/1: coherence 2.000000 must lie in [0, 1]"));
  EXPECT_THAT(err(R"({"w":2,"mag":9e18,"phase_deg":0})"),
              HasSubstr("/points/1: mag 9000000000000000000.000000 is not an amplitude ratio"));
  // A step or cycle count an int cannot hold (found by the fuzzer: undefined conversion).
  EXPECT_THAT(err(R"({"w":2,"mag":1,"phase_deg":0,"step":-494309189535})"),
              HasSubstr("m.json: /points/1/step: a whole number is needed"));
  EXPECT_THAT(err(R"({"w":2,"mag":1,"phase_deg":0,"n_cycles":2.5})"),
              HasSubstr("/points/1/n_cycles"));
  EXPECT_EQ(err(R"({"w":2,"mag":1,"phase_deg":0,"sigma":0.01,"coherence":1.0})"), "no error");
  EXPECT_THAT(err(R"({"w":2,"mag":1,"phase_deg":0,"sigma_nl":-1})"),
              HasSubstr("/points/1/sigma_nl: sigma_nl must be >= 0"));
  EXPECT_THAT(err(R"({"w":2,"mag":1,"phase_deg":0,"realisations":-2})"),
              HasSubstr("/points/1: realisations -2 is < 0"));
  EXPECT_THAT(err(R"({"w":2,"mag":1,"phase_deg":0,"line_amplitude":-1})"),
              HasSubstr("/points/1: line_amplitude -1.000000 must be a finite >= 0"));
  FrdPoint p;
  p.w = 1;
  p.mag = std::nan("");
  EXPECT_THAT(frd_point_problem(p), HasSubstr("mag"));
  p.mag = 1;
  p.phase_deg = INFINITY;
  EXPECT_THAT(frd_point_problem(p), HasSubstr("phase_deg is not finite"));
}

TEST(Frd, PairsSplitAndNameTheirFiles) {
  EXPECT_EQ(split_pair("u_Wf:N"), std::make_pair(std::string("u_Wf"), std::string("N")));
  EXPECT_EQ(pair_file_stem("u_Wf:N"), "u_Wf_N");
  EXPECT_THROW(split_pair("Wf"), InputError);
  EXPECT_THROW(split_pair(":N"), InputError);
}

}  // namespace
}  // namespace fralab
