// A simulation made from a common-pole fit (fitted_simulation.h): the model file's paths are the
// fit's curves, every path holds the common poles, and a saved file reads back to the same
// responses; curves that do not name a path are refused naming them.
#include "fralab/diagnose/fitted_simulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <vector>

#include "fralab/core/error.h"

namespace fralab {
namespace {

using C = std::complex<double>;
constexpr double kTwoPi = 2 * std::numbers::pi;

// Two sensors of a two-mode structure, noiseless, sigma given: a curve each.
std::vector<Frd> two_sensors() {
  const double wn[2] = {kTwoPi * 5, kTwoPi * 9}, zeta[2] = {0.01, 0.02};
  const double amp[2][2] = {{1, -0.5}, {0.4, 1}};
  std::vector<Frd> out(2);
  for (int c = 0; c < 2; ++c) {
    out[size_t(c)].pair = c == 0 ? "force:acc1" : "force:acc2";
    for (int i = 0; i < 200; ++i) {
      const double w = kTwoPi * (2 + 10.0 * i / 199);
      C v = 0;
      for (int k = 0; k < 2; ++k)
        v += amp[c][k] * wn[k] * wn[k] / C(wn[k] * wn[k] - w * w, 2 * zeta[k] * wn[k] * w);
      FrdPoint p;
      p.w = w, p.mag = std::abs(v), p.phase_deg = std::arg(v) * 180 / std::numbers::pi;
      p.sigma = 1e-6, p.valid = true;
      out[size_t(c)].points.push_back(p);
    }
  }
  return out;
}

// Each path of the model is its curve's fit to 1e-9 (relative), the same poles in both paths, and
// a saved file reads back to the same responses.
TEST(FittedSimulation, EachPathIsItsCurvesFitWithTheCommonPoles) {
  constexpr double kRel = 1e-9;
  const std::vector<Frd> curves = two_sensors();
  CommonPoleOptions o;
  o.stabilisation = false;
  const CommonPoleResult r = fit_common_poles(curves, {"a.csv", "b.csv"}, o);
  const Model m = fitted_simulation(r, "two sensors");
  ASSERT_EQ(m.inputs.size(), 1u);
  ASSERT_EQ(m.outputs.size(), 2u);
  ASSERT_EQ(m.paths.size(), 2u);
  EXPECT_EQ(m.inputs[0].name, "force");
  EXPECT_EQ(m.paths[0].tf.poles.size(), m.paths[1].tf.poles.size());
  const std::string file = ::testing::TempDir() + "/fitted_simulation_test.json";
  save_model(file, m);
  const Model back = load_model(file);
  for (size_t c = 0; c < 2; ++c) {
    const int o_idx = m.output_index(c == 0 ? "acc1" : "acc2");
    ASSERT_GE(o_idx, 0);
    for (const FrdPoint& p : curves[c].points) {
      const C fit = r.fit.at(c, p.w);
      EXPECT_LT(std::abs(m.path_response(o_idx, 0, p.w) - fit), kRel * std::abs(fit)) << p.w;
      EXPECT_LT(std::abs(back.path_response(o_idx, 0, p.w) - fit), kRel * std::abs(fit)) << p.w;
    }
  }
}

TEST(FittedSimulation, CurvesThatNameNoPathAreRefusedNamingThem) {
  std::vector<Frd> curves = two_sensors();
  CommonPoleOptions o;
  o.stabilisation = false;
  curves[1].pair = "force:acc1";  // two curves of one path
  CommonPoleResult r = fit_common_poles(curves, {"a.csv", "b.csv"}, o);
  try {
    fitted_simulation(r, "x");
    FAIL() << "two curves of one pair accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("b.csv"), std::string::npos) << e.what();
  }
  curves[1].pair = "u_force:force";  // an actuator's own curve names no path
  r = fit_common_poles(curves, {"a.csv", "b.csv"}, o);
  EXPECT_THROW(fitted_simulation(r, "x"), InputError);
}

}  // namespace
}  // namespace fralab
