#include "fralab/plant/simulator.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "test_util.h"

using namespace fralab;
using fralab::testing::sine_phasor;
using fralab::testing::source_path;
using fralab::testing::wrap_deg;

namespace {

struct SimRun {
  std::vector<std::vector<double>> ch;  // per channel
};

// Sinusoidal command of amplitude `amp` on input `in` at `f` Hz, others at DC.
SimRun run_sine(const Model& m, const SimulatorOptions& opt, int in, double f, double amp,
                size_t n) {
  Simulator sim(m, opt);
  SimRun r;
  r.ch.assign(sim.n_channels(), {});
  std::vector<double> u(m.inputs.size()), y(sim.n_channels());
  const double h = 1.0 / opt.sample_rate_hz;
  for (size_t k = 0; k < n; ++k) {
    for (size_t i = 0; i < u.size(); ++i) u[i] = m.dc(m.inputs[i].name);
    u[in] += amp * std::sin(2 * std::numbers::pi * f * k * h);
    sim.step(u.data(), y.data());
    for (size_t c = 0; c < y.size(); ++c) r.ch[c].push_back(y[c]);
  }
  return r;
}

}  // namespace

// The simulator's acceptance: steady-state sinusoid of every J85 95 % channel vs the model's H(jw),
// gain within 0.1 %, phase within 0.1 degree, noise off. Linear inputs only (A8 has backlash).
TEST(Simulator, J85SinusoidalResponseMatchesTheModel) {
  Model m = load_model(source_path("models/j85_95.json"));
  SimulatorOptions opt;
  opt.noise = false;
  const double h = 1e-3;
  for (int in : {0, 2, 3}) {
    for (double f : {0.2, 2.0, 10.0}) {
      const double w = 2 * std::numbers::pi * f;
      const size_t settle = size_t(std::ceil(30.0 / h)),
                   n = size_t(std::round(std::max(10.0, 10 * f) / f / h));
      const double amp = 0.02 * m.inputs[in].full_scale;
      SimRun r = run_sine(m, opt, in, f, amp, settle + n);
      std::vector<double> u(settle + n);
      for (size_t k = 0; k < u.size(); ++k) u[k] = amp * std::sin(w * k * h);
      Complex uph = sine_phasor(u, w, h, settle, n);
      // position channel
      Complex g = sine_phasor(r.ch[in], w, h, settle, n) / uph, want = m.actuator_response(in, w);
      EXPECT_NEAR(std::abs(g) / std::abs(want), 1.0, 1e-3) << m.inputs[in].name << " " << f;
      EXPECT_NEAR(wrap_deg(std::arg(g / want) * 180 / std::numbers::pi), 0.0, 0.1) << f;
      for (size_t o = 0; o < m.outputs.size(); ++o) {
        if (!m.path(m.outputs[o].name, m.inputs[in].name)) continue;
        Complex go = sine_phasor(r.ch[m.inputs.size() + o], w, h, settle, n) / uph;
        Complex wo = m.command_to_output(int(o), in, w);
        EXPECT_NEAR(std::abs(go) / std::abs(wo), 1.0, 1e-3)
            << m.outputs[o].name << "/" << m.inputs[in].name << " " << f;
        EXPECT_NEAR(wrap_deg(std::arg(go / wo) * 180 / std::numbers::pi), 0.0, 0.1)
            << m.outputs[o].name << "/" << m.inputs[in].name << " " << f;
      }
    }
  }
}

TEST(Simulator, BacklashActuatorFollowsItsDescribingFunction) {
  // Identity actuator tf, backlash only: position/command = N(A) at low frequency.
  Tf unit;
  Model m = fralab::testing::siso_model(unit, &unit);
  m.inputs[0].nonlinearity.push_back({NonlinearityKind::kHysteresis, 0.8});
  SimulatorOptions opt;
  opt.noise = false;
  const double f = 0.5, w = 2 * std::numbers::pi * f, h = 1e-3;
  SimRun r = run_sine(m, opt, 0, f, 1.0, 8000);
  std::vector<double> u(8000);
  for (size_t k = 0; k < u.size(); ++k) u[k] = std::sin(w * k * h);
  Complex g = sine_phasor(r.ch[0], w, h, 4000, 4000) / sine_phasor(u, w, h, 4000, 4000);
  EXPECT_NEAR(std::abs(g - backlash_describing_function(1.0, 0.8)), 0.0, 2e-3);
}

TEST(Simulator, SameSeedSameSamplesAndNoiseHasItsRms) {
  Model m = load_model(source_path("models/j85_95.json"));
  SimulatorOptions opt;
  opt.seed = 42;
  SimRun a = run_sine(m, opt, 0, 1.0, 10.0, 20000), b = run_sine(m, opt, 0, 1.0, 10.0, 20000);
  EXPECT_EQ(a.ch, b.ch);
  opt.seed = 43;
  SimRun c = run_sine(m, opt, 0, 1.0, 10.0, 20000);
  EXPECT_NE(a.ch[4], c.ch[4]);
  // Noise alone: IGV position, no excitation on it, nothing drives it.
  SimulatorOptions quiet = opt;
  quiet.noise = false;
  SimRun clean = run_sine(m, quiet, 0, 1.0, 10.0, 20000);
  double s2 = 0;
  for (size_t k = 0; k < 20000; ++k) s2 += std::pow(c.ch[3][k] - clean.ch[3][k], 2);
  EXPECT_NEAR(std::sqrt(s2 / 20000) / m.inputs[3].noise_rms, 1.0, 0.03);
}

TEST(Simulator, NanCommandIsAnErrorNamingInputAndSample) {
  Model m = load_model(source_path("models/j85_95.json"));
  Simulator sim(m, SimulatorOptions{});
  std::vector<double> u = {1504.0, 115.0, 0.115, std::nan("")}, y(sim.n_channels());
  try {
    sim.step(u.data(), y.data());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::HasSubstr("input IGV at sample 0")) << e.what();
  }
}

TEST(Simulator, MeasurementCouplingAddsTheOutputToThePositionChannel) {
  Tf path;
  path.gain = 2.0;
  path.poles = {Root::Real(-5.0)};
  Model m = fralab::testing::siso_model(path);
  m.inputs[0].measurement_coupling.push_back({"y", -0.5});
  SimulatorOptions opt;
  opt.noise = false;
  SimRun r = run_sine(m, opt, 0, 1.0, 1.0, 3000);
  for (size_t k = 0; k < 3000; k += 97) {
    double u = std::sin(2 * std::numbers::pi * k * 1e-3);
    EXPECT_NEAR(r.ch[0][k], u - 0.5 * r.ch[1][k], 1e-12);
  }
}
