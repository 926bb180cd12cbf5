// Stage 5b, the findings sized together (diagnose/src/stages/joint.cc), on a known answer: a
// path's gain and a lag the data do not hold, refined jointly, the gain to its value and the lag's
// corner no further than the range its cause is searched in.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>

#include "../../../diagnose/src/stages/stages.h"
#include "fralab/diagnose/diagnose.h"
#include "test_util.h"

using namespace fralab;
using namespace fralab::diag;

namespace {

constexpr double kRelSigma = 0.002;  // the data's sigma, relative to |G|
constexpr double kGainDb = 1.0;      // the truth's gain over the simulation's
constexpr double kGainTolDb = 0.05;  // the refined gain within this of it
constexpr double kTopRadS = 200;     // the band's top

// One input u, one output y = 2 / (s/3 + 1).
Model simulation() {
  Tf t;
  t.gain = 2.0;
  t.poles = {Root::Real(-3)};
  return fralab::testing::siso_model(t);
}

// u:y of the simulation kGainDb higher, exact, 0.05-200 rad/s at 10 per decade.
std::vector<MeasuredPair> measured(const Model& sim) {
  MeasuredPair mp;
  mp.pair = mp.frd.pair = "u:y";
  for (int k = 0; k <= 36; ++k) {
    const double w = 0.05 * std::pow(10.0, k / 10.0);
    const std::complex<double> g =
        *model_pair_response(sim, "u:y", w, 0.02) * std::pow(10.0, kGainDb / 20);
    FrdPoint p;
    p.w = w;
    p.mag = std::abs(g);
    p.phase_deg = std::arg(g) * 180 / M_PI;
    p.sigma = kRelSigma * std::abs(g);
    p.amplitude = 0.02;
    p.input = "u";
    mp.frd.points.push_back(p);
  }
  return {mp};
}

Finding at_path(CauseKind cause, Param key, double v) {
  Finding f;
  f.cause = cause;
  f.scope = Scope::kPath;
  f.input = "u";
  f.output = "y";
  f.parameters[key] = v;
  f.pairs = {"u:y"};
  return f;
}

}  // namespace

// The lag's chi2 falls without end as its corner rises (a corner far above the band is no lag
// there): the refinement stops it where the corner causes' search stops, the band's top widened
// by corner_decades_beyond, and sizes the gain beside it.
TEST(Joint, AFrequencyIsRefinedNoFurtherThanItsCauseIsSearched) {
  const Model sim = simulation();
  const std::vector<MeasuredPair> data = measured(sim);
  const DiagnoseOptions opt;
  DiagnosisRun r(sim, data, opt);
  prepare(r);
  std::vector<Finding> fs = {at_path(CauseKind::kGainMismatch, Param::kGainDb, 0.5),
                             at_path(CauseKind::kMissingLag, Param::kCornerRadS, 300)};
  refine(r, fs, {0, 1}, fitted_pairs(r, {"u:y"}), 2);
  const double top = kTopRadS * std::pow(10.0, opt.corner_decades_beyond);
  EXPECT_GT(fs[1].parameters.at(Param::kCornerRadS), 300);
  EXPECT_LE(fs[1].parameters.at(Param::kCornerRadS), top * (1 + 1e-9));
  EXPECT_NEAR(fs[0].parameters.at(Param::kGainDb), kGainDb, kGainTolDb);
}
