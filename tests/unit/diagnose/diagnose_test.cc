// The diagnosis on synthetic residuals, without processes: a truth model (the simulation with one
// hidden effect) gives exact frequency-response data to fit and an independent validation
// measurement (another amplitude, noise of its sigma); the diagnosis must name the effect, its
// scope and its parameter within named tolerances, extend the model so the error falls on both,
// and report nothing when nothing is hidden. One test per cause of the catalogue.
#include "fralab/diagnose/diagnose.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>

#include "fralab/core/measurement_chain.h"
#include "fralab/diagnose/report.h"
#include "fralab/plant/lti.h"
#include "random_machine.h"
#include "random_modal.h"
#include "test_util.h"

namespace fralab {
// gtest prints the enums by name.
std::ostream& operator<<(std::ostream& os, CauseKind c) { return os << to_string(c); }
std::ostream& operator<<(std::ostream& os, Scope s) { return os << to_string(s); }

namespace {

using fralab::testing::source_path;
using ::testing::ElementsAre;
using ::testing::Field;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

constexpr double kRelSigma = 0.002;  // the data's sigma, relative to |G|
constexpr double kAmplitude = 0.02;  // excitation amplitude, input units
// The validation measurement: another amplitude (a nonlinearity's describing function changes
// with it), noise of the data's sigma drawn with this seed.
constexpr double kValidationAmplitude = 0.03;
constexpr uint64_t kValidationSeed = 2;
// A model that is the truth predicts the validation measurement to its noise: the error metric
// (rms of |ln(G_model / G_measured)|) of complex noise of relative sigma kRelSigma is kRelSigma
// (to 1/sqrt(points)); within this factor of it.
constexpr double kAtTheNoise = 1.5;

Tf tf(double gain, std::vector<Root> poles, std::vector<Root> zeros = {}) {
  Tf t;
  t.gain = gain;
  t.poles = std::move(poles);
  t.zeros = std::move(zeros);
  return t;
}

// One actuator u (pole at 20 rad/s), two outputs: y = 2/(s/3+1), z = -1/((s/8+1)(pair 30, 0.3)).
Model simulation() {
  Model m;
  m.name = "diagnose_test";
  m.source = "test";
  ModelInput in;
  in.name = "u";
  in.units = "1";
  in.full_scale = 1.0;
  in.actuator = tf(1.0, {Root::Real(-20)});
  m.inputs.push_back(in);
  for (const char* n : {"y", "z"}) {
    ModelOutput o;
    o.name = n;
    o.units = "1";
    m.outputs.push_back(o);
  }
  m.paths = {{"y", "u", tf(2.0, {Root::Real(-3)}), Json::object()},
             {"z", "u", tf(-1.0, {Root::Real(-8), Root::Pair(30, 0.3)}), Json::object()}};
  return m;
}

// The value g with complex noise of standard deviation `sigma` (sigma^2 = E|e|^2, an frd's sigma).
Complex with_noise(Complex g, double sigma, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, sigma / std::sqrt(2.0));
  const double re = n(rng);
  return g + Complex(re, n(rng));
}

// Data of `truth` for u:y, u:z and the actuator u_u:u, 0.05-200 rad/s at 10 per decade: exact at
// kAmplitude to fit; the validation at kValidationAmplitude with noise of the points' sigma (seed
// kValidationSeed). `h3` is the odd-harmonic level recorded on the actuator's points (the
// nonlinearity's trigger).
std::vector<MeasuredPair> measure(const Model& truth, double h3 = 0.0,
                                  const std::vector<std::string>& pairs = {"u:y", "u:z", "u_u:u"}) {
  std::mt19937_64 rng(kValidationSeed);
  std::vector<MeasuredPair> out;
  for (const std::string& pair : pairs) {
    MeasuredPair mp;
    mp.pair = mp.frd.pair = mp.validation.pair = pair;
    for (const bool validation : {false, true}) {
      const double amplitude = validation ? kValidationAmplitude : kAmplitude;
      for (int k = 0; k <= 36; ++k) {
        const double w = 0.05 * std::pow(10.0, k / 10.0);
        Complex g = *model_pair_response(truth, pair, w, amplitude);
        const double sigma = kRelSigma * std::abs(g);
        if (validation) g = with_noise(g, sigma, rng);
        FrdPoint p;
        p.w = w;
        p.mag = std::abs(g);
        p.phase_deg = std::arg(g) * 180 / M_PI;
        p.sigma = sigma;
        p.amplitude = amplitude;
        p.input = "u";
        p.h3_rel = pair == "u_u:u" ? h3 : 0.0;
        (validation ? mp.validation : mp.frd).points.push_back(p);
      }
    }
    out.push_back(mp);
  }
  return out;
}

ModelPath& path(Model& m, const std::string& out) {
  for (auto& p : m.paths)
    if (p.output == out) return p;
  throw std::runtime_error("no path");
}

// The one finding of a diagnosis, with the extended model closer to the data than the simulation
// and predicting the independent validation measurement to its noise (neither beyond it nor, on
// another draw, below it), where the simulation is beyond it.
Finding only_finding(const Diagnosis& d) {
  EXPECT_EQ(d.findings.size(), 1u);
  EXPECT_LT(d.error_after, 0.2 * d.error_before);
  EXPECT_LT(d.validation_after, 0.2 * d.validation_before);
  EXPECT_LT(d.validation_after, kAtTheNoise * kRelSigma);
  EXPECT_GT(d.validation_after, kRelSigma / kAtTheNoise);
  EXPECT_GT(d.validation_before, 5 * kAtTheNoise * kRelSigma);
  return d.findings.at(0);
}

TEST(Diagnose, NothingHiddenNothingFound) {
  const Model sim = simulation();
  const Diagnosis d = diagnose(sim, measure(sim));
  EXPECT_THAT(d.findings, IsEmpty());
  EXPECT_LT(d.error_before, 1e-9);
  // The validation measurement is another draw: the simulation errs there by its noise alone.
  EXPECT_GT(d.validation_before, kRelSigma / kAtTheNoise);
  EXPECT_LT(d.validation_before, kAtTheNoise * kRelSigma);
  EXPECT_EQ(d.validation_after, d.validation_before);
}

TEST(Diagnose, TimeDelayInOnePath) {
  Model truth = simulation();
  path(truth, "y").tf.delay_s = 0.011;
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(f.cause, CauseKind::kTimeDelay);
  EXPECT_EQ(f.scope, Scope::kPath);
  EXPECT_EQ(f.output, "y");
  EXPECT_NEAR(f.parameters.at(Param::kDelayS), 0.011, 0.2e-3);
  EXPECT_THAT(f.explanation, HasSubstr("phase residual linear in w"));
}

// The finding's explicit 1-sigma interval: where chi2 rises by 1 (the fit is exact here). For a
// delay on u:y with relative sigma_eff r at each point, chi2(tau0 + d) - chi2(tau0) = sum (w d)^2 /
// r^2 to first order, so the half-width is r / sqrt(sum w^2); it holds the truth.
TEST(Diagnose, AFindingsIntervalIsWhereChi2RisesByOne) {
  Model truth = simulation();
  path(truth, "y").tf.delay_s = 0.011;
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  ASSERT_TRUE(f.intervals.count(Param::kDelayS));
  const auto [lo, hi] = f.intervals.at(Param::kDelayS);
  const double r = std::hypot(kRelSigma, DiagnoseOptions{}.sigma_floor);
  double sw2 = 0;
  for (int k = 0; k <= 36; ++k) sw2 += std::pow(0.05 * std::pow(10.0, k / 10.0), 2);
  const double half = r / std::sqrt(sw2);
  EXPECT_NEAR(hi - f.parameters.at(Param::kDelayS), half, 0.05 * half);
  EXPECT_NEAR(f.parameters.at(Param::kDelayS) - lo, half, 0.05 * half);
  EXPECT_LT(lo, 0.011);
  EXPECT_GT(hi, 0.011);
  EXPECT_GT(lo, 0.0) << "the simulation's 0 is outside: resolved";
  const Json j = diagnosis_to_json(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(j["findings"][0]["intervals"]["delay_s"].size(), 2u);
}

// A path the simulation lacks: the data respond in u:w, the simulation has no path there; the
// path is fitted (gain, lag, delay as the truth's) and the extended model has it.
TEST(Diagnose, APathTheSimulationLacksIsFittedAndAdded) {
  Model sim = simulation();
  ModelOutput w;
  w.name = "w";
  w.units = "1";
  sim.outputs.push_back(w);
  Model truth = sim;
  Tf t = tf(0.5, {Root::Real(-5)});
  t.delay_s = 0.02;
  truth.paths.push_back({"w", "u", t, Json::object()});
  const Diagnosis d = diagnose(sim, measure(truth, 0.0, {"u:y", "u:z", "u_u:u", "u:w"}));
  for (const auto& x : d.dropped) ADD_FAILURE() << "dropped: " << x.reason;
  ASSERT_EQ(d.findings.size(), 1u);
  const Finding& f = d.findings[0];
  EXPECT_EQ(f.cause, CauseKind::kMissingPath);
  EXPECT_EQ(f.scope, Scope::kPath);
  EXPECT_EQ(f.input, "u");
  EXPECT_EQ(f.output, "w");
  EXPECT_NEAR(f.parameters.at(Param::kGain), 0.5, 0.01 * 0.5);
  EXPECT_NEAR(f.parameters.at(Param::kDelayS), 0.02, 0.5e-3);
  EXPECT_EQ(f.parameters.at(Param::kPoles), 1.0);
  ASSERT_TRUE(f.tf);
  EXPECT_NEAR(f.tf->poles.at(0).real, -5.0, 0.05);
  EXPECT_EQ(f.error_before, 1.0);
  EXPECT_LT(f.error_after, 0.01);
  ASSERT_NE(d.extended.path("w", "u"), nullptr);
  EXPECT_LT(std::abs(d.extended.path("w", "u")->tf.at(3.0) / t.at(3.0) - 1.0), 0.01);
  EXPECT_THAT(f.explanation, HasSubstr("where the simulation has no path"));
  EXPECT_EQ(diagnosis_to_json(d)["findings"][0]["cause"], "missing_path");
  // Noise alone in a pair without a path in either: nothing.
  const Diagnosis none = diagnose(sim, measure(sim, 0.0, {"u:y", "u:z", "u_u:u"}));
  EXPECT_THAT(none.findings, IsEmpty());
}

TEST(Diagnose, MissingLag) {
  Model truth = simulation();
  path(truth, "z").tf.poles.push_back(Root::Real(-15));
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(f.cause, CauseKind::kMissingLag);
  EXPECT_EQ(f.output, "z");
  EXPECT_NEAR(f.parameters.at(Param::kCornerRadS), 15, 0.03 * 15);
}

// A lag above the band (400 rad/s, the data end at 200) whose gain the data resolve (-1 dB at
// the top, 1 % sigma) stays a lag: a delay does not fit it as well.
TEST(Diagnose, ALagAboveTheBandWhoseGainTheDataResolveStaysALag) {
  Model truth = simulation();
  path(truth, "z").tf.poles.push_back(Root::Real(-400));
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(f.cause, CauseKind::kMissingLag);
  EXPECT_NEAR(f.parameters.at(Param::kCornerRadS), 400, 0.03 * 400);
}

TEST(Diagnose, MissingLead) {
  Model truth = simulation();
  path(truth, "y").tf.zeros.push_back(Root::Real(-6));
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(f.cause, CauseKind::kMissingLead);
  EXPECT_NEAR(f.parameters.at(Param::kCornerRadS), 6, 0.03 * 6);
}

TEST(Diagnose, GainMismatch) {
  Model truth = simulation();
  path(truth, "y").tf.gain *= std::pow(10.0, 1.0 / 20);  // +1 dB
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(f.cause, CauseKind::kGainMismatch);
  EXPECT_NEAR(f.parameters.at(Param::kGainDb), 1.0, 0.05);
}

TEST(Diagnose, PoleShiftInAPath) {
  Model truth = simulation();
  path(truth, "y").tf.poles[0] = Root::Real(-4.5);
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(f.cause, CauseKind::kPoleShift);
  EXPECT_NEAR(f.parameters.at(Param::kFromRadS), 3, 1e-12);
  EXPECT_NEAR(f.parameters.at(Param::kToRadS), 4.5, 0.03 * 4.5);
}

// Two effects on one path that overlap: the pole moved from 3 to 3.3 rad/s and the gain 0.5 dB
// higher (the Silverbox's measured resonance against a linear model fitted at another level:
// frequency and gain both moved). Fitted one after the other, each on what the other left, the
// second absorbs part of the first; refined jointly, each is its own size.
TEST(Diagnose, TwoOverlappingEffectsOnOnePathAreSizedJointly) {
  constexpr double kPoleTol = 0.01, kGainTolDb = 0.05;
  Model truth = simulation();
  path(truth, "y").tf.poles[0] = Root::Real(-3.3);
  path(truth, "y").tf.gain *= std::pow(10.0, 0.5 / 20);
  const Diagnosis d = diagnose(simulation(), measure(truth));
  const Finding* pole = nullptr;
  const Finding* gain = nullptr;
  for (const Finding& f : d.findings) {
    if (f.cause == CauseKind::kPoleShift) pole = &f;
    if (f.cause == CauseKind::kGainMismatch) gain = &f;
  }
  ASSERT_NE(pole, nullptr) << diagnosis_to_json(d).dump(1);
  ASSERT_NE(gain, nullptr) << diagnosis_to_json(d).dump(1);
  EXPECT_NEAR(pole->parameters.at(Param::kToRadS) / 3.3, 1.0, kPoleTol)
      << diagnosis_to_json(d).dump(1);
  EXPECT_NEAR(gain->parameters.at(Param::kGainDb), 0.5, kGainTolDb) << diagnosis_to_json(d).dump(1);
  EXPECT_LT(d.validation_after, kAtTheNoise * kRelSigma);
}

// The machine-shaped self-check's case 17 (tests/util/random_machine.h, seed 1): one input, five
// outputs, a slow mode in every path moved 0.914 -> 2.153 rad/s, and the output Y3's calibration
// +3.59 dB on its one weak path. Fitted alone, Y3's path splits the two as a larger shift and a
// smaller gain, which vetoed the plant's group; sized jointly, its shift agrees with the other
// paths', and the five become one plant finding (regroup) beside the path's gain.
TEST(Diagnose, PathFindingsConsistentAfterJointSizingBecomeOnePlantFinding) {
  constexpr double kPoleTol = 0.01, kGainTolDb = 0.1;
  const testing::RandomCase c = testing::random_machine_case(1, 17);
  ASSERT_EQ(c.engine.inputs.size(), 1u);
  const std::string in = c.engine.inputs[0].name;
  std::vector<std::string> pairs{"u_" + in + ":" + in};
  for (const ModelOutput& o : c.engine.outputs) pairs.push_back(in + ":" + o.name);
  const double amplitude = 0.02 * c.engine.inputs[0].full_scale;
  std::mt19937_64 rng(kValidationSeed);
  std::vector<MeasuredPair> data;
  for (const std::string& pair : pairs) {
    MeasuredPair mp;
    mp.pair = mp.frd.pair = mp.validation.pair = pair;
    for (const bool validation : {false, true})
      for (int k = 0; k <= 25; ++k) {
        const double w = 0.1 * std::pow(10.0, k / 10.0);  // 0.1-31 rad/s, 10 per decade
        const double a = validation ? 1.5 * amplitude : amplitude;
        Complex g = *model_pair_response(c.engine, pair, w, a);
        const double sigma = kRelSigma * std::abs(g);
        if (validation) g = with_noise(g, sigma, rng);
        FrdPoint p;
        p.w = w, p.mag = std::abs(g), p.phase_deg = std::arg(g) * 180 / M_PI;
        p.sigma = sigma, p.amplitude = a, p.input = in;
        (validation ? mp.validation : mp.frd).points.push_back(p);
      }
    data.push_back(mp);
  }
  const Diagnosis d = diagnose(c.simulation, data);
  const std::string json = diagnosis_to_json(d).dump(1);
  const Finding* pole = nullptr;
  const Finding* gain = nullptr;
  for (const Finding& f : d.findings) {
    if (f.cause == CauseKind::kPoleShift) {
      EXPECT_EQ(pole, nullptr) << "one pole shift, not one per path" << json;
      pole = &f;
    }
    if (f.cause == CauseKind::kGainMismatch) gain = &f;
  }
  ASSERT_NE(pole, nullptr) << json;
  ASSERT_NE(gain, nullptr) << json;
  ASSERT_EQ(c.hidden.size(), 2u);
  const testing::HiddenEffect& moved =
      c.hidden[0].cause == CauseKind::kPoleShift ? c.hidden[0] : c.hidden[1];
  const testing::HiddenEffect& calibration = &moved == &c.hidden[0] ? c.hidden[1] : c.hidden[0];
  ASSERT_EQ(moved.cause, CauseKind::kPoleShift);
  ASSERT_EQ(calibration.cause, CauseKind::kGainMismatch);
  EXPECT_EQ(pole->scope, Scope::kPlant) << json;
  EXPECT_NEAR(pole->parameters.at(Param::kToRadS) / moved.value, 1.0, kPoleTol) << json;
  EXPECT_EQ(gain->scope, Scope::kPath);
  EXPECT_EQ(gain->output, calibration.output);
  EXPECT_NEAR(gain->parameters.at(Param::kGainDb), calibration.value, kGainTolDb) << json;
}

// A machine-shaped self-check case measured offline: every actuator pair and path at 12 points,
// 0.6-126 rad/s, at 2 % of full scale (validation: 3 %, another noise draw); a path's sigma
// relative to its response, and at least `noise_of_strongest` of its output's strongest path's
// response (a weak path's points as noisy as the output's noise makes them). *weakest (when
// given): the weakest path into `out` relative to the strongest.
std::vector<MeasuredPair> measure_machine_case(const testing::RandomCase& c,
                                               double noise_of_strongest,
                                               const std::string& out = "",
                                               double* weakest = nullptr) {
  std::vector<std::string> pairs;
  for (const ModelInput& in : c.engine.inputs) {
    pairs.push_back("u_" + in.name + ":" + in.name);
    for (const ModelOutput& o : c.engine.outputs) pairs.push_back(in.name + ":" + o.name);
  }
  auto w_of = [](int k) { return 0.6 * std::pow(10.0, k / 5.0); };  // 0.6-126 rad/s, 5 a decade
  auto response = [&](const std::string& pair, double w, bool validation) {
    const auto [e1, e2] = split_pair(pair);
    const std::string in = e1.rfind("u_", 0) == 0 ? e1.substr(2) : e1;
    const double a =
        (validation ? 0.03 : 0.02) * c.engine.inputs[size_t(c.engine.input_index(in))].full_scale;
    return *model_pair_response(c.engine, pair, w, a);
  };
  // Each output's noise: a fraction of its strongest path's response at that frequency.
  auto strongest = [&](const std::string& o, double w) {
    double s = 0;
    for (const ModelInput& in : c.engine.inputs)
      s = std::max(s, std::abs(response(in.name + ":" + o, w, false)));
    return s;
  };
  std::mt19937_64 rng(kValidationSeed);
  std::vector<MeasuredPair> data;
  if (weakest) *weakest = 1;
  for (const std::string& pair : pairs) {
    const auto [e1, e2] = split_pair(pair);
    const bool actuator = e1.rfind("u_", 0) == 0;
    MeasuredPair mp;
    mp.pair = mp.frd.pair = mp.validation.pair = pair;
    for (const bool validation : {false, true})
      for (int k = 0; k <= 11; ++k) {
        const double w = w_of(k);
        Complex g = response(pair, w, validation);
        const double sigma =
            actuator ? kRelSigma * std::abs(g)
                     : std::max(kRelSigma * std::abs(g), noise_of_strongest * strongest(e2, w));
        if (weakest && e2 == out && !actuator && !validation)
          *weakest = std::min(*weakest, std::abs(g) / strongest(e2, w));
        g = with_noise(g, sigma, rng);
        FrdPoint p;
        p.w = w, p.mag = std::abs(g), p.phase_deg = std::arg(g) * 180 / M_PI;
        p.input = actuator ? e1.substr(2) : e1;
        p.sigma = sigma,
        p.amplitude = (validation ? 0.03 : 0.02) *
                      c.engine.inputs[size_t(c.engine.input_index(p.input))].full_scale;
        (validation ? mp.validation : mp.frd).points.push_back(p);
      }
    data.push_back(mp);
  }
  return data;
}

// The machine-shaped self-check's case 35 (seed 1): three inputs, two outputs, a 7.36 ms delay in
// the output Y1's sensor; of the three paths into Y1 one is weak (its response far below the
// strongest, its points as noisy as the output's noise makes them). The two strong paths each fit
// the delay; the weak one, alone, cannot tell it. Applied there, the delay costs no chi2 the noise
// can tell, so the three are one finding at the output, its sensor.
TEST(Diagnose, ASensorDelayTheWeakPathCannotTellIsStillTheOutputs) {
  constexpr double kDelayTolS = 0.3e-3, kNoiseOfStrongest = 0.005;
  const testing::RandomCase c = testing::random_machine_case(1, 35);
  ASSERT_EQ(c.hidden.size(), 1u);
  ASSERT_EQ(c.hidden[0].cause, CauseKind::kTimeDelay);
  ASSERT_EQ(c.hidden[0].scope, Scope::kOutput);
  const std::string out = c.hidden[0].output;
  double weakest = 1;  // the weakest path into `out`, relative to the strongest
  const std::vector<MeasuredPair> data = measure_machine_case(c, kNoiseOfStrongest, out, &weakest);
  ASSERT_LT(weakest, 0.1) << "the case has a weak path into " << out;
  const Diagnosis d = diagnose(c.simulation, data);
  const std::string json = diagnosis_to_json(d).dump(1);
  ASSERT_EQ(d.findings.size(), 1u) << json;
  const Finding& f = d.findings[0];
  EXPECT_EQ(f.cause, CauseKind::kTimeDelay) << json;
  EXPECT_EQ(f.scope, Scope::kOutput) << json;
  EXPECT_EQ(f.output, out) << json;
  EXPECT_NEAR(f.parameters.at(Param::kDelayS), c.hidden[0].value, kDelayTolS) << json;
}

// The hidden effect of `cause` at `scope` in case c (the last drawn, when several), or nullptr.
static const testing::HiddenEffect* hidden_at(const testing::RandomCase& c, CauseKind cause,
                                              Scope scope) {
  const testing::HiddenEffect* found = nullptr;
  for (const auto& h : c.hidden)
    if (h.cause == cause && h.scope == scope) found = &h;
  return found;
}

// The finding of `cause` in d (the last, when several), or nullptr.
static const Finding* found_of(const Diagnosis& d, CauseKind cause) {
  const Finding* found = nullptr;
  for (const Finding& f : d.findings)
    if (f.cause == cause) found = &f;
  return found;
}

// A machine case hiding the plant's slow pole moved and a lag at `lag_scope`, measured without the
// lab (measure_machine_case): exactly two findings, the plant's pole within 2 % and the lag at its
// place within 5 %.
static void expect_the_plants_pole_and_a_lag(int index, Scope lag_scope) {
  constexpr double kPoleTol = 0.02, kCornerTol = 0.05, kNoiseOfStrongest = 0.005;
  const testing::RandomCase c = testing::random_machine_case(1, index);
  ASSERT_EQ(c.hidden.size(), 2u);
  const testing::HiddenEffect* pole = hidden_at(c, CauseKind::kPoleShift, Scope::kPlant);
  const testing::HiddenEffect* lag = hidden_at(c, CauseKind::kMissingLag, lag_scope);
  ASSERT_NE(pole, nullptr);
  ASSERT_NE(lag, nullptr);
  const Diagnosis d = diagnose(c.simulation, measure_machine_case(c, kNoiseOfStrongest));
  const std::string json = diagnosis_to_json(d).dump(1);
  ASSERT_EQ(d.findings.size(), 2u) << json;
  const Finding* plant = nullptr;
  const Finding* found_lag = nullptr;
  for (const Finding& f : d.findings) {
    if (f.cause == CauseKind::kPoleShift && f.scope == Scope::kPlant) plant = &f;
    if (f.cause == CauseKind::kMissingLag && f.scope == lag_scope) found_lag = &f;
  }
  ASSERT_NE(plant, nullptr) << json;
  ASSERT_NE(found_lag, nullptr) << json;
  EXPECT_NEAR(plant->parameters.at(Param::kToRadS) / pole->value, 1.0, kPoleTol) << json;
  EXPECT_EQ(found_lag->output, lag->output) << json;
  EXPECT_NEAR(found_lag->parameters.at(Param::kCornerRadS) / lag->value, 1.0, kCornerTol) << json;
}

// The machine-shaped self-check's case 10 (seed 1): one input, five outputs, the plant's slow pole
// moved 0.789 -> 1.618 rad/s and a 22 rad/s lag the simulation lacks on the path into Y1. Four
// paths fit the pole; Y1's own fit splits the overlap wrongly (a pole at 1.20 and a resonance in
// place of the lag). Fitted again against the simulation extended by the four's plant pole, Y1
// shows its lag: two findings, the plant's pole and Y1's lag, each within its tolerance.
TEST(Diagnose, APathThatSplitsAnOverlapWronglyIsFittedAgainWithThePlantsPole) {
  expect_the_plants_pole_and_a_lag(10, Scope::kPath);
}

// An output's pole_shift of a pole its sensor does not hold (the plant's slow mode, seen moved at
// that output only) moves the pole in every path into the output; a path without the pole takes
// the factor D_from / D_to itself; a pole the sensor holds moves in the sensor. Each extended
// response is the simulation's times D_from / D_to, to rounding.
TEST(Diagnose, AnOutputsPoleShiftMovesThePoleWhereItIs) {
  constexpr double kRel = 1e-12;
  Model sim = simulation();
  sim.outputs[0].sensor = tf(1.0, {Root::Real(-50)});
  sim.paths.push_back({"y", "v", tf(1.0, {Root::Real(-8)}), Json::object()});
  ModelInput v = sim.inputs[0];
  v.name = "v";
  sim.inputs.push_back(v);
  auto shift = [](double from, double to) {
    Finding f;
    f.cause = CauseKind::kPoleShift;
    f.scope = Scope::kOutput;
    f.output = "y";
    f.parameters = {{Param::kFromRadS, from}, {Param::kToRadS, to}};
    return f;
  };
  for (const auto& [from, to] : {std::pair{3.0, 5.0}, std::pair{50.0, 40.0}}) {
    const Model ext = extend_model(sim, {shift(from, to)});
    for (const std::string pair : {"u:y", "v:y", "u:z"})
      for (const double w : {0.3, 3.0, 30.0}) {
        const Complex s(0, w);
        const Complex moved = pair == "u:z" ? Complex(1) : (1.0 + s / from) / (1.0 + s / to);
        const Complex ratio =
            *model_pair_response(ext, pair, w, 0.02) / *model_pair_response(sim, pair, w, 0.02);
        EXPECT_NEAR(std::abs(ratio / moved - 1.0), 0, kRel) << pair << " at " << w << " rad/s";
      }
    if (from == 3.0) {
      EXPECT_NEAR(ext.paths[0].tf.poles.at(0).real, -5.0, kRel) << "u:y moves its own pole";
      EXPECT_EQ(ext.paths[2].tf.zeros.size(), 1u) << "v:y, without the pole, takes the factor";
      EXPECT_NEAR(ext.outputs[0].sensor->poles.at(0).real, -50.0, kRel);
    } else {
      EXPECT_NEAR(ext.outputs[0].sensor->poles.at(0).real, -40.0, kRel) << "the sensor's pole";
      EXPECT_NEAR(ext.paths[0].tf.poles.at(0).real, -3.0, kRel);
    }
  }
}

// The machine-shaped self-check's case 30 (seed 1): two inputs, four outputs, the plant's slow
// pole moved 1.60 -> 3.90 rad/s and a 7.5 rad/s lag in Y0's sensor. The lag makes Y0's paths fit
// the pole apart from the others', so no plant finding forms from the paths' own fits; each
// output's two paths agree, and the pole came back as four output findings beside Y0's lag. The
// outputs' findings of one cause and value over every pair are the plant's: two findings, each
// within its tolerance.
TEST(Diagnose, ThePlantsPoleSeenAtSomeOutputsIsThePlantsBesideAnotherOutputsLag) {
  expect_the_plants_pole_and_a_lag(30, Scope::kOutput);
}

// The machine-shaped self-check's case 42 of seed 2: two inputs, two outputs, Y0's sensor reads
// 3.91 dB high and U0's calibration 3.05 dB low. Each path's own fit holds their sum (U0:Y0
// 0.86 dB, U1:Y0 3.91, U0:Y1 -3.05, U1:Y1 nothing), so no output or input group forms. The fewest
// inputs' and outputs' gains that add up to every path's are the two hidden ones: two gain
// findings, each at its place and within its tolerance.
TEST(Diagnose, AnInputsAndAnOutputsCalibrationsAreNamedWhereTheyAre) {
  constexpr double kGainTolDb = 0.1, kNoiseOfStrongest = 0.005;
  const testing::RandomCase c = testing::random_machine_case(2, 42);
  std::map<Scope, const testing::HiddenEffect*> hidden;
  for (const auto& h : c.hidden)
    if (h.cause == CauseKind::kGainMismatch) hidden[h.scope] = &h;
  ASSERT_EQ(hidden.size(), 2u);
  ASSERT_TRUE(hidden.count(Scope::kInput) && hidden.count(Scope::kOutput));
  const Diagnosis d = diagnose(c.simulation, measure_machine_case(c, kNoiseOfStrongest));
  const std::string json = diagnosis_to_json(d).dump(1);
  int gains = 0;
  for (const Finding& f : d.findings) {
    if (f.cause != CauseKind::kGainMismatch) continue;
    ++gains;
    ASSERT_TRUE(hidden.count(f.scope)) << json;
    const testing::HiddenEffect& h = *hidden.at(f.scope);
    EXPECT_EQ(f.input, h.input) << json;
    EXPECT_EQ(f.output, h.output) << json;
    EXPECT_NEAR(f.parameters.at(Param::kGainDb), h.value, kGainTolDb) << json;
  }
  EXPECT_EQ(gains, 2) << json;
}

// The lab's measurements of the DIR in tests/data/lab, diagnosed against `sim` through the chain
// its run.json records.
static Diagnosis diagnose_lab_data(const Model& sim, const std::string& name) {
  const std::string dir = source_path("tests/data/lab/" + name), run = dir + "/run.json";
  DiagnoseOptions opt;
  opt.chain =
      chain_from_json(json_load_file(run).at("measurement_chain"), {run, "/measurement_chain"});
  return diagnose(sim, read_measured_dir(dir), opt);
}

// A case of the machine-shaped self-check (tests/util/random_machine.h) diagnosed against the lab's
// own measurement of it (tests/data/lab/machine_s<seed>_c<index>), with the diagnosis' JSON for
// failure messages.
struct LabCase {
  LabCase(uint64_t seed, int index)
      : c(testing::random_machine_case(seed, index)),
        d(diagnose_lab_data(c.simulation,
                            "machine_s" + std::to_string(seed) + "_c" + std::to_string(index))),
        json(diagnosis_to_json(d).dump(1)) {}
  testing::RandomCase c;
  Diagnosis d;
  std::string json;
};

// The lab's measurement of the machine-shaped self-check's case `index` of `seed`: each of its
// `hidden` effects found, and no other finding.
void expect_every_effect_and_no_other(uint64_t seed, int index, int hidden) {
  const auto& [c, d, json] = LabCase(seed, index);
  const testing::Score s = testing::score(c, d.findings);
  ASSERT_EQ(s.hidden, hidden);
  EXPECT_EQ(s.found, hidden) << json;
  EXPECT_EQ(s.true_findings, s.findings) << json;
}

// The machine-shaped self-check's case 3 of seed 37 as the lab measured it (tests/data/lab/
// machine_s37_c3): -2.50 dB at the output Y0 and -1.78 dB at the input U0 of a two-input,
// two-output plant, U0 -> Y0 carrying their sum. The three path gains split into the input's and
// the output's by least squares over the totals (every pair alike) raised two pairs' chi2 by 5,
// beyond one parameter's penalty, and the three stayed; sized on the data, the two are the
// findings, each within the self-check's tolerance.
TEST(Diagnose, AnInputsAndAnOutputsGainsSizedOnTheDataAreTwoFindings) {
  expect_every_effect_and_no_other(37, 3, 2);
}

// The machine-shaped self-check's case 27 of seed 40 as the lab measured it (tests/data/lab/
// machine_s40_c27): +2.88 dB at the input U0, -2.91 dB at U1 and -2.49 dB at the output Y1 of a
// two-input, two-output plant. A value moved from both inputs to both outputs changes no path, so
// four sets of three gains fit the curves alike; the choice fell by rounding on U0 +5.79, Y0 -2.91
// and Y1 -5.41 (three false, three missed). The set of the smallest gains is the hidden one.
TEST(Diagnose, GainsTheCurvesCannotTellApartAreTheSmallestSet) {
  expect_every_effect_and_no_other(40, 27, 3);
}

// The machine-shaped self-check's case 22 of seed 41 as the lab measured it (tests/data/lab/
// machine_s41_c22): 14.8 ms at the output Y1, 12.6 ms at Y2 and 5.5 ms on the path U0 -> Y0 of a
// three-input, three-output plant. Grouping U0 -> Y0's delay as the input U0's, the outputs'
// delays were resized on U0's paths alone (to 9.3 and 7.1 ms, U0 -> Y1 and U0 -> Y2 then as
// before), which the outputs' other paths, not among the pairs fitted, could not refuse: three
// false findings, the error 0.070 where the truth's is 0.040. Each finding is now sized on every
// pair it covers.
TEST(Diagnose, AnOutputsDelayResizedOnAnInputsScopeKeepsItsOtherPaths) {
  expect_every_effect_and_no_other(41, 22, 3);
}

// The modal self-check's case 5 of seed 17 as the lab measured it (tests/data/lab/modal_s17_c5,
// its README says how): two modes moved across each other beside three unmoved ones. The joint
// refinement took three path damping errors of the unmoved 18.17 rad/s mode to a damping of
// exactly 0, and the extended model, an undamped pair, could not be written and read back. Each
// damping now stays within its causes' search range, every extended pole in the left half plane.
TEST(Diagnose, ADampingIsRefinedWithinItsSearchRange) {
  constexpr double kZetaMin = 0.002;  // the damping causes' search range's low end
  const testing::RandomCase c = testing::random_modal_case(17, 5);
  for (const Root& q : c.engine.paths[0].tf.poles)
    std::cout << "engine pole " << q.wn << " " << q.zeta << "\n";
  for (const Root& q : c.simulation.paths[0].tf.poles)
    std::cout << "sim pole " << q.wn << " " << q.zeta << "\n";
  const Diagnosis d = diagnose_lab_data(c.simulation, "modal_s17_c5");
  const std::string json = diagnosis_to_json(d).dump(1);
  for (const Finding& f : d.findings)
    for (const Param p : {Param::kToZeta, Param::kZeta})
      if (f.parameters.count(p)) {
        const double from =
            f.parameters.count(Param::kFromZeta) ? f.parameters.at(Param::kFromZeta) : INFINITY;
        EXPECT_GE(f.parameters.at(p), std::min(kZetaMin, from / 10) * (1 - 1e-9)) << json;
      }
  for (const ModelPath& path : d.extended.paths)
    for (const Root& r : path.tf.poles)
      EXPECT_TRUE(r.pair ? r.zeta > 0 : r.real < 0) << path.input << ":" << path.output << json;
}

// The same case: two modes moved across each other, 28.47 -> 29.85 rad/s (zeta 0.018 -> 0.052)
// and 30.00 -> 29.39 (zeta 0.036 -> 0.075), beside three unmoved ones. Each bounded by the other on
// the side the simulation has it, the first took both peaks to 29.87 and the second only a damping
// (0 of 2 effects found, 6 false findings). Fitted past each other, each is its own mode's
// finding, the truth within the self-check's tolerance, and nothing else.
TEST(Diagnose, TwoModesMovedAcrossEachOtherAreEachFoundAtTheirOwnModes) {
  const testing::RandomCase c = testing::random_modal_case(17, 5);
  const Diagnosis d = diagnose_lab_data(c.simulation, "modal_s17_c5");
  const testing::Score s = testing::score(c, d.findings);
  EXPECT_EQ(s.hidden, 2);
  EXPECT_EQ(s.found, s.hidden) << diagnosis_to_json(d).dump(1);
  EXPECT_EQ(s.true_findings, s.findings) << diagnosis_to_json(d).dump(1);
}

// The machine-shaped self-check's case 9 of seed 3 as the lab measured it (tests/data/lab/
// machine_s3_c9, its README says how): one input, two outputs, the slow mode moved 1.54 -> 2.63
// rad/s in both paths (the input's scope: every path of a one-input plant) and a 7.1 ms delay on
// the path into Y1. Both paths' own fits find the pole within the tolerance, so the input's
// finding forms at once from their mean, and Y1's fit of the overlap left the delay to a
// resonance at 122 rad/s near the top of the band. That pair, diagnosed again against the pole
// sized on Y0's path, shows the delay: two findings, each within its tolerance.
TEST(Diagnose, AScopesPairThatSplitAnOverlapIsDiagnosedAgainAgainstTheOthers) {
  constexpr double kPoleTol = 0.02, kDelayTolS = 0.5e-3;
  const auto& [c, d, json] = LabCase(3, 9);
  const testing::HiddenEffect* pole = nullptr;
  const testing::HiddenEffect* delay = nullptr;
  for (const auto& h : c.hidden) {
    if (h.cause == CauseKind::kPoleShift) pole = &h;
    if (h.cause == CauseKind::kTimeDelay && h.scope == Scope::kPath) delay = &h;
  }
  ASSERT_EQ(c.hidden.size(), 2u);
  ASSERT_NE(pole, nullptr);
  ASSERT_NE(delay, nullptr);
  ASSERT_EQ(d.findings.size(), 2u) << json;
  for (const Finding& f : d.findings) {
    if (f.cause == CauseKind::kPoleShift) {
      EXPECT_EQ(f.scope, pole->scope) << json;
      EXPECT_NEAR(f.parameters.at(Param::kToRadS) / pole->value, 1.0, kPoleTol) << json;
    } else {
      EXPECT_EQ(f.cause, CauseKind::kTimeDelay) << json;
      EXPECT_EQ(f.output, delay->output) << json;
      EXPECT_NEAR(f.parameters.at(Param::kDelayS), delay->value, kDelayTolS) << json;
    }
  }
}

// A scope's cause that its other pairs, diagnosed again, would undo is not that scope's. The
// machine-shaped self-check's case 5 of seed 1 as the lab measured it (tests/data/lab/
// machine_s1_c5: a 23.6 rad/s lag in Y0's sensor, nothing else): the lag taken to the plant
// leaves Y1's paths each wanting a lead at its corner (the two together 1 there, a pair that
// cancels); that refuses the plant's lag, and the sensor's lag is the one finding, nothing
// found or dropped beside it.
TEST(Diagnose, ALagAnotherOutputWouldUndoStaysAtItsOutput) {
  constexpr double kCornerTol = 0.05;
  const auto& [c, d, json] = LabCase(1, 5);
  ASSERT_EQ(c.hidden.size(), 1u);
  EXPECT_TRUE(d.dropped.empty()) << json;
  ASSERT_EQ(d.findings.size(), 1u) << json;
  const Finding& f = d.findings[0];
  EXPECT_EQ(f.cause, CauseKind::kMissingLag) << json;
  EXPECT_EQ(f.scope, Scope::kOutput) << json;
  EXPECT_EQ(f.output, c.hidden[0].output) << json;
  EXPECT_NEAR(f.parameters.at(Param::kCornerRadS) / c.hidden[0].value, 1.0, kCornerTol) << json;
}

// An output's sensor lag and delay together, on all three of its paths (tests/data/lab/
// machine_s7_c6: Y1's 18.99 rad/s lag and 14.6 ms delay, beside a 2.99 rad/s lag on U1 -> Y0).
// Each path's own fit takes the sensor for two resonances; the simpler alternatives make each a
// lag and a delay, and once those are sized together the output's pairs agree on both: two
// findings at the output, each within its tolerance, and no path finding into Y1.
TEST(Diagnose, AnOutputsLagAndDelayTogetherAreTheOutputsTwoFindings) {
  constexpr double kCornerTol = 0.02, kDelayTolS = 0.5e-3;
  const auto& [c, d, json] = LabCase(7, 6);
  const testing::HiddenEffect* lag = hidden_at(c, CauseKind::kMissingLag, Scope::kOutput);
  const testing::HiddenEffect* delay = hidden_at(c, CauseKind::kTimeDelay, Scope::kOutput);
  ASSERT_NE(lag, nullptr);
  ASSERT_NE(delay, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  int at_output = 0;
  for (const Finding& f : d.findings) {
    if (f.scope == Scope::kPath) {
      EXPECT_NE(f.output, lag->output) << json;
      continue;
    }
    ASSERT_EQ(f.scope, Scope::kOutput) << json;
    ASSERT_EQ(f.output, lag->output) << json;
    ++at_output;
    if (f.cause == CauseKind::kMissingLag)
      EXPECT_NEAR(f.parameters.at(Param::kCornerRadS) / lag->value, 1.0, kCornerTol) << json;
    else
      EXPECT_NEAR(f.parameters.at(Param::kDelayS), delay->value, kDelayTolS) << json;
  }
  EXPECT_EQ(at_output, 2) << json;
}

// An output's delay that one of its paths sized, another took for a lag and a third sized 30 %
// long (tests/data/lab/machine_s7_c21: Y3's 11.5 ms, beside calibrations at U1 and U2): the
// output's finding is tried from the one path, its other pairs diagnosed again against it, and
// kept on the criterion over the output's pairs: the output's delay within 0.5 ms, no path finding.
TEST(Diagnose, AnOutputsDelayOnePathSizedIsTheOutputsWhenItsOtherPathsAgree) {
  constexpr double kDelayTolS = 0.5e-3;
  const auto& [c, d, json] = LabCase(7, 21);
  const testing::HiddenEffect* delay = hidden_at(c, CauseKind::kTimeDelay, Scope::kOutput);
  ASSERT_NE(delay, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  for (const Finding& f : d.findings) EXPECT_NE(f.scope, Scope::kPath) << json;
  const Finding* found = found_of(d, CauseKind::kTimeDelay);
  ASSERT_NE(found, nullptr) << json;
  EXPECT_EQ(found->scope, Scope::kOutput) << json;
  EXPECT_EQ(found->output, delay->output) << json;
  EXPECT_NEAR(found->parameters.at(Param::kDelayS), delay->value, kDelayTolS) << json;
}

// An input's and an output's calibration that the first pass of the stages leaves as three path
// gains (tests/data/lab/machine_s9_c46: U1's -3.03 dB and Y1's +2.11 dB on a 2 x 2 plant, beside
// a 4.5 rad/s lag on U0 -> Y1): once 5e and the joint sizing are done, 5d runs again and names
// the two where they are, each within its tolerance, and no path gain.
TEST(Diagnose, AnInputsAndAnOutputsCalibrationsLeftAsPathGainsAreNamedOnTheSecondPass) {
  constexpr double kGainTolDb = 0.3;
  const auto& [c, d, json] = LabCase(9, 46);
  const testing::HiddenEffect* at_input = hidden_at(c, CauseKind::kGainMismatch, Scope::kInput);
  const testing::HiddenEffect* at_output = hidden_at(c, CauseKind::kGainMismatch, Scope::kOutput);
  ASSERT_NE(at_input, nullptr);
  ASSERT_NE(at_output, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  int gains = 0;
  for (const Finding& f : d.findings) {
    if (f.cause != CauseKind::kGainMismatch) continue;
    ++gains;
    ASSERT_NE(f.scope, Scope::kPath) << json;
    const testing::HiddenEffect* h = f.scope == Scope::kInput ? at_input : at_output;
    EXPECT_EQ(f.scope == Scope::kInput ? f.input : f.output,
              f.scope == Scope::kInput ? h->input : h->output)
        << json;
    EXPECT_NEAR(f.parameters.at(Param::kGainDb), h->value, kGainTolDb) << json;
  }
  EXPECT_EQ(gains, 2) << json;
}

// A plant's slow mode moved under an output's and an input's calibration (tests/data/lab/
// machine_s13_c27: 0.683 -> 1.29 rad/s in every path of a 3 x 2 plant, Y1's -2.46 dB and U1's
// +1.92 dB). Each path into Y1 fits the overlap as its own pole shift (1.29, 1.21 and 0.96 rad/s);
// the members' mean is off, and the path left out wants the pole moved again. Sized over every
// pair at once, each pair's gains found again around it, the mode is one finding, and the gains
// left on the paths are the output's and the input's: three findings, each within its tolerance.
TEST(Diagnose, APlantsModeUnderTwoCalibrationsIsSizedOverEveryPairAtOnce) {
  constexpr double kPoleTol = 0.01, kGainTolDb = 0.3;
  const auto& [c, d, json] = LabCase(13, 27);
  const testing::HiddenEffect* pole = hidden_at(c, CauseKind::kPoleShift, Scope::kPlant);
  const testing::HiddenEffect* at_input = hidden_at(c, CauseKind::kGainMismatch, Scope::kInput);
  const testing::HiddenEffect* at_output = hidden_at(c, CauseKind::kGainMismatch, Scope::kOutput);
  ASSERT_NE(pole, nullptr);
  ASSERT_NE(at_input, nullptr);
  ASSERT_NE(at_output, nullptr);
  ASSERT_EQ(d.findings.size(), c.hidden.size()) << json;
  for (const Finding& f : d.findings) {
    ASSERT_NE(f.scope, Scope::kPath) << json;
    if (f.cause == CauseKind::kPoleShift) {
      EXPECT_EQ(f.scope, Scope::kPlant) << json;
      EXPECT_NEAR(f.parameters.at(Param::kToRadS) / pole->value, 1.0, kPoleTol) << json;
      continue;
    }
    ASSERT_EQ(f.cause, CauseKind::kGainMismatch) << json;
    const testing::HiddenEffect* h = f.scope == Scope::kInput ? at_input : at_output;
    EXPECT_EQ(f.scope == Scope::kInput ? f.input : f.output,
              f.scope == Scope::kInput ? h->input : h->output)
        << json;
    EXPECT_NEAR(f.parameters.at(Param::kGainDb), h->value, kGainTolDb) << json;
  }
}

// An output's delay and one of its paths' own delay on top (tests/data/lab/machine_s13_c33: Y0's
// 7.6 ms on its three paths, U1 -> Y0 17.5 ms more, beside U1's actuator 2.5 times faster). The
// path's own delay is the output's cause again, but delays compose: the output's group stands
// with the path's remainder beside it, each within 0.5 ms.
TEST(Diagnose, AnOutputsDelayWithAPathsOwnDelayOnTopAreTwoFindings) {
  constexpr double kDelayTolS = 0.5e-3;
  const auto& [c, d, json] = LabCase(13, 33);
  const testing::HiddenEffect* at_output = hidden_at(c, CauseKind::kTimeDelay, Scope::kOutput);
  const testing::HiddenEffect* on_path = hidden_at(c, CauseKind::kTimeDelay, Scope::kPath);
  ASSERT_NE(at_output, nullptr);
  ASSERT_NE(on_path, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  int delays = 0;
  for (const Finding& f : d.findings) {
    if (f.cause != CauseKind::kTimeDelay) continue;
    ++delays;
    const testing::HiddenEffect* h = f.scope == Scope::kOutput ? at_output : on_path;
    ASSERT_EQ(f.scope, h->scope) << json;
    EXPECT_EQ(f.output, h->output) << json;
    if (f.scope == Scope::kPath) {
      EXPECT_EQ(f.input, h->input) << json;
    }
    EXPECT_NEAR(f.parameters.at(Param::kDelayS), h->value, kDelayTolS) << json;
  }
  EXPECT_EQ(delays, 2) << json;
}

// A short delay on one path whose data end below 1 / delay (tests/data/lab/machine_s14_c12: 5.4 ms
// on U0 -> Y1 of a one-input plant, the band ending at 82 rad/s, beside a path U0 -> Y0 the
// simulation lacks). The path's own fit takes the delay for a lag at 178 rad/s, above the band,
// whose gain the data barely see; the delay fits within one parameter's penalty of it and is
// named: the delay within 0.5 ms, no lag.
TEST(Diagnose, ALagAboveTheBandThatADelayFitsAsWellIsTheDelay) {
  constexpr double kDelayTolS = 0.5e-3;
  const auto& [c, d, json] = LabCase(14, 12);
  const testing::HiddenEffect* delay = hidden_at(c, CauseKind::kTimeDelay, Scope::kPath);
  ASSERT_NE(delay, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  EXPECT_EQ(found_of(d, CauseKind::kMissingLag), nullptr) << json;
  const Finding* found = found_of(d, CauseKind::kTimeDelay);
  ASSERT_NE(found, nullptr) << json;
  EXPECT_EQ(found->scope, Scope::kPath) << json;
  EXPECT_EQ(found->input, delay->input) << json;
  EXPECT_EQ(found->output, delay->output) << json;
  EXPECT_NEAR(found->parameters.at(Param::kDelayS), delay->value, kDelayTolS) << json;
}

// A one-input plant's -2.23 dB calibration beside lags on two of its four paths (tests/data/lab/
// machine_s16_c1). The group formed from the lagged paths is -2.74 dB; the other two paths,
// diagnosed again, keep +0.51 dB of their own, which composes with it, and are joined at the
// plant in turn. Two gains at one place are one effect: one plant gain, their sum, within 0.3 dB.
TEST(Diagnose, TwoGainsAtOnePlaceAreOneFindingTheirSum) {
  constexpr double kGainTolDb = 0.3;
  const auto& [c, d, json] = LabCase(16, 1);
  const testing::HiddenEffect* gain = hidden_at(c, CauseKind::kGainMismatch, Scope::kPlant);
  ASSERT_NE(gain, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  int gains = 0;
  for (const Finding& f : d.findings) {
    if (f.cause != CauseKind::kGainMismatch) continue;
    ++gains;
    EXPECT_EQ(f.scope, Scope::kPlant) << json;
    EXPECT_NEAR(f.parameters.at(Param::kGainDb), gain->value, kGainTolDb) << json;
  }
  EXPECT_EQ(gains, 1) << json;
}

// The slow mode moved in every path of a three-input, five-output plant beside 16.1 and 15.3 rad/s
// sensor lags at Y1 and Y2 (tests/data/lab/machine_s23_c11). Y1's paths' own fits split the lag
// and the mode's move into a smaller move and a resonance at 31-36 rad/s, zeta 0.76; with the
// plant's mode sized over every pair, Y1's paths moved that resonance past critical damping (to
// 580 rad/s, zeta 18: real poles at 16.1 and 20 900 rad/s), an output's pole shift of the root its
// own resonance added. The move of a root another finding at its place added is that finding
// moved: one finding, a lag at the slower pole where the faster lies far beyond the band. Every
// hidden effect is named at its place within its tolerance, and nothing else.
TEST(Diagnose, AMoveOfARootAnotherFindingAddedIsThatFindingMoved) {
  const auto& [c, d, json] = LabCase(23, 11);
  const testing::HiddenEffect* lag = hidden_at(c, CauseKind::kMissingLag, Scope::kOutput);
  ASSERT_NE(lag, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  for (const testing::HiddenEffect& h : c.hidden)
    EXPECT_TRUE(std::any_of(d.findings.begin(), d.findings.end(),
                            [&](const Finding& f) { return h.matches(f); }))
        << h.describe() << "\n"
        << json;
  for (const Finding& f : d.findings) EXPECT_NE(f.cause, CauseKind::kMissingResonance) << json;
}

// A one-input plant's path with a 26.4 rad/s lag and an 8.0 ms delay (tests/data/lab/
// machine_s27_c53). The path's own fit takes them for a 22.1 rad/s lag and a resonance at 91 rad/s,
// zeta 0.07; the delay that replaces the resonance fits only when the lag beside it is sized again
// with it (at 22.1 rad/s the delay is refused, and a lag at 103 rad/s would stand in for it). The
// alternatives are sized together with the findings on the resonance's pairs: the lag and the
// delay, each within its tolerance, and nothing else.
TEST(Diagnose, AResonancesAlternativeIsSizedWithTheFindingsBesideIt) {
  constexpr double kCornerTol = 0.05, kDelayTolS = 1e-3;
  const auto& [c, d, json] = LabCase(27, 53);
  const testing::HiddenEffect* lag = hidden_at(c, CauseKind::kMissingLag, Scope::kPath);
  const testing::HiddenEffect* delay = hidden_at(c, CauseKind::kTimeDelay, Scope::kPath);
  ASSERT_NE(lag, nullptr);
  ASSERT_NE(delay, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  const Finding* fl = found_of(d, CauseKind::kMissingLag);
  const Finding* fd = found_of(d, CauseKind::kTimeDelay);
  ASSERT_NE(fl, nullptr) << json;
  ASSERT_NE(fd, nullptr) << json;
  EXPECT_NEAR(fl->parameters.at(Param::kCornerRadS) / lag->value, 1, kCornerTol) << json;
  EXPECT_NEAR(fd->parameters.at(Param::kDelayS), delay->value, kDelayTolS) << json;
}

// A one-input plant's slow mode moved 1.58 -> 2.63 rad/s in every path, beside its actuator made
// faster and a 26 ms delay on one path (tests/data/lab/machine_s20_c11). The mode came back as two
// plant findings, 1.58 -> 2.60 and 2.60 -> 2.63 rad/s: the second moves the root the first placed.
// One root's two moves at one place are one finding: the mode moved to 2.63, within its
// tolerance, and every hidden effect named once.
TEST(Diagnose, TwoMovesOfOneRootAreOneFinding) {
  constexpr double kPoleTol = 0.01;
  const auto& [c, d, json] = LabCase(20, 11);
  const testing::HiddenEffect* mode = hidden_at(c, CauseKind::kPoleShift, Scope::kPlant);
  ASSERT_NE(mode, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  int plant_moves = 0;
  for (const Finding& f : d.findings) {
    if (f.cause != CauseKind::kPoleShift || f.scope != Scope::kPlant) continue;
    ++plant_moves;
    EXPECT_NEAR(f.parameters.at(Param::kToRadS) / mode->value, 1, kPoleTol) << json;
  }
  EXPECT_EQ(plant_moves, 1) << json;
}

// An input's -2.75 dB calibration on its two paths beside a 9.77 rad/s lag on one of them
// (tests/data/lab/machine_s19_c35). The lagged path's own fit splits the two as -2.42 dB and a
// moved pole; the group from it, tried first, is refused. The group from the other path's -2.75
// dB is another group and is tried too: the input's gain and the path's lag, each within its
// tolerance, beside the third effect (U1's actuator).
TEST(Diagnose, AnInputsGainIsTriedFromThePathThatDidNotSplitIt) {
  constexpr double kGainTolDb = 0.3, kCornerTol = 0.1;
  const auto& [c, d, json] = LabCase(19, 35);
  const testing::HiddenEffect* gain = hidden_at(c, CauseKind::kGainMismatch, Scope::kInput);
  const testing::HiddenEffect* lag = hidden_at(c, CauseKind::kMissingLag, Scope::kPath);
  ASSERT_NE(gain, nullptr);
  ASSERT_NE(lag, nullptr);
  EXPECT_EQ(d.findings.size(), c.hidden.size()) << json;
  const Finding* found_gain = found_of(d, CauseKind::kGainMismatch);
  const Finding* found_lag = found_of(d, CauseKind::kMissingLag);
  ASSERT_NE(found_gain, nullptr) << json;
  ASSERT_NE(found_lag, nullptr) << json;
  EXPECT_EQ(found_gain->scope, Scope::kInput) << json;
  EXPECT_EQ(found_gain->input, gain->input) << json;
  EXPECT_NEAR(found_gain->parameters.at(Param::kGainDb), gain->value, kGainTolDb) << json;
  EXPECT_EQ(found_lag->scope, Scope::kPath) << json;
  EXPECT_EQ(found_lag->output, lag->output) << json;
  EXPECT_NEAR(found_lag->parameters.at(Param::kCornerRadS) / lag->value, 1.0, kCornerTol) << json;
}

// The machine-shaped self-check's case 13 of seed 4 as the lab measured it (tests/data/lab/
// machine_s4_c13): an 8.6 ms delay in Y2's sensor, beside the slow mode moved in every path and
// Y3's -1.55 dB. The band ends at 82 rad/s, where the delay is 41 degrees of phase; each path
// into Y2 fitted it as a resonance at 104 rad/s, zeta 0.38, whose gain the band barely sees.
// Over the output's pairs a delay fits as well with one parameter fewer: the output's delay,
// within 0.5 ms, and no resonance.
TEST(Diagnose, AResonanceAboveTheBandThatADelayFitsIsTheDelay) {
  constexpr double kDelayTolS = 0.5e-3;
  const auto& [c, d, json] = LabCase(4, 13);
  const testing::HiddenEffect* delay = nullptr;
  for (const auto& h : c.hidden)
    if (h.cause == CauseKind::kTimeDelay) delay = &h;
  ASSERT_NE(delay, nullptr);
  ASSERT_EQ(delay->scope, Scope::kOutput);
  EXPECT_EQ(found_of(d, CauseKind::kMissingResonance), nullptr) << json;
  const Finding* found = found_of(d, CauseKind::kTimeDelay);
  ASSERT_NE(found, nullptr) << json;
  EXPECT_EQ(found->scope, Scope::kOutput) << json;
  EXPECT_EQ(found->output, delay->output) << json;
  EXPECT_NEAR(found->parameters.at(Param::kDelayS), delay->value, kDelayTolS) << json;
  int true_findings = 0;
  for (const Finding& f : d.findings)
    for (const auto& h : c.hidden) true_findings += h.matches(f);
  EXPECT_EQ(true_findings, int(d.findings.size())) << json;
}

// The machine-shaped self-check's case 33 of seed 3 as the lab measured it (tests/data/lab/
// machine_s3_c33): one input, two outputs; the input's calibration 2.15 dB low and its slow mode
// moved 0.461 -> 1.128 rad/s, and a 9.6 rad/s lag on the path into Y0. The band starts above the
// slow mode, so Y0's own fit trades the gain for the pole (0.83 rad/s, no gain, the lag at 12.5);
// Y1's finds both right. As many findings either way after Y0 is diagnosed again against Y1's
// pole (a gain and the lag), but a better fit: the pole joins the input, then the gain: three
// findings, each within its tolerance.
TEST(Diagnose, AOneInputsCalibrationAndModeAreTheInputsBesideOnePathsLag) {
  const auto& [c, d, json] = LabCase(3, 33);
  ASSERT_EQ(c.hidden.size(), 3u);
  ASSERT_EQ(d.findings.size(), c.hidden.size()) << json;
  for (const auto& h : c.hidden) {
    int matched = 0;
    for (const Finding& f : d.findings) matched += h.matches(f);
    EXPECT_EQ(matched, 1) << to_string(h.cause) << " " << to_string(h.scope) << "\n" << json;
  }
}

// The machine-shaped self-check's case 0 of seed 5, measured offline: one input, four outputs;
// the input's calibration +1.81 dB (every path: the plant's) and Y1's +1.80 dB (its one path:
// the path's), so U0:Y1 holds their sum. The additive stage explains the totals by an input
// carrier and an output carrier, each named by the pairs it covers: the plant's and the path's.
TEST(Diagnose, AnAdditiveCarrierIsNamedByThePairsItCovers) {
  const testing::RandomCase c = testing::random_machine_case(5, 0);
  const Diagnosis d = diagnose(c.simulation, measure_machine_case(c, 0.0));
  const std::string json = diagnosis_to_json(d).dump(1);
  int gains = 0;
  for (const auto& h : c.hidden) {
    if (h.cause != CauseKind::kGainMismatch) continue;
    ++gains;
    int matched = 0;
    for (const Finding& f : d.findings) matched += h.matches(f);
    EXPECT_EQ(matched, 1) << to_string(h.scope) << " " << h.output << "\n" << json;
  }
  EXPECT_EQ(gains, 2) << json;
}

// The self-check's generator: an output's delay and its one path's delay on a one-input plant
// (seed 6, case 46) are one delay on that path, their sum, as the engine holds it (the sensor's
// delay and the path's add on the one pair); no measurement tells the two apart.
TEST(Diagnose, TheGeneratorsTwoDelaysAtOnePlaceAreOneEffect) {
  const testing::RandomCase c = testing::random_machine_case(6, 46);
  ASSERT_EQ(c.engine.inputs.size(), 1u);
  std::vector<const testing::HiddenEffect*> delays;
  for (const auto& h : c.hidden)
    if (h.cause == CauseKind::kTimeDelay) delays.push_back(&h);
  ASSERT_EQ(delays.size(), 1u);
  const testing::HiddenEffect& d = *delays[0];
  EXPECT_EQ(d.scope, Scope::kPath);
  const ModelOutput& o = c.engine.outputs[size_t(c.engine.output_index(d.output))];
  const double engine_delay = c.engine.path(d.output, d.input)->tf.delay_s +
                              (o.sensor ? o.sensor->delay_s : 0.0) -
                              c.simulation.path(d.output, d.input)->tf.delay_s;
  EXPECT_NEAR(d.value, engine_delay, 1e-12);
  EXPECT_GT(d.value, 0.025);  // 5.4 + 20.5 ms
}

// A damping_error read from a file for a pair the model does not hold, without the from_zeta its
// factor needs, is an error naming the cause and the frequency, not a crash.
TEST(Diagnose, ADampingErrorWithoutItsPairOrFromZetaIsAnError) {
  Finding f;
  f.cause = CauseKind::kDampingError;
  f.scope = Scope::kPath;
  f.input = "u";
  f.output = "y";
  f.pairs = {"u:y"};
  f.parameters = {{Param::kWnRadS, 77.0}, {Param::kToZeta, 0.2}};
  EXPECT_THAT([&] { extend_model(simulation(), {f}); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("damping_error at 77 rad/s")));
  f.parameters[Param::kFromZeta] = 0.5;  // with it, the factor D_sim / D is added
  const Model ext = extend_model(simulation(), {f});
  const Complex ratio = *model_pair_response(ext, "u:y", 77.0, 0.02) /
                        *model_pair_response(simulation(), "u:y", 77.0, 0.02);
  EXPECT_NEAR(std::abs(ratio), 0.5 / 0.2, 1e-9);  // at wn: |D_sim / D| = zeta_sim / zeta
}

// A curve whose points carry no sigma cannot be weighed: the diagnosis says which pair, instead of
// leaving it out and reporting that everything agrees. Measured curves with their sigma are
// diagnosed as before.
TEST(Diagnose, ACurveWithoutSigmaIsAnErrorNamingItsPair) {
  Model truth = simulation();
  truth.paths[0].tf.gain *= 2;
  std::vector<MeasuredPair> data = measure(truth);
  ASSERT_NO_THROW(diagnose(simulation(), data));
  for (MeasuredPair& mp : data)
    if (mp.pair == "u:y")
      for (FrdPoint& p : mp.frd.points) p.sigma = -1;  // unknown, as a file without it reads
  EXPECT_THAT([&] { diagnose(simulation(), data); },
              ::testing::ThrowsMessage<InputError>(
                  ::testing::AllOf(HasSubstr("u:y"), HasSubstr("carries a sigma"))));
}

TEST(Diagnose, ActuatorPoleShiftIsTheInputs) {
  Model truth = simulation();
  truth.inputs[0].actuator = tf(1.0, {Root::Real(-35)});
  const Diagnosis d = diagnose(simulation(), measure(truth));
  EXPECT_THAT(d.findings, ElementsAre(Field(&Finding::cause, CauseKind::kPoleShift)));
  const Finding f = only_finding(d);
  EXPECT_EQ(f.scope, Scope::kInput);
  EXPECT_EQ(f.input, "u");
  EXPECT_NEAR(f.parameters.at(Param::kToRadS), 35, 0.03 * 35);
  EXPECT_THAT(f.explanation, HasSubstr("in the actuator's own response u_u:u"));
  // The extended model's actuator carries the moved pole.
  EXPECT_NEAR(-d.extended.inputs[0].actuator->poles.at(0).real, 35, 0.03 * 35);
}

// A resonance moves as a whole: the pair of z's path at 30 rad/s, damped 0.3 in the simulation, at
// 36 rad/s damped 0.15 in the truth. One pole_shift carries both (no damping_error claims the same
// pair), the damping's 1-sigma interval holds the truth and excludes the simulation's, and the
// extended model has the moved pair.
TEST(Diagnose, APairsPoleShiftFitsItsDamping) {
  constexpr double kWnTol = 0.01, kZetaTol = 0.03;
  Model truth = simulation();
  path(truth, "z").tf.poles[1] = Root::Pair(36, 0.15);
  const Diagnosis d = diagnose(simulation(), measure(truth));
  const Finding f = only_finding(d);
  EXPECT_EQ(f.cause, CauseKind::kPoleShift);
  EXPECT_EQ(f.output, "z");
  EXPECT_NEAR(f.parameters.at(Param::kFromRadS), 30, 1e-12);
  EXPECT_NEAR(f.parameters.at(Param::kToRadS) / 36, 1.0, kWnTol);
  EXPECT_NEAR(f.parameters.at(Param::kFromZeta), 0.3, 1e-12);
  EXPECT_NEAR(f.parameters.at(Param::kToZeta) / 0.15, 1.0, kZetaTol);
  EXPECT_EQ(f.parameters.at(Param::kZeta), f.parameters.at(Param::kToZeta));
  ASSERT_TRUE(f.intervals.count(Param::kToZeta));
  EXPECT_LT(f.intervals.at(Param::kToZeta)[0], 0.15 * (1 + kZetaTol));
  EXPECT_GT(f.intervals.at(Param::kToZeta)[1], 0.15 * (1 - kZetaTol));
  EXPECT_LT(f.intervals.at(Param::kToZeta)[1], 0.3);
  EXPECT_THAT(f.explanation, HasSubstr("damped"));
  for (const auto& p : d.extended.paths) {
    if (p.output == "z") {
      EXPECT_NEAR(p.tf.poles[1].wn / 36, 1.0, kWnTol);
      EXPECT_NEAR(p.tf.poles[1].zeta / 0.15, 1.0, kZetaTol);
    }
  }
}

// A pair moved at its simulated damping: the damping is not fitted (the second parameter does not
// lower chi2 by its penalty), to_zeta stays the simulation's, and the finding says so.
TEST(Diagnose, APairsPoleShiftKeepsADampingTheDataDoNotResolve) {
  Model truth = simulation();
  path(truth, "z").tf.poles[1] = Root::Pair(36, 0.3);
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(f.cause, CauseKind::kPoleShift);
  EXPECT_NEAR(f.parameters.at(Param::kToRadS) / 36, 1.0, 0.01);
  EXPECT_EQ(f.parameters.at(Param::kToZeta), f.parameters.at(Param::kFromZeta));
  EXPECT_EQ(f.parameters.at(Param::kToZeta), 0.3);
  EXPECT_THAT(f.explanation, HasSubstr("the simulated damping 0.3 is kept"));
  ASSERT_TRUE(f.intervals.count(Param::kToZeta));
  EXPECT_LT(f.intervals.at(Param::kToZeta)[0], 0.3);
  EXPECT_GT(f.intervals.at(Param::kToZeta)[1], 0.3);
}

TEST(Diagnose, MissingResonancePeak) {
  Model truth = simulation();
  path(truth, "y").tf.poles.push_back(Root::Pair(12, 0.1));
  const Finding f = only_finding(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(f.cause, CauseKind::kMissingResonance);
  EXPECT_NEAR(f.parameters.at(Param::kWnRadS), 12, 0.03 * 12);
  EXPECT_NEAR(f.parameters.at(Param::kZeta), 0.1, 0.02);
  EXPECT_EQ(f.text_parameters.count("shape"), 0u);
}

TEST(Diagnose, MissingResonanceNotch) {
  Model truth = simulation();
  path(truth, "y").tf.zeros.push_back(Root::Pair(12, 0.1));
  const Diagnosis d = diagnose(simulation(), measure(truth));
  const Finding f = only_finding(d);
  EXPECT_EQ(f.cause, CauseKind::kMissingResonance);
  EXPECT_EQ(f.text_parameters.at("shape"), "notch");
  EXPECT_NEAR(f.parameters.at(Param::kWnRadS), 12, 0.03 * 12);
  // The notch extends the path's zeros, not its poles.
  const Model& ext = d.extended;
  for (const auto& p : ext.paths) {
    if (p.output == "y") {
      EXPECT_EQ(p.tf.zeros.size(), 1u);
    }
  }
}

TEST(Diagnose, ActuatorBacklashFromItsDescribingFunction) {
  Model truth = simulation();
  truth.inputs[0].nonlinearity.push_back({NonlinearityKind::kHysteresis, 0.012});
  const Diagnosis d = diagnose(simulation(), measure(truth, /*h3=*/0.05));
  ASSERT_FALSE(d.findings.empty());
  const Finding& f = d.findings.at(0);
  EXPECT_EQ(f.cause, CauseKind::kHysteresis);
  EXPECT_EQ(f.input, "u");
  EXPECT_NEAR(f.parameters.at(Param::kWidth), 0.012, 0.05 * 0.012);
  EXPECT_THAT(f.explanation, HasSubstr("describing function of a hysteresis"));
  EXPECT_LT(d.error_after, 0.2 * d.error_before);
  // Validated at another amplitude, where the describing function is another: the width found
  // predicts it too, to its noise.
  EXPECT_LT(d.validation_after, 0.2 * d.validation_before);
  EXPECT_LT(d.validation_after, kAtTheNoise * kRelSigma);
}

// A backlash measured by a multisine is fitted with its best linear approximation under
// that multisine, and comes out as it does from a sine. The truth: the simulation's actuator
// (20 rad/s) moved to `pole` with a backlash of `width`, the command's rms 0.028; measured through
// the lab's own code (make_campaign's multisine, 4 random-phase realisations of 2 periods, the
// plant with its noise, the pair analyser), validation on another seed. Returns the diagnosis.
Diagnosis multisine_backlash(double width, double pole) {
  Model truth = simulation();
  truth.inputs[0].actuator = tf(1.0, {Root::Real(-pole)});
  truth.inputs[0].nonlinearity.push_back({NonlinearityKind::kHysteresis, width});
  for (auto& o : truth.outputs) o.noise_rms = 1e-4;
  const AcquireOptions o = testing::random_phase_multisine("0.1:30", 8, 4, 4);
  auto run = [&](uint64_t seed) {
    return testing::analyse_run(testing::simulate_campaign(truth, o, true, seed),
                                {"u_u:u", "u:y", "u:z"});
  };
  const auto fit = run(1), val = run(2);
  std::vector<MeasuredPair> data;
  for (size_t i = 0; i < fit.size(); ++i) data.push_back({fit[i].pair, fit[i], val[i], 0, {}});
  return diagnose(simulation(), data);
}

// The J85's A8 case: a backlash of width 0.03 at a command rms of 0.028 and the actuator three
// times faster than simulated. The hysteresis within 5 % and the actuator's pole within 2 % (the
// J85 diagnosis's tolerances, diagnose_integration_test); the extended model better than the
// simulation (by less than the exact-data tests above: what remains is the distortion's scatter).
TEST(Diagnose, ActuatorBacklashFromItsMultisineBla) {
  const Diagnosis d = multisine_backlash(0.03, 60);
  const Finding* nl = nullptr;
  const Finding* shift = nullptr;
  for (const Finding& f : d.findings) {
    if (f.cause == CauseKind::kHysteresis) nl = &f;
    if (f.cause == CauseKind::kPoleShift && f.input == "u") shift = &f;
  }
  ASSERT_NE(nl, nullptr);
  ASSERT_NE(shift, nullptr);
  EXPECT_NEAR(nl->parameters.at(Param::kWidth), 0.03, 0.05 * 0.03);
  EXPECT_NEAR(shift->parameters.at(Param::kToRadS), 60, 0.02 * 60);
  EXPECT_THAT(nl->explanation, HasSubstr("best linear approximation of a hysteresis"));
  EXPECT_LT(d.validation_after, 0.5 * d.validation_before);
}

// Random cases (width 0.3-1.5 of the rms, the actuator 0.5-4 times the simulated speed, seed 13):
// what holds on plants not hand-picked is weaker. Each time a hysteresis is named and the
// extended model at least halves the simulation's validation error; the width comes out within
// 20 % in 3 of the 4 (measured: -16, -3.5 and -7.4 %; the pole within 1.5 and 5 %, and for the
// first, 23.2 rad/s, 16 % from the simulated 20, not found: the width took it up); the fourth,
// an actuator slower than simulated with a backlash wider than the rms, settles on a far slower
// actuator with a narrow backlash (3.3 rad/s and 0.0036 for 12.8 and 0.041): the two look alike
// from afar and the passes start from the simulated actuator.
TEST(Diagnose, ActuatorBacklashFromItsMultisineBlaOnRandomCases) {
  std::mt19937_64 g(13);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int within = 0;
  for (int k = 0; k < 4; ++k) {
    const double width = 0.028 * (0.3 + 1.2 * u(g));
    const double pole = 20 * std::exp(std::log(0.5) + u(g) * std::log(8));
    const Diagnosis d = multisine_backlash(width, pole);
    const Finding* nl = nullptr;
    for (const Finding& f : d.findings)
      if (f.cause == CauseKind::kHysteresis) nl = &f;
    ASSERT_NE(nl, nullptr) << width << " " << pole;
    within += std::abs(nl->parameters.at(Param::kWidth) / width - 1) < 0.2;
    EXPECT_LT(d.validation_after, 0.5 * d.validation_before) << width << " " << pole;
  }
  EXPECT_GE(within, 3);
}

TEST(Diagnose, DampingErrorOfASimulatedPair) {
  Model truth = simulation();
  path(truth, "z").tf.poles[1] = Root::Pair(30, 0.08);  // the simulation says 0.3
  const Diagnosis d = diagnose(simulation(), measure(truth));
  const Finding f = only_finding(d);
  EXPECT_EQ(f.cause, CauseKind::kDampingError);
  EXPECT_EQ(f.output, "z");
  EXPECT_NEAR(f.parameters.at(Param::kWnRadS), 30, 1e-12);
  EXPECT_NEAR(f.parameters.at(Param::kToZeta), 0.08, 0.1 * 0.08);
  for (const auto& p : d.extended.paths) {
    if (p.output == "z") {
      EXPECT_NEAR(p.tf.poles[1].zeta, 0.08, 0.1 * 0.08);
    }
  }
}

TEST(Diagnose, SignError) {
  Model truth = simulation();
  path(truth, "y").tf.gain = -path(truth, "y").tf.gain;
  const Diagnosis d = diagnose(simulation(), measure(truth));
  const Finding f = only_finding(d);
  EXPECT_EQ(f.cause, CauseKind::kSignError);
  EXPECT_EQ(f.output, "y");
  EXPECT_LT(d.error_after, 1e-6);
}

TEST(Diagnose, NamesAtTheEdgeRoundTrip) {
  for (CauseKind c :
       {CauseKind::kTimeDelay, CauseKind::kMissingLag, CauseKind::kMissingLead,
        CauseKind::kMissingResonance, CauseKind::kPoleShift, CauseKind::kGainMismatch,
        CauseKind::kHysteresis, CauseKind::kDeadband, CauseKind::kMeasurementCoupling})
    EXPECT_EQ(cause_from_string(to_string(c)), c);
  for (Scope s : {Scope::kPath, Scope::kOutput, Scope::kInput, Scope::kPlant})
    EXPECT_EQ(scope_from_string(to_string(s)), s);
  EXPECT_THROW(cause_from_string("time-delay"), InputError);
  EXPECT_THROW(scope_from_string("sensor"), InputError);
}

TEST(Diagnose, JsonKeepsTheContractsNames) {
  Model truth = simulation();
  path(truth, "y").tf.delay_s = 0.011;
  const Json j = diagnosis_to_json(diagnose(simulation(), measure(truth)));
  EXPECT_EQ(j["format"], "fralab-diagnosis/1");
  EXPECT_EQ(j["findings"][0]["cause"], "time_delay");
  EXPECT_EQ(j["findings"][0]["scope"], "path");
  EXPECT_EQ(j["findings"][0]["input"], "u");
  EXPECT_TRUE(j["summary"].contains("validation_error_after"));
}

TEST(Diagnose, OptionsAreValidated) {
  DiagnoseOptions o;
  o.delay_min_s = 0.1;
  o.delay_max_s = 0.05;
  EXPECT_THROW(o.validate(), InputError);
  o = {};
  o.pole_shift_range = 1.0;
  EXPECT_THROW(o.validate(), InputError);
  o = {};
  o.min_improvement = 1.5;
  EXPECT_THROW(diagnose(simulation(), measure(simulation()), o), InputError);
}

// A delay beyond the searched range cannot be found: the range is the option's, not a constant.
TEST(Diagnose, DelaySearchRangeIsAnOption) {
  Model truth = simulation();
  path(truth, "y").tf.delay_s = 0.08;
  DiagnoseOptions o;
  o.delay_max_s = 0.1;
  const Diagnosis d = diagnose(simulation(), measure(truth), o);
  ASSERT_EQ(d.findings.size(), 1u);
  EXPECT_EQ(d.findings[0].cause, CauseKind::kTimeDelay);
  EXPECT_NEAR(d.findings[0].parameters.at(Param::kDelayS), 0.08, 0.5e-3);
}

// A fit that the independent validation measurement does not confirm is dropped, with the figures:
// here the fitting run saw a +1 dB gain on u:y that the validation run (the simulation's truth)
// does not.
TEST(Diagnose, AFindingTheValidationDoesNotConfirmIsDropped) {
  Model seen = simulation();
  path(seen, "y").tf.gain *= std::pow(10.0, 1.0 / 20);
  auto data = measure(seen);
  const auto truth = measure(simulation());
  for (size_t i = 0; i < data.size(); ++i) data[i].validation = truth[i].validation;
  const Diagnosis d = diagnose(simulation(), data);
  EXPECT_THAT(d.findings, IsEmpty());
  ASSERT_EQ(d.dropped.size(), 1u);
  EXPECT_EQ(d.dropped[0].finding.cause, CauseKind::kGainMismatch);
  EXPECT_THAT(d.dropped[0].reason, HasSubstr("does not lower the validation error"));
  EXPECT_LE(d.validation_after, d.validation_before);  // never worse than the simulation
  EXPECT_EQ(diagnosis_to_json(d)["dropped"][0]["cause"], "gain_mismatch");
}

// A residual no cause of the catalogue describes (a gain ripple across the band) is reported as
// unexplained with its band, not forced into findings that leave it beyond the uncertainty.
// Without a validation measurement a finding earns its place on the data fitted (its removal must
// raise chi2 by more than its penalty and raise the error): a real effect stays, and the noise of a
// measurement of the simulation itself leaves nothing reported.
TEST(Diagnose, WithoutValidationAFindingEarnsItsPlaceOnTheDataFitted) {
  Model truth = simulation();
  path(truth, "y").tf.gain *= std::pow(10.0, 1.0 / 20);  // +1 dB
  std::vector<MeasuredPair> data = measure(truth);
  for (auto& mp : data) mp.validation.points.clear();
  const Diagnosis d = diagnose(simulation(), data);
  ASSERT_EQ(d.findings.size(), 1u);
  EXPECT_EQ(d.findings[0].cause, CauseKind::kGainMismatch);
  EXPECT_NEAR(d.findings[0].parameters.at(Param::kGainDb), 1.0, 0.05);
  EXPECT_THAT(d.dropped, IsEmpty());
  EXPECT_EQ(d.validation_after, -1);
  std::vector<MeasuredPair> noisy = measure(simulation());
  for (auto& mp : noisy) {
    mp.frd = mp.validation;
    mp.validation.points.clear();
  }
  EXPECT_THAT(diagnose(simulation(), noisy).findings, IsEmpty());
}

TEST(Diagnose, WhatTheCatalogueCannotExplainIsSaid) {
  auto data = measure(simulation());
  for (auto& mp : data) {
    if (mp.pair != "u:y") continue;
    for (auto* f : {&mp.frd, &mp.validation})
      for (auto& p : f->points) p.mag *= 1.0 + 0.2 * std::sin(4 * std::log(p.w));
  }
  const Diagnosis d = diagnose(simulation(), data);
  ASSERT_EQ(d.unexplained.size(), 1u);
  const Unexplained& u = d.unexplained[0];
  EXPECT_EQ(u.pair, "u:y");
  EXPECT_GE(u.band_hz[0], 0.05 / (2 * M_PI) - 1e-12);
  EXPECT_LE(u.band_hz[1], 200 / (2 * M_PI) + 1e-9);
  EXPECT_GT(u.band_hz[1], u.band_hz[0]);
  EXPECT_GT(u.residual, 0.05);
  EXPECT_FALSE(u.explanation.empty());
  const Json j = diagnosis_to_json(d);
  EXPECT_EQ(j["unexplained"][0]["pair"], "u:y");
  EXPECT_EQ(j["unexplained"][0]["band_hz"].size(), 2u);
}

// Data as fralab's plant emulator measures an engine identical to the simulation: every chain held
// by the first-order hold at 1 kHz and sampled (lti.h's exact sampled response, images included),
// 0.1-100 Hz, clean channels (sigma 0.1 %): exact to fit, the validation at kValidationAmplitude
// with noise of that sigma (seed kValidationSeed).
constexpr double kEmulatedRelSigma = 1e-3;
std::vector<MeasuredPair> emulated(const Model& m) {
  const Tf act = *m.inputs[0].actuator;
  std::mt19937_64 rng(kValidationSeed);
  std::vector<MeasuredPair> out;
  for (const std::string pair : {"u:y", "u:z", "u_u:u"}) {
    MeasuredPair mp;
    mp.pair = mp.frd.pair = mp.validation.pair = pair;
    const auto [e1, e2] = split_pair(pair);
    for (int k = 0; k <= 30; ++k) {
      const double w = 2 * M_PI * 0.1 * std::pow(10.0, k / 10.0);
      const Complex a = foh_sampled_response(act, w, 1000.0);
      Complex g = a;
      if (e2 != "u") {
        Tf chain = path(const_cast<Model&>(m), e2).tf;
        chain.poles.insert(chain.poles.end(), act.poles.begin(), act.poles.end());
        g = foh_sampled_response(chain, w, 1000.0) / a;
      }
      FrdPoint p;
      p.w = w;
      p.mag = std::abs(g);
      p.phase_deg = std::arg(g) * 180 / M_PI;
      p.sigma = kEmulatedRelSigma * p.mag;
      p.amplitude = kAmplitude;
      mp.frd.points.push_back(p);
      const Complex v = with_noise(g, p.sigma, rng);
      p.mag = std::abs(v);
      p.phase_deg = std::arg(v) * 180 / M_PI;
      p.amplitude = kValidationAmplitude;
      mp.validation.points.push_back(p);
    }
    out.push_back(mp);
  }
  return out;
}

// The lab's own hold (-0.28 dB at 100 Hz on the actuator pair) is not an engine effect: with the
// chain the run recorded, nothing is found; compared ideally, the hold is blamed on the actuator.
TEST(Diagnose, TheLabsOwnHoldIsNeverAFinding) {
  const Model sim = simulation();
  const auto data = emulated(sim);
  DiagnoseOptions o;
  o.chain.sample_rate_hz = 1000;
  o.chain.hold = MeasurementChain::Hold::kFirstOrder;
  const Diagnosis d = diagnose(sim, data, o);
  EXPECT_THAT(d.findings, IsEmpty());
  for (const auto& p : d.pairs) EXPECT_FALSE(p.beyond) << p.pair;
  EXPECT_EQ(diagnosis_to_json(d)["measurement_chain"]["hold"], "first_order");
  // With the chain, the simulation predicts the validation measurement to its noise.
  EXPECT_LT(d.validation_before, kAtTheNoise * kEmulatedRelSigma);
  EXPECT_GT(d.validation_before, kEmulatedRelSigma / kAtTheNoise);
  const Diagnosis ideal = diagnose(sim, data);
  EXPECT_FALSE(ideal.findings.empty());  // the artefact the chain removes
  // Compared ideally, the hold is beyond the noise of the validation measurement too.
  EXPECT_GT(ideal.validation_before, 2 * kAtTheNoise * kEmulatedRelSigma);
}

TEST(Diagnose, HoldFactorsAreTheHeadersEquations) {
  MeasurementChain c;
  EXPECT_EQ(c.command_factor(600.0), Complex(1.0));  // ideal
  c.sample_rate_hz = 1000;
  const double w = 2 * M_PI * 100, x = w / 2000;
  EXPECT_NEAR(std::abs(c.command_factor(w)), std::pow(std::sin(x) / x, 2), 1e-15);
  EXPECT_NEAR(20 * std::log10(std::abs(c.command_factor(w))), -0.287, 0.001);
  EXPECT_EQ(std::arg(c.command_factor(w)), 0.0);
  c.hold = MeasurementChain::Hold::kZeroOrder;
  EXPECT_NEAR(std::arg(c.command_factor(w)), -x, 1e-15);  // half a sample
  EXPECT_EQ(c.pair_factor("u", w), Complex(1.0));         // X:O: cancels
  c.reheld_inputs = {"u"};
  EXPECT_EQ(c.pair_factor("u", w), c.command_factor(w));
  const MeasurementChain back = chain_from_json(chain_to_json(c), {"t", ""});
  EXPECT_EQ(back.hold, MeasurementChain::Hold::kZeroOrder);
  EXPECT_EQ(back.reheld_inputs, c.reheld_inputs);
  EXPECT_THROW(
      chain_from_json(Json::parse(R"({"sample_rate_hz": 1000, "hold": "cubic"})"), {"t", ""}),
      InputError);
}

}  // namespace
}  // namespace fralab
