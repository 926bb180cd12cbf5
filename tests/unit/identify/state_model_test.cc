#include "fralab/identify/state_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "fralab/identify/fit_io.h"
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

// A transfer matrix with shared poles: G(s) = sum_k R_k / (s - p_k) (+ conj(R_k) / (s - conj p_k)
// for a pair), whose minimal realisation has rank(R_k) states per real pole, twice that per pair
// (Gilbert). Points at 10 per decade over 0.1-1000 rad/s, noise rel * |G| with that sigma.
struct SharedPoles {
  std::vector<Root> poles;
  std::vector<Eigen::MatrixXcd> R;
  std::complex<double> at(int o, int i, double w) const {
    std::complex<double> g = 0;
    for (size_t k = 0; k < poles.size(); ++k) {
      std::complex<double> p = poles[k].locations()[0];
      if (p.imag() < 0) p = std::conj(p);
      const std::complex<double> s(0, w);
      g += R[k](o, i) / (s - p);
      if (poles[k].pair) g += std::conj(R[k](o, i)) / (s - std::conj(p));
    }
    return g;
  }
  // Each path fitted, the transfer matrix of the fits and the measured curves.
  TransferMatrix measure(double rel, uint64_t seed,
                         std::map<std::string, std::vector<FrdPoint>>* data) const {
    const int no = int(R[0].rows()), ni = int(R[0].cols());
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> n(0.0, std::sqrt(0.5));
    std::vector<MatrixEntry> entries;
    for (int o = 0; o < no; ++o) {
      for (int i = 0; i < ni; ++i) {
        std::vector<FrdPoint> pts;
        for (int q = 0; q <= 40; ++q) {
          FrdPoint pt;
          pt.w = 0.1 * std::pow(10.0, q / 10.0);
          std::complex<double> g = at(o, i, pt.w);
          if (rel > 0) g += std::complex<double>(n(rng), n(rng)) * rel * std::abs(g);
          pt.mag = std::abs(g);
          pt.phase_deg = std::arg(g) * 180 / M_PI;
          pt.sigma = rel * std::abs(at(o, i, pt.w));
          pts.push_back(pt);
        }
        FitOptions opt;
        opt.delay = FitOptions::Delay::kNone;
        if (rel == 0) opt.c_n = 1e-12;
        const std::string in = "u" + std::to_string(i), out = "y" + std::to_string(o);
        entries.push_back({in, out, fit_tf(pts, opt)});
        (*data)[in + ":" + out] = pts;
      }
    }
    return build_transfer_matrix(entries);
  }
};

// The rank of the cluster whose mean is nearest pole p (-1: none).
int rank_at(const TransferMatrix& m, const StateModel& s, const Root& p) {
  int best = -1;
  double bd = 0.05;
  for (size_t k = 0; k < m.clusters.size(); ++k) {
    const Root& c = m.clusters[k].mean;
    if (c.pair != p.pair) continue;
    const double d = c.pair ? std::abs(c.wn / p.wn - 1) : std::abs(c.real / p.real - 1);
    if (d < bd) bd = d, best = s.rank[k];
  }
  return best;
}

}  // namespace

// Gilbert's realisation on a known answer: a 2 x 2 plant whose pole at -2 has a residue matrix of
// rank two (no rank-one product can hold it) and whose pole at -10 has one of rank one. The
// minimal order is 3: two states at -2, one at -10; the model then matches the noise-free data.
// Restricted to rank one (the report's recipe), it misses them.
TEST(StateModel, AClusterWhoseResiduesAreRankTwoGetsTwoStates) {
  SharedPoles t;
  t.poles = {Root::Real(-2), Root::Real(-10)};
  Eigen::MatrixXcd r2(2, 2), r1(2, 2);
  r2 << 1.0, 0.5, 0.3, 2.0;    // rank two
  r1 << 2.0, -2.0, 1.0, -1.0;  // (2, 1)^T (1, -1): rank one
  t.R = {r2, r1};
  std::map<std::string, std::vector<FrdPoint>> data;
  const TransferMatrix m = t.measure(0.0, 1, &data);
  ASSERT_EQ(m.state_count, 2);
  const StateModel s = build_state_model(m, data);
  EXPECT_EQ(s.order, 3);
  EXPECT_EQ(rank_at(m, s, t.poles[0]), 2);
  EXPECT_EQ(rank_at(m, s, t.poles[1]), 1);
  for (int o = 0; o < 2; ++o)
    for (int i = 0; i < 2; ++i)
      for (double w : {0.3, 3.0, 30.0})
        EXPECT_NEAR(std::abs(s.at(o, i, w) / t.at(o, i, w) - 1.0), 0.0, 1e-6);
  EXPECT_LT(s.error, 1e-6);
  StateModelOptions rank_one;
  rank_one.max_rank = 1;
  const StateModel s1 = build_state_model(m, data, rank_one);
  EXPECT_EQ(s1.order, 2);
  EXPECT_GT(s1.error, 0.05);
}

