#include "fralab/identify/state_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fralab/plant/model.h"
#include "test_util.h"

using namespace fralab;
using fralab::testing::source_path;
using fralab::testing::tf_points;

namespace {

// Truth: 4 states, inputs a, b, outputs y, z. Pole -2 everywhere, pole -10 only from input a,
// the pair 30 rad/s (zeta 0.3) only into output z.
struct Truth {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(4, 4), B = Eigen::MatrixXd(4, 2),
                  C = Eigen::MatrixXd(2, 4);
  Truth() {
    A(0, 0) = -2;
    A(1, 1) = -10;
    const double s = -0.3 * 30, w = 30 * std::sqrt(1 - 0.09);
    A(2, 2) = s;
    A(2, 3) = -w;
    A(3, 2) = w;
    A(3, 3) = s;
    B << 1.0, 0.5, 2.0, 0.0, 5.0, -3.0, 1.0, 2.0;
    C << 1.5, 0.7, 0.0, 0.0, -1.0, 0.4, 20.0, 10.0;
  }
  std::complex<double> at(int o, int i, double w) const {
    Eigen::MatrixXcd M = std::complex<double>(0, w) * Eigen::MatrixXcd::Identity(4, 4) -
                         A.cast<std::complex<double>>();
    Eigen::VectorXcd x = M.partialPivLu().solve(B.col(i).cast<std::complex<double>>());
    return (C.row(o).cast<std::complex<double>>() * x)(0);
  }
};

}  // namespace

TEST(StateModel, OrderIsTheNumberOfDistinctPolesAndTheModelMatchesTheData) {
  Truth t;
  const std::vector<std::string> ins = {"a", "b"}, outs = {"y", "z"};
  std::vector<MatrixEntry> entries;
  std::map<std::string, std::vector<FrdPoint>> data;
  for (int o = 0; o < 2; ++o) {
    for (int i = 0; i < 2; ++i) {
      std::vector<FrdPoint> pts;
      for (int k = 0; k <= 40; ++k) {
        FrdPoint p;
        p.w = 0.1 * std::pow(10.0, k / 10.0);
        auto g = t.at(o, i, p.w);
        p.mag = std::abs(g);
        p.phase_deg = std::arg(g) * 180 / M_PI;
        pts.push_back(p);
      }
      FitOptions opt;
      opt.c_n = 1e-12;
      opt.delay = FitOptions::Delay::kNone;
      FitResult r = fit_tf(pts, opt);
      ASSERT_EQ(r.status, FitResult::Status::kConverged) << r.message;
      entries.push_back({ins[i], outs[o], r});
      data[ins[i] + ":" + outs[o]] = pts;
    }
  }
  TransferMatrix m = build_transfer_matrix(entries);
  EXPECT_EQ(m.state_count, 4);  // -2, -10 and the pair
  for (const auto& c : m.clusters) {
    if (!c.mean.pair && std::abs(c.mean.real + 2) < 0.02) {
      EXPECT_EQ(c.scope, "plant");
    }
    if (!c.mean.pair && std::abs(c.mean.real + 10) < 0.1) {
      EXPECT_EQ(c.scope, "input");
      EXPECT_EQ(c.where, "a");
    }
    if (c.mean.pair) {
      EXPECT_EQ(c.scope, "output");
      EXPECT_EQ(c.where, "z");
    }
  }
  StateModel s = build_state_model(m, data);
  EXPECT_EQ(s.order, 4);
  for (double loss : s.rank1_loss) EXPECT_LT(loss, 1e-8);
  EXPECT_LT(s.error, 1e-6);
  for (int o = 0; o < 2; ++o) {
    for (int i = 0; i < 2; ++i) {
      for (double w : {0.3, 3.0, 30.0})
        EXPECT_NEAR(std::abs(s.at(o, i, w) / t.at(o, i, w) - 1.0), 0.0, 1e-6);
    }
  }
}

