#include "fralab/identify/state_model.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace fralab;

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
