// fralab monitor's rows and its live plot page (lab/monitor.h).
#include "fralab/lab/monitor.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "shell.h"

using namespace fralab;
using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

namespace {

std::vector<FrdPoint> points() {
  std::vector<FrdPoint> v;
  for (double w : {10.0, 1.0, 3.0}) {  // out of order: the plot sorts them
    FrdPoint p;
    p.w = w;
    p.mag = 2.0 / w;
    p.phase_deg = -10 * w;
    p.sigma = 0.01;
    v.push_back(p);
  }
  FrdPoint bad;
  bad.w = 5;
  bad.mag = 1;
  bad.valid = false;  // not drawn
  v.push_back(bad);
  return v;
}

}  // namespace

TEST(MonitorPage, LivePageReloadsItselfAndDrawsThePointsAgainstTheSimulation) {
  ASSERT_EQ(fralab::testing::sh("command -v gnuplot").status, 0);
  const std::string d = fralab::testing::tmpdir("monitor_page");
  const std::string page = d + "/live.html";
  auto sim = [](const FrdPoint& p) -> std::optional<std::complex<double>> {
    return std::complex<double>(1.0 / p.w, 0.0);
  };
  ASSERT_TRUE(write_monitor_page(page, "Wf:P3", points(), sim, true, 3));
  std::string html = fralab::testing::slurp(page);
  EXPECT_THAT(html, HasSubstr("<meta http-equiv=\"refresh\" content=\"3\">"));
  EXPECT_THAT(html, HasSubstr("<svg"));
  EXPECT_THAT(html, HasSubstr("3 points so far"));
  // The plotted data: the three valid points sorted by frequency, measured dB and the
  // simulation's dB (column 6) per row.
  std::ifstream dat(d + "/live.plot/pair.dat");
  std::vector<double> f, db, sim_db;
  for (std::string line; std::getline(dat, line);) {
    std::istringstream r(line);
    double v[6];
    for (double& x : v) r >> x;
    f.push_back(v[0]);
    db.push_back(v[1]);
    sim_db.push_back(v[5]);
  }
  ASSERT_EQ(f.size(), 3u);
  const double ws[] = {1.0, 3.0, 10.0};
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(f[i], ws[i] / (2 * M_PI), 1e-9);
    EXPECT_NEAR(db[i], 20 * std::log10(2.0 / ws[i]), 1e-9);
    EXPECT_NEAR(sim_db[i], 20 * std::log10(1.0 / ws[i]), 1e-9);
  }
  // The final page stays still.
  ASSERT_TRUE(write_monitor_page(page, "Wf:P3", points(), sim, false));
  html = fralab::testing::slurp(page);
  EXPECT_THAT(html, Not(HasSubstr("http-equiv=\"refresh\"")));
  EXPECT_THAT(html, HasSubstr("3 points, complete"));
  EXPECT_FALSE(fs::exists(page + ".tmp"));
  // No point yet: a page that says so, nothing drawn.
  EXPECT_FALSE(write_monitor_page(page, "Wf:P3", {}, nullptr, true));
  EXPECT_THAT(fralab::testing::slurp(page), HasSubstr("No point yet"));
}
