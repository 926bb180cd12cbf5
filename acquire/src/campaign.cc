#include "fralab/acquire/campaign.h"

#include <fftw3.h>

#include <algorithm>
#include <cmath>
#include <complex>
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

StatusEvent SegmentCampaign::sine_step_settle(const std::string& run_id, int i, int step,
                                              int n_steps, const SineStep& s, double phi) const {
  StatusEvent e;
  e.run_id = run_id;
  e.sample_rate_hz = fs_;
  e.step = step;
  e.n_steps = n_steps;
  e.frequency_hz = s.f_hz;
  e.n_cycles = s.n_cycles;
  e.inputs = names();
  e.amplitudes = only(i);
  e.state = RunState::kSettle;
  e.sample = total_;
  e.ref_phase_rad = phi;
  e.n_samples = s.settle_samples;
  return e;
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
    if (m >= s.start + s.length) continue;  // after the last segment: the operating point
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
      StatusEvent e = sine_step_settle(run_id, i, global++, n_steps, s, phi);
      e.seq = seq++;
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
  if (phases != "schroeder" && phases != "random" && phases != "low-crest")
    throw InputError("--multisine-phases must be schroeder, random or low-crest");
  if (realisations < 1 || realisations > 1000) throw InputError("--realisations must be 1..1000");
  if (realisations > 1 && design != Design::kOrthogonal)
    throw InputError("--realisations > 1 needs the orthogonal multisine design");
  if (realisations > 1 && phases == "schroeder")
    throw InputError(
        "--realisations > 1 needs random or low-crest phases (Schroeder phases are one "
        "realisation)");
  if (level != "peak" && level != "rms")
    throw InputError("multisine level \"" + level + "\": peak or rms");
  if (!(settle_time_constants >= 0) || !(slowest_time_constant_s >= 0))
    throw InputError("multisine settling times must be >= 0");
  for (size_t j = 0; j < zoom.size(); ++j)
    if (!(zoom[j].wn_rad_s > 0) || !std::isfinite(zoom[j].wn_rad_s) || !(zoom[j].zeta > 0) ||
        !(zoom[j].zeta < 1))
      throw InputError("--zoom mode " + std::to_string(j + 1) +
                       ": wn must be finite and > 0 rad/s, zeta in (0, 1)");
  // 16 x a 25 s period is a 400 s one, its samples held per input and experiment.
  if (!(zoom_period_factor >= 1) || !(zoom_period_factor <= 16))
    throw InputError("--zoom-period-factor must be 1..16");
}

namespace {

double hz(const ZoomMode& z) { return z.wn_rad_s / (2 * std::numbers::pi); }

// How far either side of f (relative) a zoomed mode's lines reach.
double reach(const ZoomMode& z) { return std::max(kZoomReachZetas * z.zeta, kZoomReach); }

// The period, samples, that puts kZoomLinesInBand lines in mode z's half-power band 2 zeta f.
double period_for(const ZoomMode& z, double fs) {
  return std::ceil(fs * kZoomLinesInBand / (2 * z.zeta * hz(z)) - 1e-9);
}

bool in_band(const ZoomMode& z, const MultisineOptions& o) {
  return hz(z) >= o.f_lo_hz && hz(z) <= o.f_hi_hz;
}

}  // namespace

int multisine_period_samples(const MultisineOptions& o) {
  const double p0 = double(std::llround(o.sample_rate_hz / o.f_lo_hz));
  const double most = std::floor(o.zoom_period_factor * p0);
  double p = p0;
  for (const ZoomMode& z : o.zoom)
    if (in_band(z, o) && period_for(z, o.sample_rate_hz) <= most)
      p = std::max(p, period_for(z, o.sample_rate_hz));
  return int(p);
}

namespace {

// The zoom's lines (MultisineOptions::zoom) among harmonics 1..k_hi of fs / P: per mode inside the
// band that the period resolves (P >= period_for), k0 + j step for |j step| df <= reach f, k0 the
// harmonic nearest f, step the harmonics in zeta f / 2 (at least one).
std::vector<int> zoom_lines(const MultisineOptions& o, int P, int k_hi) {
  const double df = o.sample_rate_hz / P;
  std::vector<int> lines;
  for (const ZoomMode& z : o.zoom) {
    if (!in_band(z, o) || period_for(z, o.sample_rate_hz) > P) continue;
    const double f = hz(z);
    const int step = std::max(1, int(std::floor(z.zeta * f / 2 / df + 1e-9)));
    const int k0 = int(std::llround(f / df));
    const int span = int(std::floor(reach(z) * f / df / step + 1e-9));
    for (int j = -span; j <= span; ++j) {
      int k = k0 + j * step;
      if (o.odd_lines && k % 2 == 0) ++k;
      if (k >= 1 && k <= k_hi && k < P / 2) lines.push_back(k);
    }
  }
  return lines;
}

// `lines` with `more` sorted in, each once.
std::vector<int> merged(std::vector<int> lines, const std::vector<int>& more) {
  lines.insert(lines.end(), more.begin(), more.end());
  std::sort(lines.begin(), lines.end());
  lines.erase(std::unique(lines.begin(), lines.end()), lines.end());
  return lines;
}

}  // namespace

