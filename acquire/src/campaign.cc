#include "fralab/acquire/campaign.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "fralab/core/json_util.h"

namespace fralab {

void SteppedSineOptions::validate() const {
  auto bad = [](const std::string& m) { throw InputError(m); };
  if (!(sample_rate_hz > 0)) bad("sample rate must be > 0 Hz");
  if (!(f_lo_hz > 0) || !(f_hi_hz >= f_lo_hz)) {
    bad("band " + std::to_string(f_lo_hz) + ":" + std::to_string(f_hi_hz) +
        " Hz must satisfy 0 < LO <= HI");
  }
  if (f_hi_hz > sample_rate_hz / 4) {
    bad("band top " + std::to_string(f_hi_hz) + " Hz is above fs/4 = " +
        std::to_string(sample_rate_hz / 4) + " Hz: lower --band or raise the sample rate");
  }
  if (points_per_decade < 1) bad("points per decade must be >= 1");
  if (min_cycles < 2) bad("min_cycles must be >= 2 (the noise estimate needs two blocks)");
  if (min_integrate_s < 0 || settle_cycles < 0 || settle_time_constants < 0 ||
      slowest_time_constant_s < 0) {
    bad("settle and integration times must be >= 0");
  }
}

std::vector<SineStep> plan_stepped_sine(const SteppedSineOptions& o) {
  o.validate();
  const double decades = std::log10(o.f_hi_hz / o.f_lo_hz);
  const int n = std::max(1, int(std::round(decades * o.points_per_decade)) + 1);
  std::vector<SineStep> steps;
  for (int i = 0; i < n; ++i) {
    double f = n == 1 ? o.f_lo_hz : o.f_lo_hz * std::pow(10.0, decades * i / (n - 1));
    SineStep s;
    s.index = i;
    s.n_cycles = std::max(o.min_cycles, int(std::ceil(o.min_integrate_s * f)));
    s.integrate_samples = std::llround(s.n_cycles * o.sample_rate_hz / f);
    s.f_hz = s.n_cycles * o.sample_rate_hz / double(s.integrate_samples);
    double settle_s =
        std::max(o.settle_cycles / f, o.settle_time_constants * o.slowest_time_constant_s);
    s.settle_samples = std::llround(settle_s * o.sample_rate_hz);
    steps.push_back(s);
  }
  return steps;
}

double plan_duration_s(const std::vector<SineStep>& steps, double fs) {
  int64_t n = 0;
  for (const auto& s : steps) n += s.settle_samples + s.integrate_samples;
  return n / fs;
}

double SegmentCampaign::add_segment(int input, int64_t length, double fa, double beta,
                                    double phi0) {
  if (input < 0 || input >= int(inputs_.size()))
    throw InputError("campaign: input index out of range");
  segs_.push_back({input, total_, length, fa, beta, phi0});
  total_ += length;
  const double t = double(length) / fs_;
  const double cycles = beta == 0.0 ? fa * t : fa * std::expm1(beta * t) / beta;
  return std::fmod(phi0 + 2 * std::numbers::pi * cycles, 2 * std::numbers::pi);
}

std::vector<std::string> SegmentCampaign::names() const {
  std::vector<std::string> v;
  for (const auto& in : inputs_) v.push_back(in.name);
  return v;
}

std::vector<double> SegmentCampaign::only(int i) const {
  std::vector<double> a(inputs_.size(), 0.0);
  a.at(i) = inputs_[i].amplitude;
  return a;
}

void SegmentCampaign::finish(const std::string& run_id, int64_t seq, int n_steps,
                             Excitation excitation) {
  StatusEvent done;
  done.run_id = run_id;
  done.seq = seq;
  done.sample_rate_hz = fs_;
  done.excitation = excitation;
  done.state = RunState::kDone;
  done.sample = total_;
  done.n_steps = n_steps;
  done.step = n_steps;
  done.inputs = names();
  done.amplitudes.assign(inputs_.size(), 0.0);
  events_.push_back(done);
}

void SegmentCampaign::fill(int64_t start, int n, std::vector<std::vector<double>>& cmd,
                           std::vector<double>& ref_phase, std::vector<double>& ref_freq) const {
  cmd.assign(inputs_.size(), std::vector<double>(n));
  ref_phase.assign(n, 0.0);
  ref_freq.assign(n, 0.0);
  for (size_t i = 0; i < inputs_.size(); ++i)
    std::fill(cmd[i].begin(), cmd[i].end(), inputs_[i].dc);
  // The segment of the first sample, then walk.
  auto it = std::upper_bound(segs_.begin(), segs_.end(), start,
                             [](int64_t v, const Segment& s) { return v < s.start; });
  size_t si = it == segs_.begin() ? 0 : size_t(it - segs_.begin() - 1);
  for (int k = 0; k < n; ++k) {
    const int64_t m = start + k;
    if (m >= total_ || segs_.empty()) continue;
    while (si + 1 < segs_.size() && segs_[si + 1].start <= m) ++si;
    const Segment& s = segs_[si];
    const double t = double(m - s.start) / fs_;
    const double phi = s.beta == 0.0
                           ? s.phi0 + 2 * std::numbers::pi * s.fa * t
                           : s.phi0 + 2 * std::numbers::pi * s.fa * std::expm1(s.beta * t) / s.beta;
    ref_phase[k] = phi;
    ref_freq[k] = s.fa * std::exp(s.beta * t);
    cmd[s.input][k] = inputs_[s.input].dc + inputs_[s.input].amplitude * std::sin(phi);
  }
}

SteppedSineCampaign::SteppedSineCampaign(std::vector<CampaignInput> inputs, std::vector<int> excite,
                                         std::vector<SineStep> steps, double fs, std::string run_id)
    : SegmentCampaign(std::move(inputs), fs) {
  if (steps.empty()) throw InputError("campaign: no frequency steps");
  if (excite.empty()) throw InputError("campaign: no input to excite");
  double phi = 0.0;
  int64_t seq = 0;
  const int n_steps = int(steps.size() * excite.size());
  int global = 0;
  for (int i : excite) {
    if (i < 0 || i >= int(inputs_.size())) throw InputError("campaign: input index out of range");
    for (const SineStep& s : steps) {
      const double dphi = 2 * std::numbers::pi * s.f_hz / fs;
      StatusEvent e;
      e.run_id = run_id;
      e.sample_rate_hz = fs;
      e.step = global++;
      e.n_steps = n_steps;
      e.frequency_hz = s.f_hz;
      e.n_cycles = s.n_cycles;
      e.inputs = names();
      e.amplitudes = only(i);
      e.seq = seq++;
      e.state = RunState::kSettle;
      e.sample = total_;
      e.ref_phase_rad = phi;
      e.n_samples = s.settle_samples;
      events_.push_back(e);
      e.seq = seq++;
      e.state = RunState::kIntegrate;
      e.sample = total_ + s.settle_samples;
      e.ref_phase_rad = std::fmod(phi + dphi * double(s.settle_samples), 2 * std::numbers::pi);
      e.n_samples = s.integrate_samples;
      events_.push_back(e);
      phi = add_segment(i, s.settle_samples + s.integrate_samples, s.f_hz, 0.0, phi);
    }
  }
  finish(run_id, seq, n_steps, Excitation::kStepped);
}

SweepCampaign::SweepCampaign(std::vector<CampaignInput> inputs, std::vector<int> excite,
                             const SteppedSineOptions& o, std::string run_id)
    : SegmentCampaign(std::move(inputs), o.sample_rate_hz) {
  const auto steps = plan_stepped_sine(o);  // validates; gives the centres and cycle counts
  if (excite.empty()) throw InputError("campaign: no input to excite");
  const double r =
      steps.size() > 1 ? steps[1].f_hz / steps[0].f_hz : std::pow(10.0, 1.0 / o.points_per_decade);
  int64_t seq = 0;
  double phi = 0.0;
  const int n_steps = int(steps.size() * excite.size());
  int global = 0;
  for (int i : excite) {
    if (i < 0 || i >= int(inputs_.size())) throw InputError("campaign: input index out of range");
    StatusEvent e;
    e.run_id = run_id;
    e.sample_rate_hz = fs_;
    e.excitation = Excitation::kSweep;
    e.n_steps = n_steps;
    e.inputs = names();
    e.amplitudes = only(i);
    // Settle at the sweep's starting frequency.
    const double f0 = steps[0].f_hz / std::sqrt(r);
    e.seq = seq++;
    e.state = RunState::kSettle;
    e.step = global;
    e.sample = total_;
    e.frequency_hz = f0;
    e.ref_phase_rad = phi;
    e.n_samples = steps[0].settle_samples;
    events_.push_back(e);
    phi = add_segment(i, steps[0].settle_samples, f0, 0.0, phi);
    for (const SineStep& st : steps) {
      const double fa = st.f_hz / std::sqrt(r);
      const double T = st.n_cycles * std::log(r) / (fa * (r - 1));  // N cycles while f rises by r
      const int64_t L = std::max<int64_t>(1, std::llround(T * fs_));
      e.seq = seq++;
      e.state = RunState::kIntegrate;
      e.step = global++;
      e.sample = total_;
      e.frequency_hz = st.f_hz;
      e.ref_phase_rad = phi;
      e.n_cycles = st.n_cycles;
      e.n_samples = L;
      events_.push_back(e);
      phi = add_segment(i, L, fa, std::log(r) / (double(L) / fs_), phi);
    }
  }
  finish(run_id, seq, n_steps, Excitation::kSweep);
}

void MultisineOptions::validate() const {
  if (!(sample_rate_hz > 0)) throw InputError("sample rate must be > 0 Hz");
  if (!(f_lo_hz > 0) || !(f_hi_hz > f_lo_hz))
    throw InputError("multisine band must satisfy 0 < LO < HI");
  if (f_hi_hz > sample_rate_hz / 4)
    throw InputError("multisine band top is above fs/4: lower --band");
  if (points_per_decade < 1) throw InputError("points per decade must be >= 1");
  if (periods < 2)
    throw InputError("a multisine needs >= 2 measured periods (noise from their spread)");
  if (phases != "schroeder" && phases != "random")
    throw InputError("--multisine-phases must be schroeder or random");
}

MultisineCampaign::MultisineCampaign(std::vector<CampaignInput> inputs, std::vector<int> excite,
                                     const MultisineOptions& o, std::string run_id)
    : Campaign(std::move(inputs), o.sample_rate_hz) {
  o.validate();
  if (excite.empty()) throw InputError("campaign: no input to excite");
  P_ = int(std::llround(fs_ / o.f_lo_hz));
  const double df = fs_ / P_;
  // Lines near log-spaced targets, unique, optionally odd.
  std::vector<int> lines;
  const int n_targets =
      int(std::round(std::log10(o.f_hi_hz / o.f_lo_hz) * o.points_per_decade)) + 1;
  for (int j = 0; j < n_targets; ++j) {
    int k = int(std::llround(o.f_lo_hz * std::pow(10.0, double(j) / o.points_per_decade) / df));
    if (o.odd_lines && k % 2 == 0) ++k;
    if (k < 1 || k >= P_ / 2) continue;
    if (lines.empty() || k > lines.back()) lines.push_back(k);
  }
  const int ni = int(excite.size());
  if (int(lines.size()) < ni)
    throw InputError("multisine: fewer lines than excited inputs; widen the band");
  std::vector<int> line_input;
  std::vector<std::vector<int>> per(inputs_.size());
  for (size_t j = 0; j < lines.size(); ++j) {
    const int i = excite[j % ni];
    if (i < 0 || i >= int(inputs_.size())) throw InputError("campaign: input index out of range");
    line_input.push_back(i);
    per[i].push_back(lines[j]);
  }
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> uni(0.0, 2 * std::numbers::pi);
  period_.assign(inputs_.size(), {});
  std::vector<double> amps(inputs_.size(), 0.0);
  for (int i : excite) {
    std::vector<double> x(P_, 0.0);
    const double nk = double(per[i].size());
    for (size_t j = 0; j < per[i].size(); ++j) {
      const double ph =
          o.phases == "schroeder" ? -std::numbers::pi * double(j) * double(j + 1) / nk : uni(rng);
      for (int n = 0; n < P_; ++n)
        x[n] += std::sin(2 * std::numbers::pi * double(per[i][j]) * n / P_ + ph);
    }
    double peak = 0;
    for (double v : x) peak = std::max(peak, std::abs(v));
    for (double& v : x) v *= inputs_[i].amplitude / peak;
    period_[i] = std::move(x);
    amps[i] = inputs_[i].amplitude;
  }
  const int settle =
      std::max(1, int(std::ceil(o.settle_time_constants * o.slowest_time_constant_s * df)));
  StatusEvent e;
  e.run_id = run_id;
  e.sample_rate_hz = fs_;
  e.excitation = Excitation::kMultisine;
  for (const auto& in : inputs_) e.inputs.push_back(in.name);
  e.amplitudes = amps;
  e.n_steps = 1;
  e.frequency_hz = df;
  e.period_samples = P_;
  e.lines = lines;
  e.line_input = line_input;
  e.seq = 0;
  e.state = RunState::kSettle;
  e.sample = 0;
  e.n_cycles = settle;
  e.n_samples = int64_t(settle) * P_;
  events_.push_back(e);
  e.seq = 1;
  e.state = RunState::kIntegrate;
  e.sample = int64_t(settle) * P_;
  e.n_cycles = o.periods;
  e.n_samples = int64_t(o.periods) * P_;
  events_.push_back(e);
  total_ = int64_t(settle + o.periods) * P_;
  e.seq = 2;
  e.state = RunState::kDone;
  e.sample = total_;
  e.n_samples = 0;
  e.step = 1;
  events_.push_back(e);
}

void MultisineCampaign::fill(int64_t start, int n, std::vector<std::vector<double>>& cmd,
                             std::vector<double>& ref_phase, std::vector<double>& ref_freq) const {
  cmd.assign(inputs_.size(), std::vector<double>(n));
  ref_phase.assign(n, 0.0);
  ref_freq.assign(n, 0.0);
  const double df = fs_ / P_;
  for (size_t i = 0; i < inputs_.size(); ++i) {
    for (int k = 0; k < n; ++k) {
      const int64_t m = start + k;
      cmd[i][k] =
          inputs_[i].dc + (period_[i].empty() || m >= total_ ? 0.0 : period_[i][size_t(m % P_)]);
    }
  }
  for (int k = 0; k < n; ++k) {
    const int64_t m = start + k;
    if (m >= total_) continue;
    ref_phase[k] = std::fmod(2 * std::numbers::pi * double(m % P_) / P_, 2 * std::numbers::pi);
    ref_freq[k] = df;
  }
}

}  // namespace fralab
