#include "test_util.h"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

#include "fralab/acquire/model_info.h"
#include "fralab/plant/simulator.h"

namespace fralab::testing {

std::string source_path(const std::string& rel) { return std::string(FRALAB_TEST_SOURCE_DIR) + "/" + rel; }

std::complex<double> sine_phasor(const std::vector<double>& x, double w, double h, size_t start,
                                 size_t n) {
  Eigen::MatrixXd a(n, 3);
  Eigen::VectorXd y(n);
  for (size_t k = 0; k < n; ++k) {
    double t = double(start + k) * h;
    a(k, 0) = 1.0;
    a(k, 1) = std::sin(w * t);
    a(k, 2) = std::cos(w * t);
    y(k) = x[start + k];
  }
  Eigen::Vector3d c = a.colPivHouseholderQr().solve(y);
  return {c(1), c(2)};
}

Model siso_model(const Tf& path, const Tf* actuator, const Tf* sensor, double noise_rms) {
  Model m;
  m.name = "siso";
  m.source = "test";
  ModelInput in;
  in.name = "u";
  in.units = "1";
  in.full_scale = 1.0;
  if (actuator) in.actuator = *actuator;
  m.inputs.push_back(in);
  ModelOutput out;
  out.name = "y";
  out.units = "1";
  out.noise_rms = noise_rms;
  if (sensor) out.sensor = *sensor;
  m.outputs.push_back(out);
  m.paths.push_back(ModelPath{"y", "u", path, Json::object()});
  return m;
}

TapeRun simulate_tape(const Model& m, const std::vector<std::string>& excite, const SteppedSineOptions& so,
                      bool noise, uint64_t seed, int block, double amplitude_pct) {
  std::string csv;
  for (const auto& e : excite) csv += (csv.empty() ? "" : ",") + e;
  SteppedSineCampaign camp(campaign_inputs(m, amplitude_pct), select_inputs(m, csv), plan_stepped_sine(so),
                           so.sample_rate_hz, "test");
  SimulatorOptions opt;
  opt.sample_rate_hz = so.sample_rate_hz;
  opt.noise = noise;
  opt.seed = seed;
  Simulator sim(m, opt);
  TapeRun r;
  r.events = camp.events();
  std::vector<std::vector<double>> cmd;
  std::vector<double> ph, fr, u(m.inputs.size()), y(sim.n_channels());
  const int ni = int(m.inputs.size());
  for (int64_t s0 = 0, seq = 0; s0 < camp.total_samples(); s0 += block, ++seq) {
    const int n = int(std::min<int64_t>(block, camp.total_samples() - s0));
    camp.fill(s0, n, cmd, ph, fr);
    Block b;
    b.run_id = "test";
    b.seq = seq;
    b.start_sample = s0;
    b.sample_rate_hz = so.sample_rate_hz;
    b.n_samples = n;
    b.final_block = s0 + n >= camp.total_samples();
    for (const auto& in : m.inputs) b.channels.push_back("u_" + in.name);
    for (const auto& c : sim.channel_names()) b.channels.push_back(c);
    b.samples.resize(b.channels.size() * n);
    for (int k = 0; k < n; ++k) {
      for (int i = 0; i < ni; ++i) u[i] = cmd[i][k];
      sim.step(u.data(), y.data());
      for (int i = 0; i < ni; ++i) b.at(i, k) = u[i];
      for (size_t c = 0; c < y.size(); ++c) b.at(ni + int(c), k) = y[c];
    }
    r.blocks.push_back(std::move(b));
  }
  return r;
}

double wrap_deg(double d) {
  while (d > 180.0) d -= 360.0;
  while (d <= -180.0) d += 360.0;
  return d;
}

}  // namespace fralab::testing
