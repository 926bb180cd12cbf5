#include "fralab/diagnose/data_faults.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>

#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"

namespace fralab {
namespace {

constexpr std::pair<DataAlternative::Kind, const char*> kKindWords[] = {
    {DataAlternative::Kind::kWiringSign, "wiring_sign"},
    {DataAlternative::Kind::kUnits, "units"},
    {DataAlternative::Kind::kSwap, "swap"},
    {DataAlternative::Kind::kClipping, "clipping"},
    {DataAlternative::Kind::kDeadChannel, "dead_channel"},
    {DataAlternative::Kind::kClock, "clock"}};

// A silent output: its points hold no more than noise (at most this share above kNoiseSigmas)
// where the simulation expects at least kExpectedShare of them (and kMinExpected) above
// kExpectedSigmas. A complex Gaussian of standard deviation sigma exceeds 3 sigma in about 1 %
// of the points.
constexpr double kNoiseSigmas = 3, kSilentShare = 0.2;
constexpr double kExpectedSigmas = 10, kExpectedShare = 0.5;
constexpr int kMinExpected = 5;

struct UnitsFactor {
  double factor;
  const char* what;  // "A read as B": a channel in A taken for B multiplies by factor
};
constexpr UnitsFactor kUnits[] = {{6.894757, "psi and kPa"},
                                  {14.50377, "bar and psi"},
                                  {100.0, "bar and kPa, or % and a fraction"},
                                  {3.386389, "inHg and kPa"},
                                  {1.8, "degF (degR) and degC (K)"},
                                  {25.4, "in and mm"},
                                  {2.54, "in and cm"},
                                  {3.280840, "ft and m"},
                                  {2.204623, "lb and kg"},
                                  {4.448222, "lbf and N"},
                                  {9.549297, "rpm and rad/s"},
                                  {60.0, "rpm and Hz"},
                                  {57.29578, "deg and rad"},
                                  {6.4516, "in^2 and cm^2"},
                                  {10.76391, "ft^2 and m^2"},
                                  {7936.641, "lb/h and kg/s"},
                                  {1000.0, "a unit and its kilo-unit"}};

// Two outputs look exchanged when their exchanged errors sum to less than this share of the
// straight ones (and neither exceeds half the smaller straight one): the J85's P3 and P5
// exchanged give 0.25, its other pairs of outputs 1.1-15.
constexpr double kSwapRatio = 0.35;

std::string channel_of(const Finding& f) {
  if (f.scope == Scope::kOutput) return f.output;
  if (f.scope == Scope::kInput) return f.input;
  return "";
}

// rms over points of |ln(measured O / model O')| for every measured pair X:O with a path X -> O'.
double exchanged_error(const Model& sim, const std::vector<MeasuredPair>& data,
                       const std::string& o, const std::string& other, const DiagnoseOptions& opt) {
  double s = 0;
  int n = 0;
  for (const MeasuredPair& mp : data) {
    const PairId id = PairId::parse(mp.pair);
    if (id.output != o || id.command) continue;
    PairId swapped = id;
    swapped.output = other;
    for (const FrdPoint& p : mp.frd.points) {
      if (!p.valid || p.mag == 0) continue;
      const auto m = model_pair_response(sim, swapped.str(), p.w, p.amplitude, opt.chain);
      if (!m || std::abs(*m) == 0) continue;
      const std::complex<double> l = std::log(*m / p.value());
      s +=
          std::norm(std::complex<double>(l.real(), std::remainder(l.imag(), 2 * std::numbers::pi)));
      ++n;
    }
  }
  return n ? std::sqrt(s / n) : INFINITY;
}

}  // namespace

const char* to_string(DataAlternative::Kind k) { return enum_word(kKindWords, k); }

std::vector<SilentOutput> silent_outputs(const Model& sim, const std::vector<MeasuredPair>& data,
                                         const DiagnoseOptions& opt) {
  std::vector<SilentOutput> out;
  for (const ModelOutput& o : sim.outputs) {
    SilentOutput s;
    s.output = o.name;
    for (const MeasuredPair& mp : data) {
      const PairId id = PairId::parse(mp.pair);
      if (id.output != o.name || id.command) continue;
      bool counted = false;
      for (const FrdPoint& p : mp.frd.points) {
        if (!p.valid || !(p.sigma > 0)) continue;
        const auto g = model_pair_response(sim, mp.pair, p.w, p.amplitude, opt.chain);
        if (!g) continue;
        counted = true;
        ++s.points;
        s.above_noise += p.mag > kNoiseSigmas * p.sigma;
        s.expected += std::abs(*g) > kExpectedSigmas * p.sigma;
      }
      if (!counted) continue;
      s.pairs.push_back(mp.pair);
      if (std::find(s.inputs.begin(), s.inputs.end(), id.input) == s.inputs.end())
        s.inputs.push_back(id.input);
    }
    if (s.points == 0 || s.expected < kMinExpected ||
        double(s.expected) < kExpectedShare * s.points ||
        double(s.above_noise) > kSilentShare * s.points)
      continue;
    s.text = o.name + " holds no more than its noise on every measured path (" +
             std::to_string(s.above_noise) + " of " + std::to_string(s.points) +
             " points above 3 sigma) where the simulation expects " + std::to_string(s.expected) +
             " above 10 sigma: a dead channel from before the run's first period";
    out.push_back(std::move(s));
  }
  return out;
}

namespace {

// A clock error that could stand for finding f (index i): the delay it stands for (a lag's at low
// frequency is 1 / corner) within the delay the clock's 2-sigma band gives its output's samples
// by the measured periods' mean time.
std::optional<DataAlternative> clock_alternative(
    const Finding& f, int i, const std::map<std::string, ClockEvidence>& clocks) {
  const auto c = clocks.find(f.output);
  if (c == clocks.end()) return std::nullopt;
  double tau = 0;
  if (f.cause == CauseKind::kTimeDelay && f.parameters.count(Param::kDelayS))
    tau = f.parameters.at(Param::kDelayS);
  else if (f.cause == CauseKind::kMissingLag && f.parameters.count(Param::kCornerRadS))
    tau = 1 / f.parameters.at(Param::kCornerRadS);
  const ClockEvidence& e = c->second;
  const double lo = (std::abs(e.eps) - 2 * e.sigma) * e.t_mid_s,
               hi = (std::abs(e.eps) + 2 * e.sigma) * e.t_mid_s;
  if (!(tau > 0 && e.eps > 0 && std::abs(e.eps) >= 2 * e.sigma && tau >= lo && tau <= hi))
    return std::nullopt;
  DataAlternative a;
  a.kind = DataAlternative::Kind::kClock;
  a.channel = f.output;
  a.finding = i;
  a.text = "or " + f.output + "'s recorder runs on a clock " + significant(100 * e.eps, 3) +
           " % fast (+-" + significant(100 * e.sigma, 2) +
           " %, too little for the recordings' checks to name): by the measured periods' " +
           "mean time, " + significant(e.t_mid_s, 3) + " s from the run's start, that " +
           "delays its samples by " + significant(1e3 * e.eps * e.t_mid_s, 3) + " ms; " +
           "check its clock against the excitation's before changing the model";
  return a;
}

// A finding at one channel that a wiring or units fault reproduces: a sign error (the wiring),
// a gain within 1 % of a units factor or its inverse.
void channel_alternatives(const Finding& f, int i, std::vector<DataAlternative>& out) {
  const std::string ch = channel_of(f);
  if (ch.empty()) return;
  if (f.cause == CauseKind::kSignError) {
    DataAlternative a;
    a.kind = DataAlternative::Kind::kWiringSign;
    a.channel = ch;
    a.finding = i;
    a.text = "or " + ch + " is wired with the wrong sign: check its wiring and the sign in " +
             "the channel list before changing the model";
    out.push_back(std::move(a));
  } else if (f.cause == CauseKind::kGainMismatch && f.parameters.count(Param::kGainDb)) {
    const double k = std::pow(10.0, f.parameters.at(Param::kGainDb) / 20);
    for (const UnitsFactor& u : kUnits) {
      for (const double want : {u.factor, 1.0 / u.factor}) {
        if (std::abs(std::log(k / want)) > std::log(1.01)) continue;
        DataAlternative a;
        a.kind = DataAlternative::Kind::kUnits;
        a.channel = ch;
        a.finding = i;
        a.factor = want;
        a.text = "or " + ch + " is recorded in one unit and read in another: its gain " +
                 significant(k, 4) + " is the factor " + significant(want, 7) + " between " +
                 u.what + "; check the channel's units before changing the model";
        out.push_back(std::move(a));
      }
    }
  }
}

// Two outputs exchanged: each measured output matches the simulation's other far better than its
// own.
void swapped_outputs(const Model& sim, const std::vector<MeasuredPair>& data,
                     const DiagnoseOptions& opt, std::vector<DataAlternative>& out) {
  for (size_t a = 0; a < sim.outputs.size(); ++a) {
    for (size_t b = a + 1; b < sim.outputs.size(); ++b) {
      const std::string &A = sim.outputs[a].name, &B = sim.outputs[b].name;
      const double ab = exchanged_error(sim, data, A, B, opt),
                   ba = exchanged_error(sim, data, B, A, opt);
      const double aa = exchanged_error(sim, data, A, A, opt),
                   bb = exchanged_error(sim, data, B, B, opt);
      if (!(ab + ba < kSwapRatio * (aa + bb) && std::max(ab, ba) < 0.5 * std::min(aa, bb)))
        continue;
      DataAlternative s;
      s.kind = DataAlternative::Kind::kSwap;
      s.channel = A;
      s.other = B;
      s.text = A + " and " + B + " look exchanged: measured " + A + " matches the simulation's " +
               B + " (error " + significant(ab, 3) + " against " + significant(aa, 3) +
               ") and measured " + B + " its " + A + " (" + significant(ba, 3) + " against " +
               significant(bb, 3) + "); check the wiring and the channel list: the findings on " +
               "their paths may be that alone";
      out.push_back(std::move(s));
    }
  }
}

}  // namespace

std::vector<DataAlternative> data_alternatives(const Diagnosis& d, const Model& sim,
                                               const std::vector<MeasuredPair>& data,
                                               const DiagnoseOptions& opt,
                                               const std::map<std::string, double>& clipped,
                                               const std::vector<SilentOutput>& silent,
                                               const std::map<std::string, ClockEvidence>& clocks) {
  std::vector<DataAlternative> out;
  for (size_t i = 0; i < d.findings.size(); ++i) {
    const Finding& f = d.findings[i];
    if (std::optional<DataAlternative> a = clock_alternative(f, int(i), clocks))
      out.push_back(std::move(*a));
    for (const SilentOutput& s : silent) {
      if (f.output != s.output) continue;
      DataAlternative a;
      a.kind = DataAlternative::Kind::kDeadChannel;
      a.channel = s.output;
      a.finding = int(i);
      a.text = "or " + s.output + "'s channel is dead (" + s.text +
               "): check the sensor and its wiring before changing the model";
      out.push_back(std::move(a));
    }
    for (const std::string& at : {f.output, f.input}) {
      const auto c = clipped.find(at);
      if (at.empty() || c == clipped.end()) continue;
      DataAlternative a;
      a.kind = DataAlternative::Kind::kClipping;
      a.channel = at;
      a.finding = int(i);
      a.text = "or the clipping of " + at + " (" + significant(100 * c->second, 3) +
               " % of its samples at its range, filled from the samples it kept) left its mark "
               "on its curves: measure again within range before changing the model";
      out.push_back(std::move(a));
    }
    channel_alternatives(f, int(i), out);
  }
  swapped_outputs(sim, data, opt, out);
  return out;
}

Json data_alternatives_to_json(const std::vector<DataAlternative>& alts) {
  Json j = Json::array();
  for (const DataAlternative& a : alts) {
    Json x{{"kind", to_string(a.kind)}, {"channel", a.channel}, {"text", a.text}};
    x["other"] = a.other.empty() ? Json(nullptr) : Json(a.other);
    x["finding"] = a.finding < 0 ? Json(nullptr) : Json(a.finding);
    x["factor"] = a.factor > 0 ? Json(a.factor) : Json(nullptr);
    j.push_back(std::move(x));
  }
  return j;
}

}  // namespace fralab
