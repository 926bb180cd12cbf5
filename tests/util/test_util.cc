#include "test_util.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <random>

#include "fralab/acquire/acquisition.h"
#include "fralab/analyze/pair_analyzer.h"
#include "fralab/core/text.h"
#include "fralab/plant/lockstep.h"

namespace fralab::testing {

std::string source_path(const std::string& rel) {
  return std::string(FRALAB_TEST_SOURCE_DIR) + "/" + rel;
}

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

TapeRun simulate_tape(const Model& m, const std::vector<std::string>& excite,
                      const SteppedSineOptions& so, bool noise, uint64_t seed, int block,
                      double amplitude_pct, const std::string& excitation) {
  AcquireOptions o;
  for (const auto& e : excite) o.inputs += (o.inputs.empty() ? "" : ",") + e;
  o.band = lossless(so.f_lo_hz) + ":" + lossless(so.f_hi_hz);
  // "multisine:zippered" / "multisine:orthogonal": the multisine design too.
  const auto colon = excitation.find(':');
  o.excitation = excitation_from_string(excitation.substr(0, colon));
  if (colon != std::string::npos)
    o.multisine_design = multisine_design_from_string(excitation.substr(colon + 1));
  o.points_per_decade = so.points_per_decade;
  o.amplitude_pct = amplitude_pct;
  o.min_cycles = so.min_cycles;
  o.min_integrate_s = so.min_integrate_s;
  o.sample_rate_hz = so.sample_rate_hz;
  o.slowest_time_constant_s = so.slowest_time_constant_s;
  o.block = block;
  return simulate_campaign(m, o, noise, seed);
}

AcquireOptions random_phase_multisine(const std::string& band, int points_per_decade,
                                      double amplitude_pct, int realisations) {
  AcquireOptions o;
  o.band = band;
  o.excitation = Excitation::kMultisine;
  o.points_per_decade = points_per_decade;
  o.amplitude_pct = amplitude_pct;
  o.min_cycles = 2;
  o.realisations = realisations;
  o.multisine_phases = "random";
  return o;
}

AcquireOptions lab_multisine() {
  AcquireOptions o;
  o.band = "0.1:20";
  o.points_per_decade = 5;
  o.excitation = Excitation::kMultisine;
  o.min_cycles = 2;
  return o;
}

TapeRun simulate_campaign(const Model& m, const AcquireOptions& given, bool noise, uint64_t seed) {
  AcquireOptions o = given;
  o.block = block_samples(m, o);  // as fralab-acquire sizes it
  const std::unique_ptr<Campaign> camp = make_campaign(m, o, "test");
  SimulatorOptions opt;
  opt.sample_rate_hz = o.sample_rate_hz;
  opt.noise = noise;
  opt.seed = seed;
  LockstepPlant plant(m, opt, "test");
  TapeRun r;
  // The adaptive stepped sine decides as fralab-acquire does (acquisition_node.h): before a block
  // at or after the pending decision's sample goes out.
  const std::unique_ptr<AutoIntegrator> ai = make_auto_integrator(*camp, m, o);
  for (int64_t seq = 0; seq < command_block_count(*camp, o.block); ++seq) {
    while (ai && ai->decision_sample() >= 0 && seq * o.block >= ai->decision_sample())
      if (!ai->decide()) throw std::logic_error("adaptive: the tape of a decision is missing");
    if (seq >= command_block_count(*camp, o.block)) break;
    r.blocks.push_back(plant.advance(command_block(*camp, seq, o.block, o.sample_rate_hz, "test")));
    if (ai) ai->on_block(r.blocks.back());
  }
  r.events = camp->events();
  if (ai) r.adaptive = ai->results();
  return r;
}

std::vector<Frd> analyse_run(const TapeRun& r, const std::vector<std::string>& pairs) {
  std::vector<Frd> out;
  for (const std::string& pair : pairs) {
    PairAnalyzer a(pair);
    for (const auto& e : r.events) a.on_status(e);
    for (const auto& b : r.blocks) a.on_block(b);
    a.flush();
    out.push_back(a.frd());
  }
  return out;
}

std::vector<FrdPoint> tf_points(const Tf& tf, double f_lo, double f_hi, int per_decade,
                                double rel_noise, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::normal_distribution<double> n(0.0, std::sqrt(0.5));
  const int k = int(std::round(std::log10(f_hi / f_lo) * per_decade));
  std::vector<FrdPoint> out;
  for (int i = 0; i <= k; ++i) {
    const double w = 2 * std::numbers::pi * f_lo * std::pow(10.0, double(i) / per_decade);
    std::complex<double> v = tf.at(w);
    const double s = rel_noise * std::abs(v);
    if (rel_noise > 0) v += std::complex<double>(n(g), n(g)) * s;
    FrdPoint p;
    p.w = w;
    p.mag = std::abs(v);
    p.phase_deg = std::arg(v) * 180 / std::numbers::pi;
    if (rel_noise > 0) p.sigma = s;
    out.push_back(p);
  }
  return out;
}

double worst_root_error(const std::vector<Root>& truth, const std::vector<Root>& fit, double w_lo,
                        double w_hi) {
  double worst = 0;
  for (const Root& t : truth) {
    const double wt = t.pair ? t.wn : std::abs(t.real);
    if (wt < w_lo || wt > w_hi) continue;
    std::complex<double> lt = t.locations()[0];
    if (lt.imag() < 0) lt = std::conj(lt);
    double best = INFINITY;
    for (const Root& f : fit) {
      if (f.pair != t.pair) continue;
      std::complex<double> lf = f.locations()[0];
      if (lf.imag() < 0) lf = std::conj(lf);
      best = std::min(best, std::abs(lf - lt) / std::abs(lt));
    }
    worst = std::max(worst, best);
  }
  return worst;
}

double wrap_deg(double d) {
  while (d > 180.0) d -= 360.0;
  while (d <= -180.0) d += 360.0;
  return d;
}

Eigen::MatrixXd graded_triangular_factor(int rows, int k, unsigned seed, double decades,
                                         bool dependent, double perturb) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  Eigen::MatrixXd A(rows, k);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < k; ++j) A(i, j) = n01(rng);
  if (dependent) {
    Eigen::VectorXd c(k - 1);
    for (int j = 0; j < k - 1; ++j) c(j) = n01(rng);
    A.col(k - 1) = A.leftCols(k - 1) * c;
    for (int i = 0; i < rows; ++i) A(i, k - 1) += perturb * n01(rng);
  }
  for (int j = 0; j < k; ++j) A.col(j) *= std::pow(10.0, -decades * j / std::max(1, k - 1));
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  return qr.matrixQR().topRows(k).triangularView<Eigen::Upper>();
}

double root_error(const Root& fit, const Root& want) {
  if (fit.pair != want.pair) return INFINITY;
  auto upper = [](const Root& r) {
    const std::complex<double> l = r.locations()[0];
    return l.imag() < 0 ? std::conj(l) : l;
  };
  return std::abs(upper(fit) - upper(want)) / std::abs(upper(want));
}

double worst_error(const std::vector<Root>& fit, const std::vector<Root>& want) {
  if (fit.size() != want.size()) return INFINITY;
  double worst = 0;
  for (size_t i = 0; i < fit.size(); ++i) worst = std::max(worst, root_error(fit[i], want[i]));
  return worst;
}

}  // namespace fralab::testing
