// The excitation campaign: what the oscillator does, sample by sample, with no I/O.
//
// Stepped sine (the default, Appendix A's Fourier analysis at discrete frequencies): frequencies
// log-spaced over [f_lo, f_hi] Hz, points_per_decade per decade (both ends included). Per step:
//   settle    max(settle_cycles / f, settle_time_constants * slowest_time_constant_s) seconds,
//   integrate N whole cycles, N = max(min_cycles, ceil(min_integrate_s * f)),
// and f is nudged so that N cycles are exactly an integer number of samples L (f = N fs / L), so
// the Fourier filter's window holds whole cycles exactly. min_cycles = 8 gives 8 blocks of one or
// more cycles for the noise estimate; min_integrate_s keeps high-frequency points from being too
// short; the low frequencies still dominate: 0.04-100 Hz at 10 points per decade is ~19 min of
// engine time per actuator at the defaults (the report: 0.5 h per actuator).
//
// Inputs are excited one after the other, each through the whole list of steps. The command of the
// excited input is dc + A sin(phi(n)); phi is continuous across steps (no jumps in the command);
// phi(n) = phi_step + 2 pi f (n - n_step) / fs within a step.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fralab/core/block.h"

namespace fralab {

struct SteppedSineOptions {
  double f_lo_hz = 0.04;
  double f_hi_hz = 100.0;
  int points_per_decade = 10;
  int min_cycles = 8;
  double min_integrate_s = 4.0;
  double settle_cycles = 1.0;
  double settle_time_constants = 5.0;
  double slowest_time_constant_s = 0.0;  // from the model (largest 1/|pole|)
  double sample_rate_hz = 1000.0;
  /// Throws InputError naming the bad option (band order, f_hi above fs/4, ...).
  void validate() const;
};

struct SineStep {
  int index = 0;
  double f_hz = 0.0;  // exact: n_cycles * fs / integrate_samples
  int n_cycles = 0;
  int64_t settle_samples = 0;
  int64_t integrate_samples = 0;
};

std::vector<SineStep> plan_stepped_sine(const SteppedSineOptions& opt);

struct CampaignInput {
  std::string name;
  double dc = 0.0;
  double amplitude = 0.0;   // peak, input units, when excited
  double full_scale = 0.0;  // input units (0: unknown)
  double max_rate = 0.0;    // the actuator's rate limit, input units per second (0: none)
};

/// What the oscillator does over a whole run, sample-exact: commands, reference, status events.
class Campaign {
 public:
  virtual ~Campaign() = default;
  int64_t total_samples() const { return total_; }
  double sample_rate_hz() const { return fs_; }
  /// Status events in sample order, ending with "done".
  const std::vector<StatusEvent>& events() const { return events_; }
  /// Every plant input (dc values and test amplitudes).
  const std::vector<CampaignInput>& inputs() const { return inputs_; }
  /// Fills commands for samples [start, start + n): cmd[i][k] absolute command of input i,
  /// ref_phase[k] (radians, continuous within a segment) and ref_freq_hz[k] (0 when idle).
  virtual void fill(int64_t start, int n, std::vector<std::vector<double>>& cmd,
                    std::vector<double>& ref_phase, std::vector<double>& ref_freq) const = 0;

 protected:
  Campaign(std::vector<CampaignInput> inputs, double fs) : inputs_(std::move(inputs)), fs_(fs) {}
  std::vector<CampaignInput> inputs_;
  std::vector<StatusEvent> events_;
  double fs_;
  int64_t total_ = 0;
};

/// A campaign made of contiguous segments, each exciting one input with phase
/// phi(t) = phi0 + 2 pi fa (e^{beta t} - 1) / beta (beta = 0: phi0 + 2 pi fa t, a constant
/// frequency), t the time since the segment's start; phase is continuous from one segment to the
/// next. The stepped sine and the sweep differ only in their segments and status events.
class SegmentCampaign : public Campaign {
 public:
  void fill(int64_t start, int n, std::vector<std::vector<double>>& cmd,
            std::vector<double>& ref_phase, std::vector<double>& ref_freq) const override;