std::vector<ZoomPlacement> zoom_placement(const MultisineOptions& o, int P,
                                          const std::vector<int>& lines) {
  const double df = o.sample_rate_hz / P;
  std::vector<ZoomPlacement> out;
  for (const ZoomMode& z : o.zoom) {
    if (!in_band(z, o)) continue;
    ZoomPlacement zp;
    zp.mode = z;
    zp.resolution_hz = df;
    zp.zoomed = period_for(z, o.sample_rate_hz) <= P;
    zp.period_needed_s = period_for(z, o.sample_rate_hz) / o.sample_rate_hz;
    for (int k : lines) {
      const double off = std::abs(k * df - hz(z)) / hz(z);
      zp.lines_in_band += off <= z.zeta;
      zp.lines_in_reach += off <= reach(z);
    }
    out.push_back(zp);
  }
  return out;
}

const char* to_string(MultisineOptions::Design d) {
  return d == MultisineOptions::Design::kOrthogonal ? "orthogonal" : "zippered";
}

MultisineOptions::Design multisine_design_from_string(const std::string& word) {
  if (word == "orthogonal") return MultisineOptions::Design::kOrthogonal;
  if (word == "zippered") return MultisineOptions::Design::kZippered;
  throw InputError("--multisine-design \"" + word + "\": orthogonal or zippered");
}

std::vector<int> multisine_lines(const MultisineOptions& o, int P) {
  const double df = o.sample_rate_hz / P;
  std::vector<int> lines;
  auto odd_up = [&](int k) { return o.odd_lines && k % 2 == 0 ? k + 1 : k; };
  if (o.design == MultisineOptions::Design::kOrthogonal) {
    const double r = std::pow(10.0, 1.0 / o.points_per_decade);
    const int k_hi = int(std::floor(o.f_hi_hz / df * (1 + 1e-12)));
    for (int k = odd_up(std::max(1, int(std::llround(o.f_lo_hz / df)))); k <= k_hi && k < P / 2;) {
      lines.push_back(k);
      k = odd_up(std::max(k + 1, int(std::floor(k * r))));
    }
    return o.zoom.empty() ? lines : merged(lines, zoom_lines(o, P, k_hi));
  }
  const int n_targets =
      int(std::round(std::log10(o.f_hi_hz / o.f_lo_hz) * o.points_per_decade)) + 1;
  for (int j = 0; j < n_targets; ++j) {
    int k =
        odd_up(int(std::llround(o.f_lo_hz * std::pow(10.0, double(j) / o.points_per_decade) / df)));
    if (k < 1 || k >= P / 2) continue;
    if (lines.empty() || k > lines.back()) lines.push_back(k);
  }
  if (o.zoom.empty()) return lines;
  return merged(lines, zoom_lines(o, P, int(std::floor(o.f_hi_hz / df * (1 + 1e-12)))));
}

namespace {

// One period of sum_k sin(2 pi k n / P + phase[j]) over lines[j].
std::vector<double> multisine_period(int P, const std::vector<int>& lines,
                                     const std::vector<double>& phase) {
  std::vector<double> x(P, 0.0);
  for (size_t j = 0; j < lines.size(); ++j)
    for (int n = 0; n < P; ++n)
      x[n] += std::sin(2 * std::numbers::pi * double(int64_t(lines[j]) * n % P) / P + phase[j]);
  return x;
}

// Phases of |K| lines: Schroeder's, or uniform random from `rng` (low-crest: then optimised).
std::vector<double> line_phases(const std::string& kind, int P, const std::vector<int>& lines,
                                std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uni(0.0, 2 * std::numbers::pi);
  std::vector<double> ph(lines.size());
  const double nk = double(lines.size());
  for (size_t j = 0; j < lines.size(); ++j)
    ph[j] = kind == "schroeder" ? -std::numbers::pi * double(j) * double(j + 1) / nk : uni(rng);
  return kind == "low-crest" ? low_crest_phases(P, lines, ph) : ph;
}

double peak_of(const std::vector<double>& x) {
  double peak = 0;
  for (double v : x) peak = std::max(peak, std::abs(v));
  return peak;
}

}  // namespace

