#include "test_util.h"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>

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

double wrap_deg(double d) {
  while (d > 180.0) d -= 360.0;
  while (d <= -180.0) d += 360.0;
  return d;
}

}  // namespace fralab::testing
