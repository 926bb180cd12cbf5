// Identification speed: every transfer function of the report (Tables 4-23, the 57 of models/:
// actuators and paths at 70/85/95 %) fitted from 0.05-100 Hz data, 10 points per decade, 2 % noise;
// one order-3 fit from 100 points; and the smallest right singular vector of an SK iteration's
// triangular factor (null_vector.h) against the JacobiSVD it replaced, at denominator orders n;
// a pole set (pole_set_fit.h) of a 4000-point curve of ten light modes; and the impact-hammer
// accelerance of tests/data/realdata with default options.
#include <benchmark/benchmark.h>

#include <complex>
#include <numbers>
#include <random>

#include "fralab/identify/null_vector.h"
#include "fralab/identify/pole_set_fit.h"
#include "fralab/identify/readers.h"
#include "fralab/identify/tfns.h"
#include "fralab/plant/model.h"
#include "test_util.h"

using namespace fralab;

static void BM_ReportCampaignFits(benchmark::State& state) {
  std::vector<std::vector<FrdPoint>> data;
  for (int op : {70, 85, 95}) {
    Model m =
        load_model(std::string(FRALAB_SOURCE_DIR) + "/models/j85_" + std::to_string(op) + ".json");
    for (const auto& in : m.inputs)
      data.push_back(fralab::testing::tf_points(*in.actuator, 0.05, 100, 10, 0.02, 3));
    for (const auto& p : m.paths)
      data.push_back(fralab::testing::tf_points(p.tf, 0.05, 100, 10, 0.02, 3));
  }
  for (auto _ : state) {
    for (const auto& d : data) benchmark::DoNotOptimize(fit_tf(d, FitOptions{}).tf.gain);
  }
  state.counters["fits"] = double(data.size());
}
BENCHMARK(BM_ReportCampaignFits)->Unit(benchmark::kMillisecond);

static void BM_Order3Fit100Points(benchmark::State& state) {
  Tf t;
  t.gain = 2.86;
  t.zeros = {Root::Real(192)};
  t.poles = {Root::Real(-2.86), Root::Real(-76.7), Root::Real(-260)};
  auto d = fralab::testing::tf_points(t, 0.05, 100, 30, 0.02, 3);  // 100 points
  FitOptions o;
  o.delay = FitOptions::Delay::kNone;
  for (auto _ : state) benchmark::DoNotOptimize(fit_tf(d, o).tf.gain);
  state.counters["points"] = double(d.size());
}
BENCHMARK(BM_Order3Fit100Points)->Unit(benchmark::kMicrosecond);

// Ten modes, zeta 2e-4 .. 2e-3, two of them 0.5 % apart, 4000 lines from 20 to 1000 Hz, noise of
// known sigma (pole_set_fit_test's structure).
static void BM_PoleSet10Modes4000Points(benchmark::State& state) {
  const double f[] = {90, 210, 300, 301.5, 420, 515, 640, 700, 820, 930};
  std::vector<double> w;
  std::vector<std::complex<double>> g;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> nd(0, std::sqrt(0.5));
  for (int i = 0; i < 4000; ++i) {
    const double x = 2 * std::numbers::pi * (20 + 980.0 * i / 3999);
    std::complex<double> v = 0;
    for (int k = 0; k < 10; ++k) {
      const double wn = 2 * std::numbers::pi * f[k], z = 2e-4 * std::pow(10.0, k % 3 / 2.0);
      v += 1e4 * (1 + 0.3 * k) / std::complex<double>(wn * wn - x * x, 2 * z * wn * x);
    }
    w.push_back(x);
    g.push_back(v + std::complex<double>(nd(rng), nd(rng)) * 1e-3);
  }
  const std::vector<double> W(w.size(), 1e6);
  int order = 0;
  for (auto _ : state) order = fit_pole_set(w, {g}, {W}).order;
  state.counters["poles"] = order;
}
BENCHMARK(BM_PoleSet10Modes4000Points)->Unit(benchmark::kMillisecond);

static void BM_ImpactHammerDefaultFit(benchmark::State& state) {
  const auto d = read_frd_csv(std::string(FRALAB_SOURCE_DIR) +
                              "/tests/data/realdata/pyfrf_impact_hammer/h1_accelerance.csv")
                     .points;
  for (auto _ : state) benchmark::DoNotOptimize(fit_tf(d, FitOptions{}).tf.gain);
  state.counters["points"] = double(d.size());
}
BENCHMARK(BM_ImpactHammerDefaultFit)->Unit(benchmark::kMillisecond)->Iterations(1);

// An SK iteration's (n+1) x (n+1) factor: of a 60-row matrix with columns graded over 8 decades.
static Eigen::MatrixXd sk_factor(int n) {
  return fralab::testing::graded_triangular_factor(60, n + 1, 7, 8);
}

static void BM_NullVector(benchmark::State& state) {
  const Eigen::MatrixXd R = sk_factor(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(smallest_right_singular_vector(R)(0));
}
BENCHMARK(BM_NullVector)->Arg(4)->Arg(10)->Arg(14)->Unit(benchmark::kMicrosecond);

static void BM_NullVectorJacobiSvd(benchmark::State& state) {
  const Eigen::MatrixXd R = sk_factor(int(state.range(0)));
  for (auto _ : state) {
    Eigen::JacobiSVD<Eigen::MatrixXd, Eigen::NoQRPreconditioner> svd(R, Eigen::ComputeFullV);
    benchmark::DoNotOptimize(svd.matrixV()(0, R.cols() - 1));
  }
}
BENCHMARK(BM_NullVectorJacobiSvd)->Arg(4)->Arg(10)->Arg(14)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