// Randomised: 20 plants of 3 outputs (units 1, 1e-3 and 100) and 3 inputs with poles at -1 and -8
// and a pair at 40 rad/s (zeta 0.2), each pole's residue matrix of a random rank 1-3 (orthonormal
// factors, singular values 0.5-1), measured at 1 % noise with sigma. Each cluster's rank must come
// back as drawn in at least 90 % of the plants, and every path within 2 chi2 per point.
TEST(StateModel, RandomSharedPolesComeBackAtTheirResidueRanks) {
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> rank_of(1, 3);
  std::uniform_real_distribution<double> sv(0.5, 1.0);
  std::normal_distribution<double> n01;
  const Eigen::Vector3d units(1.0, 1e-3, 100.0);
  int plants_right = 0, plants = 20;
  for (int d = 0; d < plants; ++d) {
    SCOPED_TRACE("plant " + std::to_string(d));
    SharedPoles t;
    t.poles = {Root::Real(-1), Root::Real(-20), Root::Pair(200, 0.2)};
    std::vector<int> ranks;
    for (const Root& p : t.poles) {
      const int r = rank_of(rng);
      ranks.push_back(r);
      auto draw = [&] {
        Eigen::MatrixXcd a(3, 3);
        for (int i = 0; i < 9; ++i)
          a(i) = p.pair ? std::complex<double>(n01(rng), n01(rng)) : n01(rng);
        return Eigen::HouseholderQR<Eigen::MatrixXcd>(a).householderQ() *
               Eigen::MatrixXcd::Identity(3, 3);
      };
      const Eigen::MatrixXcd U = draw(), V = draw();
      Eigen::MatrixXcd R = Eigen::MatrixXcd::Zero(3, 3);
      for (int l = 0; l < r; ++l) R += sv(rng) * U.col(l) * V.col(l).adjoint();
      // A real pole's residues are real; each pole's scaled by its frequency (a gain of order 1).
      if (!p.pair) R = R.real().cast<std::complex<double>>().eval();
      R *= p.pair ? p.wn : -p.real;
      t.R.push_back(units.cast<std::complex<double>>().asDiagonal() * R);
    }
    std::map<std::string, std::vector<FrdPoint>> data;
    const TransferMatrix m = t.measure(0.01, 100 + d, &data);
    const StateModel s = build_state_model(m, data);
    bool right = true;
    for (size_t k = 0; k < t.poles.size(); ++k)
      right = right && rank_at(m, s, t.poles[k]) == ranks[k];
    plants_right += right;
    for (const auto& [key, c] : s.path_check) {
      if (c.fit_status != "converged") continue;
      EXPECT_LT(c.chi2_per_point, 2.0) << key << ", its own fit " << c.fit_chi2_per_point;
    }
  }
  EXPECT_GE(plants_right, 18) << "of " << plants;
}

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
// worst 1.4e6); fitted to the data at rank one, IGV:P3, whose own rotor pole (3.25 rad/s) shares
// the 3.38 rad/s state with three other paths, stays at 171 (141 after 20000 sweeps). With a
// cluster's rank raised where the data need it (Gilbert), two more states and every path in the
// model within 3 chi2 per point (measured 0.72-2.34; its own fit 0.6-1.2). The paths with no
// response stay within their noise, and each path's error is measured on its clear points only.
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
  StateModelOptions rank_one;
  rank_one.max_rank = 1;
  const StateModel r1 = build_state_model(tm, data, rank_one);
  const StateModel s = build_state_model(tm, data);
  EXPECT_EQ(r1.order, tm.state_count);
  // Gilbert: the states are the clusters' ranks (measured: two real clusters at rank two).
  int states = 0;
  for (size_t k = 0; k < tm.clusters.size(); ++k) states += s.rank[k] * tm.clusters[k].mean.order();
  EXPECT_EQ(s.order, states);
  EXPECT_GT(s.order, tm.state_count);
  EXPECT_LE(s.order, tm.state_count + 4);
  EXPECT_GT(r1.path_check.at("IGV:P3").chi2_per_point, 100.0);  // rank one (measured 171)
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
      EXPECT_LT(c.chi2_per_point, 3.0) << "its own fit: " << c.fit_chi2_per_point;
      EXPECT_LT(c.error, 0.04);  // 2 % noise on its clear points
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

