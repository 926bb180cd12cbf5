// The stabilisation diagram (stabilisation.h): a structure's modes stay put as the order grows and
// are told physical; the poles an over-sized fit spends on noise wander and are not.
#include "fralab/identify/stabilisation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <filesystem>
#include <numbers>
#include <random>
#include <vector>

#include "fralab/core/error.h"
#include "fralab/identify/pole_set_fit.h"

namespace fralab {
namespace {

using C = std::complex<double>;
constexpr double kTwoPi = 2 * std::numbers::pi;

// Three accelerometers on a structure of four light modes (rank-one residues of mixed sign), on
// 400 lines over 2-20 Hz with complex noise of known sigma.
struct Structure {
  std::vector<double> f_hz{4.1, 7.3, 11.0, 15.6}, zeta{0.008, 0.005, 0.012, 0.02};
  std::vector<std::vector<double>> amp{{1, 2, -1, 0.5}, {-0.5, 1.5, 1, 1}, {2, -1, 0.3, -0.8}};
  std::vector<double> w;
  std::vector<std::vector<C>> g;
  std::vector<std::vector<double>> W;

  explicit Structure(double sigma) {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> nd(0, std::sqrt(0.5));
    for (int i = 0; i < 400; ++i) w.push_back(kTwoPi * (2 + 18.0 * i / 399));
    for (const auto& a : amp) {
      std::vector<C> c;
      for (double x : w) {
        C v = 0;
        for (size_t k = 0; k < f_hz.size(); ++k) {
          const double wn = kTwoPi * f_hz[k];
          v += a[k] * wn * wn / C(wn * wn - x * x, 2 * zeta[k] * wn * x);
        }
        c.push_back(v + C(nd(rng), nd(rng)) * sigma);
      }
      g.push_back(c);
      W.emplace_back(w.size(), 1 / (sigma * sigma));
    }
  }
};

// A fit of 12 pairs holds the four modes and eight pairs of noise: the four are physical, within
// 0.1 % in frequency of the truth, and none of the eight is.
TEST(Stabilisation, TheModesAreTheColumnsThatStayAndTheNoisesPolesAreNot) {
  constexpr double kFreqTol = 1e-3;
  const Structure s(2e-3);
  StabilisationOptions o;
  o.max_pairs = 12;
  const StabilisationDiagram d = stabilisation_diagram(s.w, s.g, s.W, o);
  ASSERT_EQ(d.rows.size(), 12u);
  const std::vector<C> top = relocated_poles(s.w, s.g, s.W, 12, o.relocations);
  ASSERT_FALSE(top.empty());
  std::vector<int> found(s.f_hz.size(), 0);
  for (C p : top) {
    int mode = -1;
    for (size_t k = 0; k < s.f_hz.size(); ++k)
      if (std::abs(std::abs(p) / (kTwoPi * s.f_hz[k]) - 1) < kFreqTol) mode = int(k);
    EXPECT_EQ(physical_pole(d, p, o), mode >= 0)
        << std::abs(p) / kTwoPi << " Hz, zeta " << -p.real() / std::abs(p) << ", in "
        << stable_rows(d, p, o) << " rows";
    if (mode >= 0) ++found[size_t(mode)];
  }
  for (size_t k = 0; k < s.f_hz.size(); ++k) EXPECT_EQ(found[k], 1) << s.f_hz[k] << " Hz";
  // From the fifth row on, every mode is marked stable against the row below.
  for (size_t k = 0; k < s.f_hz.size(); ++k) {
    for (size_t r = 5; r < d.rows.size(); ++r) {
      bool stable = false;
      for (size_t j = 0; j < d.rows[r].poles.size(); ++j)
        stable = stable ||
                 (std::abs(std::abs(d.rows[r].poles[j]) / (kTwoPi * s.f_hz[k]) - 1) < kFreqTol &&
                  d.rows[r].stability[j] == PoleStability::kStable);
      EXPECT_TRUE(stable) << s.f_hz[k] << " Hz in row " << d.rows[r].pairs;
    }
  }
}

TEST(Stabilisation, BadOptionsAreRefusedNamingThem) {
  StabilisationOptions o;
  o.frequency_rel = 0;
  EXPECT_THROW(o.validate(), InputError);
  o = {};
  o.max_pairs = 0;
  EXPECT_THROW(o.validate(), InputError);
}

// The picture: rendered when gnuplot is there, its data beside it either way.
TEST(Stabilisation, TheDiagramIsDrawn) {
  const Structure s(2e-3);
  StabilisationOptions o;
  o.max_pairs = 6;
  const StabilisationDiagram d = stabilisation_diagram(s.w, s.g, s.W, o);
  const std::string dir = ::testing::TempDir() + "/stabilisation_test";
  std::filesystem::remove_all(dir);
  const bool drawn = render_stabilisation_diagram(d, {}, s.w, s.g, dir + "/diagram.png");
  EXPECT_TRUE(std::filesystem::exists(dir + "/diagram_poles.dat"));
  if (drawn) {
    EXPECT_GT(std::filesystem::file_size(dir + "/diagram.png"), 1000u);
  }
}

}  // namespace
}  // namespace fralab
