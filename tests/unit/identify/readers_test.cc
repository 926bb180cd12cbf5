#include "fralab/identify/readers.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

using namespace fralab;

namespace {

std::string write(const std::string& name, const std::string& text) {
  auto p = std::filesystem::temp_directory_path() / ("fralab_readers_" + name);
  std::ofstream(p) << text;
  return p.string();
}

// A data card: 1 flag, 15-29 frequency, 30-44 part 1, 45-59 part 2.
std::string card(char flag, const std::string& f, const std::string& a, const std::string& b) {
  std::string l(60, ' ');
  l[0] = flag;
  l.replace(14, f.size(), f);
  l.replace(29, a.size(), a);
  l.replace(44, b.size(), b);
  return l + "\n";
}

std::string error_of(const std::string& file) {
  try {
    read_fit_input(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(Readers, CsvWithNamedColumns) {
  Frd a = read_frd_csv(write("a.csv", "f_hz,mag_db,phase_deg,sigma\n1,20,-45,0.1\n0.5,0,10,0.2\n"));
  ASSERT_EQ(a.points.size(), 2u);  // sorted by frequency
  EXPECT_NEAR(a.points[1].w, 2 * std::numbers::pi, 1e-12);
  EXPECT_NEAR(a.points[1].mag, 10.0, 1e-12);
  EXPECT_NEAR(a.points[1].phase_deg, -45.0, 1e-12);
  EXPECT_DOUBLE_EQ(a.points[1].sigma, 0.1);
  Frd b = read_fit_input(write("b.csv", "w,re,im\n3,0,-2\n")).frd;
  EXPECT_NEAR(b.points[0].mag, 2.0, 1e-12);
  EXPECT_NEAR(b.points[0].phase_deg, -90.0, 1e-12);
}

// '#' lines are comments wherever a CSV has them, the first line included: such a file is a CSV,
// not a TFNS deck.
TEST(Readers, ACsvThatBeginsWithCommentsIsReadAsACsv) {
  const Frd f = read_fit_input(write("comment_first.csv",
                                     "# measured on rig 3\n# units: rad/s\nw,mag,phase_deg\n"
                                     "# a comment between rows\n2,0.5,-30\n1,1,-10\n"))
                    .frd;
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_EQ(f.points[0].w, 1.0);
  EXPECT_NEAR(f.points[1].mag, 0.5, 1e-15);
  EXPECT_NEAR(f.points[1].phase_deg, -30.0, 1e-12);
}

// The CSV `fralab export --to csv` writes reads back: an empty sigma or coherence is unknown, and
// a point the analyser refused (valid 0) stays refused.
TEST(Readers, TheExportedCsvReadsBackWithUnknownsAndRefusedPoints) {
  const Frd f = read_fit_input(write("exported.csv",
                                     "# pair Wf:P3; w rad/s, f_hz Hz, phase_deg degrees, sigma of "
                                     "the complex ratio (empty: unknown)\n"
                                     "w,f_hz,mag,mag_db,phase_deg,re,im,sigma,coherence,valid\n"
                                     "1,0.159,2,6.02,0,2,0,,,1\n"
                                     "2,0.318,1,0,-90,0,-1,0.01,0.98,0\n"))
                    .frd;
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_LT(f.points[0].sigma, 0);      // unknown
  EXPECT_LT(f.points[0].coherence, 0);  // unknown
  EXPECT_TRUE(f.points[0].valid);
  EXPECT_EQ(f.points[1].sigma, 0.01);
  EXPECT_EQ(f.points[1].coherence, 0.98);
  EXPECT_FALSE(f.points[1].valid);
  const std::string bad = write("bad_valid.csv", "w,mag,phase_deg,valid\n1,1,0,2\n");
  EXPECT_THAT(error_of(bad), ::testing::HasSubstr(bad + ":2: valid must be 1 or 0"));
}

TEST(Readers, CsvErrorsNameFileAndLine) {
  std::string f = write("c.csv", "w,mag,phase_deg\n1,2,3\n2,x,3\n");
  EXPECT_THAT(error_of(f), ::testing::HasSubstr(f + ":3: \"x\" is not a number")) << error_of(f);
  f = write("d.csv", "w,gain,phase\n1,2,3\n");
  EXPECT_THAT(error_of(f),
              ::testing::HasSubstr("the header needs mag or mag_db with phase_deg, or re and im"));
  f = write("e.csv", "w,re,im\n1,1,0\n2,nan,0\n");  // a NaN sample is refused, not fitted around
  EXPECT_THAT(error_of(f), ::testing::HasSubstr(f + ":3: \"nan\" is not a number")) << error_of(f);
  f = write("empty.csv", "\n  \n");
  EXPECT_THAT(error_of(f),
              ::testing::HasSubstr(f + ": empty: expected fralab-frd/1 JSON, a CSV with a header"))
      << error_of(f);
}

TEST(Readers, CsvNonsenseIsRefusedNamingTheLine) {
  auto err = [](const std::string& text) {
    try {
      read_frd_csv(write("nonsense.csv", text));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(err("w,mag,phase_deg,sigma\n1,1,0,0.1\n2,1,0,0\n"),
              ::testing::HasSubstr("nonsense.csv:3: sigma must be > 0"));
  EXPECT_THAT(err("w,mag,phase_deg\n1,9e18,0\n"), ::testing::HasSubstr("nonsense.csv:2: mag"));
  EXPECT_THAT(err("w,mag,phase_deg\n1,nan,0\n"), ::testing::HasSubstr("nonsense.csv:2"));
  EXPECT_EQ(err("w,mag,phase_deg,sigma\n1,1,0,0.1\n"), "no error");
}

TEST(Readers, TfnsDeckWithUnitOverrides) {
  std::string deck = std::string("C        3         2     0.005      0.02       0.1      0.01\n") +
                     "O       10        40      0.01\n" + "P03 Z02\n" + "*\n" +
                     card(' ', "1.0", "20.0", "-45.0") +        // Bode: rad/s, dB, degrees
                     card('B', "H1.0", "M2.0", "R-0.5") +       // Hz, magnitude, radians
                     card('P', "R10.0", "3.0", "-1.0") +        // polar: magnitude, radians
                     card('R', "20.0", "0.0", "-4.0") + "*\n";  // rectangular
  FitInput in = read_tfns_deck(write("deck.dat", deck));
  ASSERT_TRUE(in.has_control);
  EXPECT_EQ(in.options.den_order_start, 3);
  EXPECT_EQ(in.options.num_order_start, 2);
  EXPECT_DOUBLE_EQ(in.options.c_phi, 0.005);
  EXPECT_DOUBLE_EQ(in.options.c_n, 0.02);
  EXPECT_EQ(in.deletions, (std::vector<std::string>{"P03", "Z02"}));
  ASSERT_EQ(in.frd.points.size(), 4u);
  EXPECT_NEAR(in.frd.points[0].mag, 10.0, 1e-12);
  EXPECT_NEAR(in.frd.points[0].phase_deg, -45.0, 1e-12);
  EXPECT_NEAR(in.frd.points[1].w, 2 * std::numbers::pi, 1e-12);
  EXPECT_NEAR(in.frd.points[1].mag, 2.0, 1e-12);
  EXPECT_NEAR(in.frd.points[1].phase_deg, -0.5 * 180 / std::numbers::pi, 1e-9);
  EXPECT_NEAR(in.frd.points[2].mag, 3.0, 1e-12);
  EXPECT_NEAR(in.frd.points[3].mag, 4.0, 1e-12);
  EXPECT_NEAR(in.frd.points[3].phase_deg, -90.0, 1e-12);
}

TEST(Readers, TfnsDeckErrorsNameTheLine) {
  std::string f = write("bad.dat", "C        2         1\n*\n" + card(' ', "2.0", "0.0", "0.0") +
                                       card(' ', "1.0", "0.0", "0.0") + "*\n");
  EXPECT_THAT(error_of(f), ::testing::HasSubstr(f + ":4: cards must be in ascending frequency"))
      << error_of(f);
  f = write("nostar.dat", "C        2         1\n*\n" + card(' ', "2.0", "0.0", "0.0"));
  EXPECT_THAT(error_of(f), ::testing::HasSubstr("two groups each ended by a '*' card"))
      << error_of(f);
  f = write("badnum.dat", "C        2         1\n*\n" + card(' ', "2.0", "1.2.3", "0.0") + "*\n");
  EXPECT_THAT(error_of(f),
              ::testing::HasSubstr(f + ":3 (columns 30-44): \"1.2.3\" is not a number"))
      << error_of(f);
}

TEST(Readers, RootDeletionKeepsTheDcGain) {
  Tf t;
  t.gain = 2.0;
  t.zeros = {Root::Real(-10.0), Root::Pair(50.0, 0.1)};
  t.poles = {Root::Real(-1.0), Root::Real(-3.0), Root::Pair(40.0, 0.2)};
  Tf d = delete_roots(t, {"P03", "Z02"});
  EXPECT_EQ(d.poles.size(), 2u);
  EXPECT_EQ(d.zeros.size(), 1u);
  EXPECT_DOUBLE_EQ(d.at(0).real(), 2.0);
  EXPECT_THROW(delete_roots(t, {"P04"}), InputError);
}