// A single-input plant whose every path reached the maximum order (the auto campaign's curves of
// a random plant, one input and three outputs, kept in tests/data/single_input_max_order): no
// pole is clustered, so the factors' fit has nothing to solve for. The identifier's whole chain
// (fit_and_write) ends with every file written and an empty state model that still checks each
// path against its data, where a decomposition of an empty matrix crashed it.
TEST(StateModel, ASingleInputRunWithNoConvergedFitGivesAnEmptyModelNotACrash) {
  std::vector<Frd> curves;
  for (const char* stem : {"Bypass_Pin", "Bypass_Speed", "Bypass_Torque", "u_Bypass_Bypass"})
    curves.push_back(load_frd(source_path("tests/data/single_input_max_order/") + stem + ".json"));
  const std::string dir = ::testing::TempDir() + "single_input_max_order";
  std::filesystem::remove_all(dir);
  FitOptions o;
  const std::vector<FitResult> fits = fit_and_write(curves, o, dir, "single input");
  ASSERT_EQ(fits.size(), 4u);
  for (const char* stem : {"Bypass_Pin", "Bypass_Speed", "Bypass_Torque", "u_Bypass_Bypass"})
    EXPECT_TRUE(std::filesystem::exists(dir + "/tf/" + stem + ".json")) << stem;
  const Json tm = json_load_file(dir + "/transfer_matrix.json");
  const Json& sm = tm.at("state_model");
  int converged = 0;
  for (int k = 0; k < 3; ++k) converged += fits[size_t(k)].status == FitResult::Status::kConverged;
  EXPECT_EQ(converged, 0) << "the data no longer reach the shape this test is about";
  EXPECT_EQ(sm.at("order"), 0);
  // Each output path is checked against its data: the empty model's error is the whole response.
  for (const char* pair : {"Bypass:Pin", "Bypass:Speed", "Bypass:Torque"}) {
    ASSERT_TRUE(sm.at("path_check").contains(pair)) << pair;
    EXPECT_GT(sm["path_check"][pair].at("points").get<int>(), 10) << pair;
  }
  std::filesystem::remove_all(dir);
}

// One pole set over the paths (common_pole_matrix): a 3 x 3 plant whose every path has the pair at
// 12 rad/s (zeta 0.05) and the pole at -2, and whose output y2 alone has a sensor lag at -40; 2 %
// noise. Fitted one by one the paths place the shared roots each a little apart; the pole set
// places each once: the pair within 0.5 % and zeta within 5 %, the pole at -2 in every path
// ("plant"), -40 in y2's paths only ("output" y2). Its state model, with the ranks Gilbert's
// realisation finds, holds every path within its noise.
TEST(StateModel, OnePoleSetOverThePathsPlacesEachSharedStateOnce) {
  constexpr double kWnTol = 5e-3, kZetaTol = 0.05, kRealTol = 0.02;
  SharedPoles sp;
  sp.poles = {Root::Real(-2.0), Root::Pair(12.0, 0.05), Root::Real(-40.0)};
  Eigen::MatrixXcd r0(3, 3), r1(3, 3), r2 = Eigen::MatrixXcd::Zero(3, 3);
  r0 << 1.0, 2.0, -1.0, 0.5, 1.0, -0.5, 2.0, -1.0, 1.5;  // rank 2 at most
  r1 << std::complex<double>(1, 3), std::complex<double>(2, 1), std::complex<double>(-1, 2),
      std::complex<double>(0.5, -1), std::complex<double>(1, 1), std::complex<double>(2, -2),
      std::complex<double>(-1, 1), std::complex<double>(3, 1), std::complex<double>(1, 1);
  r2.row(2) << 80.0, -40.0, 60.0;  // the sensor of y2
  sp.R = {r0, r1, r2};
  std::map<std::string, std::vector<FrdPoint>> data;
  const TransferMatrix m = sp.measure(0.02, 11, &data);
  const CommonPoleMatrix c = common_pole_matrix(m, data);
  ASSERT_NE(c.fit.status, PoleSetFit::Status::kFailed) << c.fit.message;
  EXPECT_EQ(c.paths.size(), 9u);
  const PoleCluster* pair = nullptr;
  const PoleCluster* slow = nullptr;
  const PoleCluster* sensor = nullptr;
  for (const PoleCluster& k : c.matrix.clusters) {
    if (k.mean.pair && std::abs(k.mean.wn / 12 - 1) < 0.05) pair = &k;
    if (!k.mean.pair && std::abs(k.mean.real / -2 - 1) < 0.1) slow = &k;
    if (!k.mean.pair && std::abs(k.mean.real / -40 - 1) < 0.1) sensor = &k;
  }
  ASSERT_NE(pair, nullptr) << c.fit.message;
  ASSERT_NE(slow, nullptr) << c.fit.message;
  ASSERT_NE(sensor, nullptr) << c.fit.message;
  EXPECT_NEAR(pair->mean.wn / 12, 1.0, kWnTol);
  EXPECT_NEAR(pair->mean.zeta / 0.05, 1.0, kZetaTol);
  EXPECT_NEAR(slow->mean.real / -2, 1.0, kRealTol);
  EXPECT_EQ(slow->scope, "plant");
  EXPECT_EQ(pair->scope, "plant");
  EXPECT_EQ(sensor->scope, "output");
  EXPECT_EQ(sensor->where, "y2");
  const StateModel s = build_state_model(c.matrix, data);
  for (const auto& [k, pc] : s.path_check) {
    SCOPED_TRACE(k);
    EXPECT_LT(pc.chi2_per_point, 2.0) << "its own fit: " << pc.fit_chi2_per_point;
  }
}
