// The diagnosis of a structure (diagnose/src/stages/modes.cc, diagnose/baseline.h): modes every
// sensor carries, moved together, come back as one finding each over every pair; a baseline's
// misfit is the simulation's own and not a finding. Synthetic: one force, three accelerometers,
// three light modes with rank-one residues of mixed sign, exact responses with noise of known
// sigma.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <vector>

#include "fralab/core/error.h"
#include "fralab/diagnose/baseline.h"
#include "fralab/diagnose/diagnose.h"
#include "fralab/identify/pole_set_fit.h"
#include "random_modal.h"

namespace fralab {
namespace {

using C = std::complex<double>;

constexpr double kRelSigma = 0.002;  // the data's sigma, relative to |G|
constexpr double kWnTol = 0.003;     // a moved mode's frequency, relative
constexpr double kZetaTol = 0.1;     // a fitted damping, relative

struct Mode {
  double wn, zeta;
};

const std::vector<Mode> kSim = {{10, 0.01}, {20, 0.02}, {35, 0.015}};

// The structure's model: a path force -> acc_j per sensor, each d_j + sum_k A_jk / (s^2 + 2 zeta_k
// wn_k s + wn_k^2) written as a factored tf (PoleSetFit::to_tf), every path holding every mode;
// A_jk (the mode shapes' product) from the simulation's modes kSim, so that a structure whose
// modes moved keeps its shapes.
Model structure(const std::vector<Mode>& modes) {
  const double residue[3][3] = {{1, -0.6, 0.4}, {0.5, 1, -0.8}, {-0.7, 0.3, 1}};
  const std::vector<Mode>& shape_of = kSim;
  PoleSetFit f;
  for (const Mode& m : modes)
    f.poles.push_back(C(-m.zeta * m.wn, m.wn * std::sqrt(1 - m.zeta * m.zeta)));
  Model s;
  s.name = "three-mode structure";
  s.source = "test";
  ModelInput in;
  in.name = "force";
  in.full_scale = 1;
  s.inputs.push_back(in);
  for (int j = 0; j < 3; ++j) {
    std::vector<C> r;
    for (size_t k = 0; k < modes.size(); ++k) {
      const double A = 2 * residue[j][k] * shape_of[k].wn * shape_of[k].wn;
      r.push_back(A / C(0, 2 * std::imag(f.poles[k])));
    }
    f.residues.push_back(r);
    f.d.push_back(0.05);
    ModelOutput o;
    o.name = "acc" + std::to_string(j + 1);
    s.outputs.push_back(o);
    s.paths.push_back({o.name, "force", f.to_tf(size_t(j)), Json::object()});
  }
  return s;
}

// The structure with its modes moved (from sim's to truth's), every path's zeros kept: what a
// pole_shift of each mode at the plant's scope makes of the simulation.
Model moved_structure(const std::vector<Mode>& sim, const std::vector<Mode>& truth) {
  Model m = structure(sim);
  for (ModelPath& p : m.paths)
    for (Root& r : p.tf.poles)
      for (size_t k = 0; k < sim.size(); ++k)
        if (r.pair && std::abs(r.wn / sim[k].wn - 1) < 1e-6)
          r.wn = truth[k].wn, r.zeta = truth[k].zeta;
  return m;
}

// Each pair of `m` on 400 lines over 5-50 rad/s, times misfit[j] at every point, with complex noise
// of relative sigma kRelSigma drawn from `seed`.
std::vector<MeasuredPair> measure(const Model& m, uint64_t seed, const std::vector<C>& misfit) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, kRelSigma / std::sqrt(2.0));
  std::vector<MeasuredPair> out;
  for (size_t j = 0; j < m.outputs.size(); ++j) {
    MeasuredPair mp;
    mp.pair = "force:" + m.outputs[j].name;
    mp.frd.pair = mp.pair;
    for (int i = 0; i < 400; ++i) {
      const double w = 5 + 45.0 * i / 399;
      const C g = m.path_response(int(j), 0, w) * misfit[j];
      const C v = g + std::abs(g) * C(n(rng), n(rng));
      FrdPoint p;
      p.w = w, p.mag = std::abs(v), p.phase_deg = std::arg(v) * 180 / std::numbers::pi;
      p.sigma = kRelSigma * std::abs(g);
      mp.frd.points.push_back(p);
    }
    out.push_back(mp);
  }
  return out;
}

const Finding* moved(const Diagnosis& d, double from_wn) {
  for (const Finding& f : d.findings)
    if (f.cause == CauseKind::kPoleShift &&
        std::abs(f.parameters.at(Param::kFromRadS) / from_wn - 1) < 1e-3)
      return &f;
  return nullptr;
}

