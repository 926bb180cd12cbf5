// One pole set for one or several responses, its size found from the data (pole_set_fit.h): the
// modes of a known structure come back where they are, several curves share one pole set, the
// factored form is the same function, and bad grids are refused with a reason.
#include "fralab/identify/pole_set_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include "fralab/core/error.h"

namespace fralab {
namespace {

using C = std::complex<double>;

// A structure's receptance: sum_k a_k / (wk^2 - w^2 + 2 j zeta_k wk w), on a uniform grid.
struct Modes {
  std::vector<double> wn, zeta, amp;
  C at(double w) const {
    C v = 0;
    for (size_t k = 0; k < wn.size(); ++k)
      v += amp[k] / C(wn[k] * wn[k] - w * w, 2 * zeta[k] * wn[k] * w);
    return v;
  }
};

std::vector<double> grid(double lo, double hi, int n) {
  std::vector<double> w;
  for (int i = 0; i < n; ++i) w.push_back(lo + (hi - lo) * i / (n - 1));
  return w;
}

// The fitted pair nearest in frequency to wn (nullptr: none within 1 %).
const C* nearest_pair(const PoleSetFit& f, double wn) {
  const C* best = nullptr;
  for (const C& p : f.poles)
    if (p.imag() > 0 && (!best || std::abs(std::abs(p) - wn) < std::abs(std::abs(*best) - wn)))
      best = &p;
  return best && std::abs(std::abs(*best) / wn - 1) < 0.01 ? best : nullptr;
}

// Ten light modes (zeta 2e-4 .. 2e-3, two of them 0.5 % apart) on 4000 lines with noise of known
// sigma: every mode within 1e-4 in frequency and 5 % in damping, the fit consistent with the noise,
// and no more poles than the modes and a few of the background's (skimming).
TEST(PoleSetFit, TenLightModesComeBackWhereTheyAre) {
  constexpr double kFreqTol = 1e-4, kZetaTol = 0.05;
  Modes m;
  const double f[] = {90, 210, 300, 301.5, 420, 515, 640, 700, 820, 930};
  for (int k = 0; k < 10; ++k) {
    m.wn.push_back(2 * std::numbers::pi * f[k]);
    m.zeta.push_back(2e-4 * std::pow(10.0, k % 3 / 2.0));
    m.amp.push_back(1e4 * (1 + 0.3 * k));
  }
  const auto w = grid(2 * std::numbers::pi * 20, 2 * std::numbers::pi * 1000, 4000);
  std::mt19937_64 rng(1);
  std::normal_distribution<double> nd(0, std::sqrt(0.5));
  const double sigma = 1e-3;
  std::vector<C> g;
  for (double x : w) g.push_back(m.at(x) + C(nd(rng), nd(rng)) * sigma);
  const PoleSetFit r = fit_pole_set(w, {g}, {std::vector<double>(w.size(), 1 / (sigma * sigma))});
  ASSERT_EQ(r.status, PoleSetFit::Status::kAdequate) << r.message;
  for (size_t k = 0; k < m.wn.size(); ++k) {
    const C* p = nearest_pair(r, m.wn[k]);
    ASSERT_NE(p, nullptr) << "mode at " << f[k] << " Hz: " << r.message;
    EXPECT_NEAR(std::abs(*p) / m.wn[k], 1.0, kFreqTol) << f[k] << " Hz";
    EXPECT_NEAR(-p->real() / std::abs(*p) / m.zeta[k], 1.0, kZetaTol) << f[k] << " Hz";
  }
  EXPECT_LE(r.order, 26) << r.message;
}

// Three curves of one structure (three sensors: residues differ, poles are the structure's): one
// pole set holds all three, each curve fitted to its noise, and each curve's factored form is the
// same function as its partial fractions.
TEST(PoleSetFit, SeveralCurvesShareOnePoleSet) {
  constexpr double kFreqTol = 1e-4, kFormTol = 1e-8;
  Modes base;
  base.wn = {2 * std::numbers::pi * 50, 2 * std::numbers::pi * 120, 2 * std::numbers::pi * 200};
  base.zeta = {0.01, 0.003, 0.02};
  const auto w = grid(2 * std::numbers::pi * 10, 2 * std::numbers::pi * 300, 600);
  std::mt19937_64 rng(2);
  std::normal_distribution<double> nd(0, std::sqrt(0.5));
  const double sigma = 1e-4;
  std::vector<std::vector<C>> g(3);
  std::vector<std::vector<double>> W(3, std::vector<double>(w.size(), 1 / (sigma * sigma)));
  const double amps[3][3] = {{1e4, 2e4, -3e4}, {-5e3, 1e4, 4e4}, {2e4, 0, 1e4}};
  for (int c = 0; c < 3; ++c) {
    Modes m = base;
    m.amp.assign(amps[c], amps[c] + 3);
    for (double x : w) g[size_t(c)].push_back(m.at(x) + C(nd(rng), nd(rng)) * sigma);
  }
  const PoleSetFit r = fit_pole_set(w, g, W);
  ASSERT_EQ(r.status, PoleSetFit::Status::kAdequate) << r.message;
  ASSERT_EQ(r.residues.size(), 3u);
  for (double wn : base.wn) {
    const C* p = nearest_pair(r, wn);
    ASSERT_NE(p, nullptr) << wn << ": " << r.message;
    EXPECT_NEAR(std::abs(*p) / wn, 1.0, kFreqTol);
  }
  for (size_t c = 0; c < 3; ++c) {
    EXPECT_LT(r.chi2[c] / double(w.size()), 1.5) << "curve " << c;
    const Tf t = r.to_tf(c);
    for (size_t i = 0; i < w.size(); i += 37)
      EXPECT_LT(std::abs(t.at(w[i]) - r.at(c, w[i])), kFormTol * std::abs(r.at(c, w[i])) + 1e-12)
          << "curve " << c << " at " << w[i];
  }
}

// Curves on grids of their own (an orthogonal multisine gives each input its own lines): one pole
// set from both, each curve's coefficients on its own points.
TEST(PoleSetFit, CurvesOnTheirOwnGridsShareOnePoleSet) {
  constexpr double kFreqTol = 1e-4;
  Modes a, b;
  a.wn = b.wn = {2 * std::numbers::pi * 40, 2 * std::numbers::pi * 90};
  a.zeta = b.zeta = {0.02, 0.005};
  a.amp = {1e4, 3e4};
  b.amp = {-2e4, 1e4};
  const auto wa = grid(2 * std::numbers::pi * 5, 2 * std::numbers::pi * 150, 300);
  const auto wb = grid(2 * std::numbers::pi * 7.3, 2 * std::numbers::pi * 140, 211);
  std::vector<std::vector<C>> g(2);
  for (double x : wa) g[0].push_back(a.at(x));
  for (double x : wb) g[1].push_back(b.at(x));
  const std::vector<std::vector<double>> W = {std::vector<double>(wa.size(), 1e8),
                                              std::vector<double>(wb.size(), 1e8)};
  const PoleSetFit r = fit_pole_set({wa, wb}, g, W);
  ASSERT_NE(r.status, PoleSetFit::Status::kFailed) << r.message;
  for (double wn : a.wn) {
    const C* p = nearest_pair(r, wn);
    ASSERT_NE(p, nullptr) << wn << ": " << r.message;
    EXPECT_NEAR(std::abs(*p) / wn, 1.0, kFreqTol) << r.message;
  }
  for (size_t i = 0; i < wb.size(); i += 23)
    EXPECT_LT(std::abs(r.at(1, wb[i]) - b.at(wb[i])), 1e-6 * std::abs(b.at(wb[i])) + 1e-9);
}

TEST(PoleSetFit, BadGridsAreRefusedWithAReason) {
  const std::vector<C> g = {1, 2, 3, 4, 5};
  const std::vector<double> W(5, 1.0);
  PoleSetFit r = fit_pole_set({1, 2, 2, 3, 4}, {g}, {W});
  EXPECT_EQ(r.status, PoleSetFit::Status::kFailed);
  EXPECT_NE(r.message.find("increasing"), std::string::npos) << r.message;
  r = fit_pole_set({1, 2, 3, 4, 5}, {g, {1, 2}}, {W, W});
  EXPECT_EQ(r.status, PoleSetFit::Status::kFailed);
  EXPECT_NE(r.message.find("curve 1"), std::string::npos) << r.message;
  PoleSetFitOptions o;
  o.max_poles = 0;
  EXPECT_THROW(fit_pole_set({1, 2, 3, 4, 5}, {g}, {W}, o), InputError);
}

}  // namespace
}  // namespace fralab