 protected:
  SegmentCampaign(std::vector<CampaignInput> inputs, double fs) : Campaign(std::move(inputs), fs) {}
  struct Segment {
    int input;
    int64_t start, length;
    double fa, beta, phi0;
  };
  /// Appends a segment at the end of the run and returns the phase (mod 2 pi) where it ends.
  double add_segment(int input, int64_t length, double fa, double beta, double phi0);
  /// Closes the run with its "done" event.
  void finish(const std::string& run_id, int64_t seq, int n_steps, Excitation excitation);
  /// The settle status of a sine step exciting input i, starting now (at total_) with reference
  /// phase phi (seq left for the caller): what a stepped sine's step status says.
  StatusEvent sine_step_settle(const std::string& run_id, int i, int step, int n_steps,
                               const SineStep& s, double phi) const;
  /// Every input's name, and amplitudes with only input i excited.
  std::vector<std::string> names() const;
  std::vector<double> only(int i) const;

  std::vector<Segment> segs_;
};

/// The whole run: every excited input through every step, then "done". Sample-exact.
class SteppedSineCampaign : public SegmentCampaign {
 public:
  /// `inputs`: every plant input (dc values); `excite`: indices into `inputs`, in test order.
  SteppedSineCampaign(std::vector<CampaignInput> inputs, std::vector<int> excite,
                      std::vector<SineStep> steps, double sample_rate_hz, std::string run_id);
};

/// Continuous logarithmic sweep (as the BAFCO drove the engine): per excited input, a settle at the
/// lowest frequency (as a stepped-sine settle), then one continuous sweep whose frequency rises by
/// r = 10^(1/points_per_decade) over each analysis window of N whole reference cycles
/// (N = max(min_cycles, ceil(min_integrate_s f))): within window j, f = f_a r^(c/N) after c cycles,
/// f_a = f_j / sqrt(r), so phase and frequency are continuous and the windows tile the sweep. Each
/// window is an "integrate" status (excitation "sweep", frequency_hz its geometric centre f_j); the
/// analyser integrates against the recorded per-sample reference phase (tape channel ref_phase).
class SweepCampaign : public SegmentCampaign {
 public:
  SweepCampaign(std::vector<CampaignInput> inputs, std::vector<int> excite,
                const SteppedSineOptions& opt, std::string run_id);
};

/// A lightly damped mode a multisine resolves (its zoom): natural frequency wn (rad/s) and damping
/// ratio zeta, its half-power band wn (1 +- zeta).
struct ZoomMode {
  double wn_rad_s = 0;
  double zeta = 0;
  bool operator==(const ZoomMode&) const = default;
};

struct MultisineOptions {
  double f_lo_hz = 0.04;  // the frequency resolution: period = round(fs / f_lo) samples
  double f_hi_hz = 100.0;
  int points_per_decade = 10;  // line density (see the designs below)
  int periods = 8;             // measured periods per experiment (>= 2: noise from their spread)
  double settle_time_constants = 5.0;
  double slowest_time_constant_s = 0.0;
  bool odd_lines = false;  // only odd harmonics: even lines then reveal even nonlinearities
  // "schroeder", "random", or "low-crest": random phases then envelope clipping
  // (low_crest_phases), the orthogonal design's default.
  std::string phases = "low-crest";
  uint64_t seed = 1;  // random and low-crest phases (realisation r uses seed + r)
  double sample_rate_hz = 1000.0;
  /// kOrthogonal (Pintelon and Schoukens' orthogonal multisines): every excited input on every
  /// line, n_u experiments whose phase matrix is the n_u x n_u DFT matrix, so the whole FRF matrix
  /// is solved per line. kZippered: each input on its own (disjoint) lines, one experiment.
  enum class Design { kOrthogonal, kZippered } design = Design::kOrthogonal;
  /// kOrthogonal: independent phase realisations, each n_u experiments (> 1 needs random phases:
  /// their spread is what separates nonlinear distortion from noise).
  int realisations = 1;
  /// "peak": each input's largest peak is its amplitude (the sine test's peak); "rms": its rms is
  /// the sine test's, amplitude / sqrt 2 (the same power as the report's sine, spread over the
  /// lines), the peak then crest / sqrt 2 times the amplitude, capped at half the full scale.
  /// Either way a multisine's slew, max |x[n+1] - x[n]| fs over every experiment, is held to the
  /// input's rate limit (CampaignInput::max_rate), the level lowered if need be: a rate-limited
  /// actuator then moves linearly.
  std::string level = "rms";
  /// Modes to resolve. A mode inside the band is zoomed when a period of at most
  /// zoom_period_factor times fs / f_lo samples puts kZoomLinesInBand lines in its half-power band
  /// 2 zeta f (f = wn / 2 pi): the period grows to the longest such mode's need, and each zoomed
  /// mode gets lines over f (1 +- reach), reach = max(kZoomReachZetas zeta, kZoomReach) (a mode
  /// moved a few per cent stays inside), zeta f / 2 apart or every harmonic where that is finer
  /// than the resolution. A mode lighter than the factor allows is left to the grid (its
  /// placement says the period it would need): lines it cannot resolve would only share the
  /// excitation's power. Factor 1: the zoom costs no engine time. Empty: the grid alone.
  std::vector<ZoomMode> zoom;
  double zoom_period_factor = 1.0;
  void validate() const;
};

inline constexpr double kZoomReach = 0.05;      // +- 5 % of a zoomed mode's frequency at least
inline constexpr double kZoomReachZetas = 3.0;  // or three half-power half-widths
inline constexpr int kZoomLinesInBand = 4;      // lines wanted in a half-power band 2 zeta f

/// The period of the multisine o describes, samples: round(fs / f_lo), lengthened for the modes
/// of its zoom (MultisineOptions::zoom) that zoom_period_factor allows.
int multisine_period_samples(const MultisineOptions& o);

/// Where a zoomed mode's lines fell (run.json "zoom", docs/formats.md §13).
struct ZoomPlacement {
  ZoomMode mode;
  int lines_in_band = 0;       // lines within its half-power band f (1 +- zeta)
  int lines_in_reach = 0;      // lines within f (1 +- reach)
  double resolution_hz = 0;    // the multisine's line spacing fs / P
  bool zoomed = false;         // the period resolves it: it got the zoom's lines
  double period_needed_s = 0;  // the period that puts kZoomLinesInBand lines in its band, s
  bool operator==(const ZoomPlacement&) const = default;
};

/// Each mode of o.zoom inside the band, with the lines of `lines` (harmonics of fs / P) around it.
std::vector<ZoomPlacement> zoom_placement(const MultisineOptions& o, int P,
                                          const std::vector<int>& lines);

/// "orthogonal" / "zippered" (command line) and back; InputError naming the word otherwise.
const char* to_string(MultisineOptions::Design d);
MultisineOptions::Design multisine_design_from_string(const std::string& word);

/// The lines of a multisine of period P samples over [f_lo, f_hi] (harmonics k of fs / P).
/// kOrthogonal: a quasi-logarithmic grid, k_{j+1} = max(k_j + 1, floor(k_j r)),
/// r = 10^(1 / points_per_decade), from round(f_lo P / fs) (>= 1) while k f_s / P <= f_hi: every
/// ratio between neighbours is <= r, so every decade holds >= points_per_decade lines (all
/// harmonics where they are sparser than that). kZippered: the harmonics nearest log-spaced
/// targets, unique. Odd lines: only odd harmonics (k rounded up to odd). Either design adds the
/// zoom's lines (MultisineOptions::zoom), sorted in, each once.
std::vector<int> multisine_lines(const MultisineOptions& o, int P);

/// Crest-factor optimisation by envelope clipping (Van der Ouderaa, Schoukens and Renneboog's
/// clipping algorithm, 1988, applied to the analytic signal): from `phase` (radians, one per line
/// k of a period of P samples), `iterations` times: z[n] = sum_j exp(j (2 pi k_j n / P + phi_j)),
/// |z| clipped to 1.2 sqrt(|K|) (1.2 times its rms), transformed back, and phi_j the phase of line
/// k_j. Returns the phases of the lowest peak |z| met. Since every experiment of the orthogonal
/// design is Re(exp(j theta) z) for some theta, max |z| bounds the peak of all of them; a sine has
/// crest sqrt 2 and max |z| >= sqrt(2) rms.
std::vector<double> low_crest_phases(int P, const std::vector<int>& lines,
                                     std::vector<double> phase, int iterations = 200);

/// Periodic multisine campaign, sample-exact.
///
/// kZippered: all selected inputs at once with orthogonal (disjoint) line sets, so one run measures
/// the whole transfer matrix with few lines per input: the lines dealt to the excited inputs in
/// turn; each input's signal x_i[n] = a_i sum_{k in K_i} sin(2 pi k n / P + phi_k), phases
/// Schroeder (phi_k = -pi j (j - 1) / |K_i| for its j-th line) or random, a_i scaling the
/// period's peak to the input's amplitude. Settle periods (>= 1, >= the slowest time constants)
/// then `periods` measured periods in one "integrate" status (excitation "multisine", with
/// period_samples and the lines).
///
/// kOrthogonal: for realisation r and experiment e (0 <= e < n_u), excited input number q (its
/// position among the excited inputs) carries
///   x[n] = a_i sum_k sin(2 pi k n / P + phi_{r,q,k} + 2 pi q e / n_u)
/// on every line k (phi Schroeder over the lines, or random per realisation, input and line, or
/// those made low-crest (low_crest_phases); the
/// last term is the DFT phase matrix T_{qe} = exp(j 2 pi q e / n_u), unitary up to sqrt(n_u), so
/// the per-line input matrix U(k) = diag(.) T is as well conditioned as it can be); a_i scales
/// the largest peak over every experiment to the input's amplitude. Each experiment is a settle of
/// max(settle_time_constants * slowest time constant, 0.1 P) samples (one period when the time
/// constant is unknown) playing the periodic signal, then `periods` measured periods: a "settle"
/// and an "integrate" status with step = r n_u + e, n_steps = realisations n_u, the lines listed
/// once per excited input (lines[j] excited by inputs[line_input[j]]: a line listed for several
/// inputs marks the orthogonal design) and the realisation and experiment in the message. The
/// commands (tape channels u_<input>) are the references the analyser solves with.
class MultisineCampaign : public Campaign {
 public:
  MultisineCampaign(std::vector<CampaignInput> inputs, std::vector<int> excite,
                    const MultisineOptions& opt, std::string run_id);
  void fill(int64_t start, int n, std::vector<std::vector<double>>& cmd,
            std::vector<double>& ref_phase, std::vector<double>& ref_freq) const override;
  int period_samples() const { return P_; }