// Three modes, each moved 1-2 % (the third's damping doubled too), as a joint that softens moves
// every mode near it (the paths' zeros kept, as a pole_shift moves a mode): three findings, each
// the plant's over the three pairs, each within kWnTol of the truth, and nothing else. Pair by pair
// (at most two causes a path, each removing a quarter of what is left) the third move is lost.
TEST(DiagnoseModes, ModesMovedTogetherAreOneFindingEachOverEveryPair) {
  const std::vector<Mode> truth = {{10.2, 0.01}, {19.7, 0.02}, {35.5, 0.03}};
  const Model sim = structure(kSim);
  const Diagnosis d = diagnose(sim, measure(moved_structure(kSim, truth), 1, {1, 1, 1}));
  ASSERT_EQ(d.findings.size(), 3u);
  for (size_t k = 0; k < kSim.size(); ++k) {
    const Finding* f = moved(d, kSim[k].wn);
    ASSERT_NE(f, nullptr) << "mode at " << kSim[k].wn;
    EXPECT_EQ(f->scope, Scope::kPlant) << kSim[k].wn;
    EXPECT_EQ(f->pairs.size(), 3u) << kSim[k].wn;
    EXPECT_NEAR(f->parameters.at(Param::kToRadS) / truth[k].wn, 1, kWnTol) << kSim[k].wn;
  }
  EXPECT_NEAR(moved(d, 35)->parameters.at(Param::kToZeta) / 0.03, 1, kZetaTol);
  EXPECT_LT(d.error_after, 0.2 * d.error_before)
      << "error " << d.error_before << " -> " << d.error_after;
}

// Structures drawn by the self-check's generator (random_modal.h, seed 2 unless said), each
// effect to be named at its mode or output and nothing else.
void expect_every_effect_named(int index, uint64_t seed = 2) {
  const testing::RandomCase c = testing::random_modal_case(seed, index);
  const Diagnosis d = diagnose(c.simulation, testing::modal_measurement(c, seed + uint64_t(index)));
  const testing::Score s = testing::score(c, d.findings);
  EXPECT_EQ(s.found, s.hidden) << diagnosis_to_json(d).dump(1);
  EXPECT_EQ(s.true_findings, s.findings) << diagnosis_to_json(d).dump(1);
}

// A mode's damping x 2.6 beside an output's 1.8 dB calibration, two inputs, two outputs. In plain
// chi2 the modes stage moved four modes to take up the calibration, and the joint sizing then took
// the damping change's small frequency move back, so that the resolve stage dropped it whole as a
// pole_shift whose frequency the data do not resolve. Either mends it: the pair's gain left free
// in the modes stage, or the resolve stage judging such a move as the pair's damping_error.
TEST(DiagnoseModes, ADampingChangeBesideAnOutputsCalibrationIsNamed) {
  expect_every_effect_named(20);
}

// A mode at 2.59 rad/s (zeta 0.01) moved 3.5 % and another's damping halved, three inputs, four
// outputs: in plain chi2 the model's peak where the data have none outweighed everything, each
// mode's fit flattened its own peak and the move came back as seven path and output findings.
TEST(DiagnoseModes, TwoOverlappingModeChangesWithLargeMisfitsAreEachOneFinding) {
  expect_every_effect_named(28);
}

// Two modes whose half-power bands overlap (2.20 and 2.40 rad/s, zeta 0.016 and 0.042), the
// first's damping x 1.6 and the second moved 1.4 %, both with their shapes kept, two inputs, four
// outputs: each one finding. The two moves on one path add (R + delta_1 + delta_2); taken as the
// product of their factors they were 2-4 % off near the modes, and the fit moved four modes, none
// to its truth.
TEST(DiagnoseModes, TwoNeighboursMovedWithTheirShapesAreEachOneFinding) {
  expect_every_effect_named(17, 9);
}

// Three modes at 4.53, 6.47 and 7.57 rad/s (zeta 0.035-0.041) seen on two paths, the second moved
// to 6.59 with its damping halved and the third to 7.89 with its damping x 2.4, one input. Fitted
// one after the other, the third (taken first) settled at 7.66 with its damping x 3, and the
// second then fitted better as a factor D_from / D_to than with its shape kept; the factor
// multiplies the third's term too and held it there, and a damping change on the first and a path
// gain made up the rest (error 0.346 -> 0.103 against the truth's 0.0019). The forms compared
// whole, every move with its shape kept, each is one finding where it is.
TEST(DiagnoseModes, CloseModesMovedWithTheirShapesAreFoundWithTheirFormsComparedWhole) {
  expect_every_effect_named(34, 24);
}