// The J85's paths at 95 % (models/, Tables 4-23) measured at 2 % noise with their sigma, 0.04-100
// Hz at 10 points per decade; the four pairs the report has no path for (BLD and IGV into P5 and
// DPP3) measured as noise alone. Each path has its own poles: the rotor pole is 2.8-3.5 rad/s
// across the paths and clusters as one, whose residues are then not rank one, in sensors whose
// units differ by 1e4 (DPP3 against P3). The SVD's rank-one factors keep the large residues and
// lose the small sensors' (the factors' fit switched off: 7 paths over 100 chi2 per point, the
// worst 1.4e6); fitted to the data, every path in the model comes back within 6 chi2 per point
// (its own fit about 1; measured 0.8-4.9) but IGV:P3, whose own rotor pole (3.25 rad/s) shares
// the 3.38 rad/s state with three other paths: one rank-one residue matrix cannot hold the four
// (measured 171 after 500 sweeps, 141 after 20000). The paths with no response stay within their
// noise, and each path's error is measured on its clear points only.
TEST(StateModel, FittedFactorsReproduceEveryJ85PathWithinItsNoise) {
  const Model m = load_model(source_path("models/j85_95.json"));
  std::vector<MatrixEntry> entries;
  std::map<std::string, std::vector<FrdPoint>> data;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01;
  uint64_t seed = 1;
  for (const auto& in : m.inputs) {
    for (const auto& out : m.outputs) {
      const std::string key = in.name + ":" + out.name;
      std::vector<FrdPoint> pts;
      bool path = false;
      for (const auto& p : m.paths) {
        if (p.input != in.name || p.output != out.name) continue;
        pts = tf_points(p.tf, 0.04, 100, 10, 0.02, seed++);
        path = true;
      }
      if (!path) {  // noise alone, at 1e-3 of the output's largest response to Wf
        double level = 0;
        for (const auto& p : m.paths)
          if (p.output == out.name && p.input == "Wf") level = 1e-3 * std::abs(p.tf.gain);
        pts = tf_points(Tf{}, 0.04, 100, 10, 0.0, 1);
        for (auto& pt : pts) {
          const std::complex<double> e(n01(rng), n01(rng));
          const std::complex<double> g = level * e / std::sqrt(2.0);
          pt.mag = std::abs(g);
          pt.phase_deg = std::arg(g) * 180 / M_PI;
          pt.sigma = level;
        }
      }
      FitResult r = fit_tf(pts, FitOptions{});
      if (!path) {
        ASSERT_EQ(r.status, FitResult::Status::kNoResponse) << key << ": " << r.message;
      }
      entries.push_back({in.name, out.name, r});
      data[key] = pts;
    }
  }
  const TransferMatrix tm = build_transfer_matrix(entries);
  StateModelOptions svd_only;
  svd_only.max_sweeps = 0;
  const StateModel before = build_state_model(tm, data, svd_only);
  const StateModel s = build_state_model(tm, data);
  EXPECT_EQ(s.order, tm.state_count);
  double worst_before = 0;
  for (const auto& [k, c] : before.path_check)
    if (c.fit_status == "converged") worst_before = std::max(worst_before, c.chi2_per_point);
  EXPECT_GT(worst_before, 100.0);  // the case this test is about: not rank one
  EXPECT_LT(s.fit_chi2, s.start_chi2);
  int in_model = 0;
  for (const auto& [k, c] : s.path_check) {
    SCOPED_TRACE(k);
    EXPECT_EQ(c.points, 35);
    if (c.fit_status == "converged") {
      ++in_model;
      EXPECT_EQ(s.path_error.at(k), c.error);
      if (k == "IGV:P3") {  // what one rank-one cluster cannot hold (measured: 171, error 0.31)
        EXPECT_LT(c.chi2_per_point, 300.0);
        EXPECT_LT(c.error, 0.5);  // the SVD's factors: 1.4e6 and 3.2
        continue;
      }
      EXPECT_LT(c.chi2_per_point, 6.0) << "its own fit: " << c.fit_chi2_per_point;
      EXPECT_LT(c.error, 0.06);  // 2 % noise on its clear points
    } else if (c.fit_status == "no_response") {
      EXPECT_EQ(c.clear, 0);
      EXPECT_LT(c.error, 0);  // none: every point is noise
      EXPECT_FALSE(s.path_error.count(k));
      EXPECT_LT(c.chi2_per_point, 2.0);  // the model stays within the noise
    }
  }
  EXPECT_EQ(in_model, 16);
  EXPECT_LT(s.error, 0.1);  // the SVD's factors: 1.28
}
