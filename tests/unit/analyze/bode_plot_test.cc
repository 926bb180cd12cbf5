// Bode plot files: the numbers behind each figure (gain, unwrapped phase, residuals) and the PNG.
#include "fralab/analyze/bode_plot.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "fralab/core/json_util.h"

using namespace fralab;
namespace fs = std::filesystem;
using C = std::complex<double>;

namespace {

std::vector<std::vector<double>> read_dat(const std::string& file) {
  std::vector<std::vector<double>> rows;
  std::ifstream in(file);
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    std::vector<double> r;
    for (double v; s >> v;) r.push_back(v);
    rows.push_back(r);
  }
  return rows;
}

}  // namespace

TEST(BodePlot, ColumnsHoldGainUnwrappedPhaseAndResiduals) {
  // Measured: a 20 ms delay times 1/(1 + s/10), whose phase passes -180 degrees (unwrapped, it
  // keeps falling). Model: the same lag without the delay, so the residual is exactly the delay: 0
  // dB and -w tau in degrees (wrapped to +-180).
  const double tau = 0.02, kDeg = 180 / std::numbers::pi;
  BodePlot p{"delay", "delay", {}, {}, {}, {{"lag", {}}}};
  for (int k = 0; k <= 40; ++k) {  // 0.3-300 rad/s: the delay alone reaches -344 degrees
    const double w = 0.3 * std::pow(10.0, 3.0 * k / 40);
    const C s(0, w);
    p.w.push_back(w);
    p.meas.push_back(std::exp(-s * tau) / (1.0 + s / 10.0));
    p.sigma.push_back(0.01 * std::abs(p.meas.back()));
    p.models[0].g.push_back(1.0 / (1.0 + s / 10.0));
  }
  const std::string dir =
      (fs::temp_directory_path() / ("fralab_bode_" + std::to_string(::getpid()))).string();
  const bool rendered = render_bode_plots({p}, dir);
  auto rows = read_dat(dir + "/delay.dat");
  ASSERT_EQ(rows.size(), p.w.size());
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    ASSERT_EQ(r.size(), 9u);
    const double w = p.w[i];
    EXPECT_NEAR(r[0], w / (2 * std::numbers::pi), 1e-9 * r[0]);       // Hz
    EXPECT_NEAR(r[1], 20 * std::log10(std::abs(p.meas[i])), 1e-9);    // gain dB
    EXPECT_NEAR(r[2], 20 / std::log(10.0) * 0.01, 1e-9);              // sigma dB
    EXPECT_NEAR(r[3], -(w * tau + std::atan(w / 10)) * kDeg, 1e-6);   // unwrapped
    EXPECT_NEAR(r[4], 0.01 * kDeg, 1e-9);                             // sigma deg
    EXPECT_NEAR(r[7], 0.0, 1e-9);                                     // residual dB
    EXPECT_NEAR(r[8], std::remainder(-w * tau * kDeg, 360.0), 1e-6);  // residual deg
    EXPECT_LT(std::abs(r[6] - r[3]),
              180.0 + 1e-9);  // the model's phase is drawn near the measurement's
  }
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    EXPECT_TRUE(rendered);
    std::ifstream png(dir + "/delay.png", std::ios::binary);
    char magic[4] = {};
    png.read(magic, 4);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG");
    EXPECT_GT(fs::file_size(dir + "/delay.png"), 10000u);
  }
  fs::remove_all(dir);
}

TEST(BodePlot, BadPlotsAreRefusedByName) {
  auto error_of = [](const BodePlot& p) {
    try {
      render_bode_plots(
          {p},
          (fs::temp_directory_path() / ("fralab_bode_bad_" + std::to_string(::getpid()))).string());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  BodePlot p{"x", "bad", {1, 2, 3}, {1, 1, 1}, {}, {{"model", {1, 1}}}};
  EXPECT_THAT(
      error_of(p),
      ::testing::HasSubstr(
          "bode plot bad: frequencies, measurements, sigmas and model curves differ in length"))
      << error_of(p);
  BodeCurve c{"m", {1, 1, 1}};
  BodePlot q{"x", "many", {1, 2, 3}, {1, 1, 1}, {}, {c, c, c, c, c}};
  EXPECT_THAT(error_of(q),
              ::testing::HasSubstr("bode plot many: 5 model curves, at most 4 are drawn"))
      << error_of(q);
  fs::remove_all(fs::temp_directory_path() / ("fralab_bode_bad_" + std::to_string(::getpid())));
}