std::vector<double> low_crest_phases(int P, const std::vector<int>& lines,
                                     std::vector<double> phase, int iterations) {
  if (lines.empty() || P < 2) return phase;
  std::vector<std::complex<double>> spec(P), z(P);
  auto* s = reinterpret_cast<fftw_complex*>(spec.data());
  auto* t = reinterpret_cast<fftw_complex*>(z.data());
  fftw_plan inv = fftw_plan_dft_1d(P, s, t, FFTW_BACKWARD, FFTW_ESTIMATE);
  fftw_plan fwd = fftw_plan_dft_1d(P, t, s, FFTW_FORWARD, FFTW_ESTIMATE);
  const double level = 1.2 * std::sqrt(double(lines.size()));
  std::vector<double> best = phase;
  double best_peak = INFINITY;
  for (int it = 0; it <= iterations; ++it) {
    std::fill(spec.begin(), spec.end(), 0.0);
    for (size_t j = 0; j < lines.size(); ++j)
      spec[size_t(lines[j]) % P] = std::polar(1.0, phase[j]);
    fftw_execute(inv);  // z[n] = sum_j exp(j (2 pi k_j n / P + phi_j))
    double peak = 0;
    for (const auto& v : z) peak = std::max(peak, std::abs(v));
    if (peak < best_peak) best_peak = peak, best = phase;
    if (it == iterations) break;
    for (auto& v : z)
      if (std::abs(v) > level) v *= level / std::abs(v);
    fftw_execute(fwd);
    for (size_t j = 0; j < lines.size(); ++j) phase[j] = std::arg(spec[size_t(lines[j]) % P]);
  }
  fftw_destroy_plan(inv);
  fftw_destroy_plan(fwd);
  return best;
}

MultisineCampaign::MultisineCampaign(std::vector<CampaignInput> inputs, std::vector<int> excite,
                                     const MultisineOptions& o, std::string run_id)
    : Campaign(std::move(inputs), o.sample_rate_hz) {
  o.validate();
  if (excite.empty()) throw InputError("campaign: no input to excite");
  for (int i : excite)
    if (i < 0 || i >= int(inputs_.size())) throw InputError("campaign: input index out of range");
  P_ = multisine_period_samples(o);
  const bool ortho = o.design == MultisineOptions::Design::kOrthogonal;
  const std::vector<int> lines = multisine_lines(o, P_);
  const int ni = int(excite.size());
  if (lines.empty() || (!ortho && int(lines.size()) < ni))
    throw InputError("multisine: fewer lines than excited inputs; widen the band");
  const int n_exp = ortho ? o.realisations * ni : 1;
  period_.assign(n_exp, std::vector<std::vector<double>>(inputs_.size()));
  StatusEvent e;
  if (ortho)
    design_orthogonal(lines, excite, o, &e.lines, &e.line_input);
  else
    design_zippered(lines, excite, o, &e.lines, &e.line_input);
  e.amplitudes = scale_to_amplitudes(excite, o);
  e.run_id = run_id;
  schedule(o, n_exp, ni, std::move(e));
}

void MultisineCampaign::design_orthogonal(const std::vector<int>& lines,
                                          const std::vector<int>& excite, const MultisineOptions& o,
                                          std::vector<int>* ev_lines,
                                          std::vector<int>* line_input) {
  const int ni = int(excite.size());
  for (int k : lines)
    for (int i : excite) ev_lines->push_back(k), line_input->push_back(i);
  for (int r = 0; r < o.realisations; ++r) {
    std::mt19937_64 rr(o.seed + uint64_t(r));
    for (int q = 0; q < ni; ++q) {
      const std::vector<double> ph = line_phases(o.phases, P_, lines, rr);
      for (int e = 0; e < ni; ++e) {
        std::vector<double> pe = ph;
        for (double& v : pe) v += 2 * std::numbers::pi * double(q * e % ni) / ni;
        period_[size_t(r * ni + e)][excite[q]] = multisine_period(P_, lines, pe);
      }
    }
  }
}

void MultisineCampaign::design_zippered(const std::vector<int>& lines,
                                        const std::vector<int>& excite, const MultisineOptions& o,
                                        std::vector<int>* ev_lines, std::vector<int>* line_input) {
  const int ni = int(excite.size());
  std::mt19937_64 rng(o.seed);
  std::vector<std::vector<int>> per(inputs_.size());
  for (size_t j = 0; j < lines.size(); ++j) {
    const int i = excite[j % ni];
    ev_lines->push_back(lines[j]);
    line_input->push_back(i);
    per[i].push_back(lines[j]);
  }
  for (int i : excite)
    period_[0][i] = multisine_period(P_, per[i], line_phases(o.phases, P_, per[i], rng));
}