// Two modes 5.8 % apart (21.52 and 22.78 rad/s, zeta 0.048 and 0.038), the first moved to 21.80
// and the second's damping x 2.45, three inputs, three outputs. Taken first, the second's move
// covered both peaks (to 22.31, its damping x 2.5) and held the first where it was; fitted again
// in the other order, the first moves and the second's damping changes, each at its own mode.
TEST(DiagnoseModes, TwoNeighboursFittedInTheOtherOrderAreEachFoundAtTheirOwnModes) {
  expect_every_effect_named(18, 27);
}

// Two modes moved (4.75 -> 4.93 rad/s and 10.9 -> 10.4 rad/s, dampings doubled), one input, five
// outputs. Beside them the joint sizing left two unmoved modes moved by 4e-6 and 5e-6 of their
// frequencies, 1.2 and 1.4 sigma from the simulation's: changes the data do not resolve, dropped
// where the simulation's value lies within two sigma.
TEST(DiagnoseModes, AMoveWithinTwoSigmaOfTheSimulationIsNotAFinding) {
  expect_every_effect_named(28, 21);
}

// A real structure's mode moves with its shape: each path's antiresonances move with it (the
// engine is the structure with the second mode moved 3 %, its shapes kept). One
// finding, the plant's, with the shapes kept ("form": "residue"), and the extended model at the
// data's noise; the factor D_from / D_to, which keeps the zeros, leaves part of it.
TEST(DiagnoseModes, AModeMovedWithItsShapeMovesTheAntiresonancesToo) {
  constexpr double kAtTheNoise = 2.0;  // the extended model's error, in units of the data's sigma
  const std::vector<Mode> truth = {{10, 0.01}, {20.6, 0.02}, {35, 0.015}};
  const Model sim = structure(kSim);
  const Diagnosis d = diagnose(sim, measure(structure(truth), 5, {1, 1, 1}));
  ASSERT_EQ(d.findings.size(), 1u) << diagnosis_to_json(d).dump(1);
  const Finding& f = d.findings[0];
  EXPECT_EQ(f.scope, Scope::kPlant);
  ASSERT_TRUE(f.text_parameters.count("form"));
  EXPECT_EQ(f.text_parameters.at("form"), "residue");
  EXPECT_NEAR(f.parameters.at(Param::kToRadS) / 20.6, 1, kWnTol);
  EXPECT_LT(d.error_after, kAtTheNoise * kRelSigma) << d.error_before << " -> " << d.error_after;
}

// The simulation misfits its baseline by 1.5 dB at acc2 (a calibration it never had). The
// measurement at a higher level has the second mode moved and the same misfit. Against the
// baseline, the one finding is the mode; without it, the misfit is a finding too.
TEST(DiagnoseModes, ABaselinesMisfitIsTheSimulationsOwnNotAFinding) {
  const double k = std::pow(10.0, 1.5 / 20);
  const std::vector<C> misfit = {1, k, 1};
  const std::vector<Mode> truth = {{10, 0.01}, {19.5, 0.02}, {35, 0.015}};
  const Model sim = structure(kSim);
  const auto base = measure(sim, 3, misfit);
  const auto data = measure(moved_structure(kSim, truth), 4, misfit);
  BaselineSummary s;
  const Diagnosis d = diagnose(sim, relative_to_baseline(sim, data, base, {}, &s));
  EXPECT_EQ(s.pairs, 3);
  EXPECT_EQ(s.points, 1200);
  EXPECT_EQ(s.left_out, 0);
  ASSERT_EQ(d.findings.size(), 1u);
  ASSERT_NE(moved(d, 20), nullptr);
  EXPECT_NEAR(moved(d, 20)->parameters.at(Param::kToRadS) / 19.5, 1, kWnTol);
  const Diagnosis raw = diagnose(sim, data);
  bool gain = false;
  for (const Finding& f : raw.findings) gain = gain || f.cause == CauseKind::kGainMismatch;
  EXPECT_TRUE(gain) << "without the baseline the misfit should be a finding";
}

// A measured point the baseline lacks is kept, invalid and said why; a baseline without sigma is
// refused naming its pair.
TEST(DiagnoseModes, ABaselineWithoutAPointOrWithoutSigmaIsSaid) {
  const Model sim = structure(kSim);
  auto base = measure(sim, 3, {1, 1, 1});
  const auto data = measure(sim, 4, {1, 1, 1});
  base[1].frd.points.erase(base[1].frd.points.begin() + 10);
  BaselineSummary s;
  const auto rel = relative_to_baseline(sim, data, base, {}, &s);
  EXPECT_EQ(s.left_out, 1);
  EXPECT_FALSE(rel[1].frd.points[10].valid);
  EXPECT_FALSE(rel[1].frd.points[10].note.empty());
  for (FrdPoint& p : base[2].frd.points) p.sigma = -1;
  try {
    relative_to_baseline(sim, data, base, {});
    FAIL() << "a baseline without sigma accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("force:acc3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fralab