 private:
  // The periods of each experiment and input, unscaled, and the status's lines: orthogonal (every
  // input on every line, the DFT phase matrix across experiments) or zippered (lines dealt out).
  void design_orthogonal(const std::vector<int>& lines, const std::vector<int>& excite,
                         const MultisineOptions& o, std::vector<int>* ev_lines,
                         std::vector<int>* line_input);
  void design_zippered(const std::vector<int>& lines, const std::vector<int>& excite,
                       const MultisineOptions& o, std::vector<int>* ev_lines,
                       std::vector<int>* line_input);
  // Each excited input's periods scaled to its amplitude; returns the amplitudes (peaks).
  std::vector<double> scale_to_amplitudes(const std::vector<int>& excite,
                                          const MultisineOptions& o);
  // The settle, the experiment's length and the status events of n_exp experiments.
  void schedule(const MultisineOptions& o, int n_exp, int ni, StatusEvent e);
  // period_[x][i]: experiment x's (r n_u + e) period of input i's deviation (empty: idle).
  std::vector<std::vector<std::vector<double>>> period_;
  int P_ = 0;
  int64_t settle_ = 0;      // samples before each experiment's measured periods
  int64_t experiment_ = 0;  // samples per experiment (settle + periods)
};

/// Engine time of a plan for one input, seconds.
double plan_duration_s(const std::vector<SineStep>& steps, double sample_rate_hz);

}  // namespace fralab