// Each input scaled so that its largest peak over every experiment is its amplitude ("peak"),
// or its rms the sine's at that amplitude, the peak within half the full scale ("rms"); the slew,
// the period wrapping round, within the input's rate limit.
std::vector<double> MultisineCampaign::scale_to_amplitudes(const std::vector<int>& excite,
                                                           const MultisineOptions& o) {
  std::vector<double> amps(inputs_.size(), 0.0);
  for (int i : excite) {
    double peak = 0, ss = 0, n = 0;
    for (const auto& x : period_) {
      peak = std::max(peak, peak_of(x[i]));
      for (double v : x[i]) ss += v * v, n += 1;
    }
    double g = inputs_[i].amplitude / peak;
    if (o.level == "rms") {
      g = inputs_[i].amplitude / std::sqrt(2.0) / std::sqrt(ss / n);
      if (inputs_[i].full_scale > 0) g = std::min(g, 0.5 * inputs_[i].full_scale / peak);
    }
    if (inputs_[i].max_rate > 0) {
      double slew = 0;
      for (const auto& x : period_)
        for (size_t n = 0; n < x[i].size(); ++n)
          slew = std::max(slew, std::abs(x[i][(n + 1) % x[i].size()] - x[i][n]) * fs_);
      if (g * slew > inputs_[i].max_rate) g = inputs_[i].max_rate / slew;
    }
    for (auto& x : period_)
      for (double& v : x[i]) v *= g;
    amps[i] = g * peak;
  }
  return amps;
}

void MultisineCampaign::schedule(const MultisineOptions& o, int n_exp, int ni, StatusEvent e) {
  const bool ortho = o.design == MultisineOptions::Design::kOrthogonal;
  const double tc_samples = o.settle_time_constants * o.slowest_time_constant_s * fs_;
  if (ortho) {
    settle_ = o.slowest_time_constant_s > 0
                  ? std::max<int64_t>(int64_t(std::ceil(tc_samples)), int64_t(std::ceil(0.1 * P_)))
                  : P_;
  } else {
    settle_ = int64_t(std::max(1, int(std::ceil(tc_samples / P_)))) * P_;
  }
  experiment_ = settle_ + int64_t(o.periods) * P_;
  e.sample_rate_hz = fs_;
  e.excitation = Excitation::kMultisine;
  for (const auto& in : inputs_) e.inputs.push_back(in.name);
  e.n_steps = n_exp;
  e.frequency_hz = fs_ / P_;
  e.period_samples = P_;
  int64_t seq = 0;
  for (int x = 0; x < n_exp; ++x) {
    e.step = x;
    if (ortho)
      e.message = "orthogonal multisine: realisation " + std::to_string(x / ni + 1) + " of " +
                  std::to_string(o.realisations) + ", experiment " + std::to_string(x % ni + 1) +
                  " of " + std::to_string(ni) + " (DFT phase matrix, " + o.phases + " phases)";
    e.seq = seq++;
    e.state = RunState::kSettle;
    e.sample = x * experiment_;
    e.n_cycles = int(settle_ / P_);
    e.n_samples = settle_;
    events_.push_back(e);
    e.seq = seq++;
    e.state = RunState::kIntegrate;
    e.sample = x * experiment_ + settle_;
    e.n_cycles = o.periods;
    e.n_samples = int64_t(o.periods) * P_;
    events_.push_back(e);
  }
  total_ = n_exp * experiment_;
  e.message.clear();
  e.seq = seq;
  e.state = RunState::kDone;
  e.sample = total_;
  e.n_samples = 0;
  e.step = n_exp;
  events_.push_back(e);
}

void MultisineCampaign::fill(int64_t start, int n, std::vector<std::vector<double>>& cmd,
                             std::vector<double>& ref_phase, std::vector<double>& ref_freq) const {
  cmd.assign(inputs_.size(), std::vector<double>(n));
  ref_phase.assign(n, 0.0);
  ref_freq.assign(n, 0.0);
  const double df = fs_ / P_;
  for (int k = 0; k < n; ++k) {
    const int64_t m = start + k;
    const bool on = m >= 0 && m < total_;
    const size_t x = on ? size_t(m / experiment_) : 0;
    // The sample's place in the period: the measured periods start at the settle's end.
    const int64_t o = on ? ((m % experiment_ - settle_) % P_ + P_) % P_ : 0;
    for (size_t i = 0; i < inputs_.size(); ++i) {
      const auto& per = period_[x][i];
      cmd[i][k] = inputs_[i].dc + (!on || per.empty() ? 0.0 : per[size_t(o)]);
    }
    if (!on) continue;
    ref_phase[k] = 2 * std::numbers::pi * double(o) / P_;
    ref_freq[k] = df;
  }
}

}  // namespace fralab
