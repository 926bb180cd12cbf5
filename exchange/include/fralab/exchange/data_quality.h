// The recording's faults told from the plant's response (docs/method/data-quality.md): a run's
// channels, as recorded, checked against what a clean recording of a periodic excitation looks
// like, before anything is fitted. What can be mended is mended in a copy of the series (the tape
// itself stays as recorded); what cannot is said, with its channel and time span.
//
// Channels checked: every channel of the series except the commands u_<input>, the reference
// (ref_*) and the plant's underrun flag. Times are seconds on the sample clock (t = n / fs).
// Checks, each on one channel x[n]:
//   lost      samples that are NaN (a link that lost them). Mended by linear interpolation between
//             the good samples either side when the gap is at most max_gap_s (so that the hum and
//             drift checks see no hole), then, inside the integration windows, filled as clipped
//             samples are (below: a straight line across a gap of a tenth of a period at the
//             band's top is no response); longer gaps stay NaN (the analyser then makes the
//             windows they cut invalid, naming the gap).
//   held      runs of identical consecutive samples (a link that repeated its last value) away
//             from the channel's extremes, on a channel whose resolution makes a repeat
//             improbable: repeats are expected with probability q / (sigma_d sqrt(2 pi)) per
//             sample (q the smallest nonzero step, sigma_d the robust spread of the steps);
//             flagged when runs of two or more exceed 5 sqrt(expected) + 3. Mended as lost.
//   (held samples and clipping are looked for only on a channel with noise: its nonzero 4th
//   differences changing sign from one sample to the next in more than 3 of 5 pairs, as white
//   noise's do in 4 of 5 and a smooth signal's do not; a noise-free channel holds a value exactly
//   where the plant does, a backlash's dwell or an actuator at its stop)
//   clipping  samples equal to the channel's largest (smallest) value, when at least
//             max(20, 3 m2 + 3) of them and 0.01 % of the run (m2: how many share the next
//             value inside; a handful at an actuator's own stop is no range): a transducer
//             or converter at its range; the share of samples and the level are reported.
//             Mended inside the integration windows: the clipped samples are missing data, each
//             multisine period's (a sine step's window's) samples inside the range fitted by
//             least squares with the window's basis, x[n] ~ c0 + sum_k (a_k cos 2 pi k n / P +
//             b_k sin 2 pi k n / P) over its excited bins k (a sine: its frequency and 2nd and
//             3rd harmonics, plus a straight line), and the fit put in the clipped samples'
//             place, so the Fourier filter's lines are those of the samples the range kept.
//             A stretch keeping fewer than twice the basis' samples is set NaN instead.
//   hum       lines at multiples m = 1..max_harmonic of 50 and 60 Hz (within mains_search_hz),
//             away from every excited line, standing above the spectrum around them: |X|^2 of
//             the Hann-windowed channel above hum_ratio times the mean noise power there (the
//             median over +-2 Hz, excited lines and the candidate excluded, over ln 2) and as
//             far above a multisine's non-excited grid lines there (where its distortion sits),
//             and lasting: in each quarter of the run at least half its amplitude over the run
//             (a sine step's harmonic holds in one), and above 1e-9 of the channel's range or
//             level (a noise-free channel's rounding). The frequency is refined (Brent on the
//             line's amplitude), its amplitude A and phase fitted over the channel, and the
//             sinusoid subtracted.
//   drift     the means of each eighth of a multisine's period (a sine window's blocks of whole
//             cycles) regressed on time within each window, each eighth its own offset: a slope
//             beyond drift_sigmas times its sigma (from the means' scatter about the lines).
//             Mended by subtracting rate (t - t_mid).
//   clock     the channel's own clock runs at another rate than the excitation's: within each
//             integration window, the phase of each block (a multisine period; a sine's block of
//             whole cycles) at the excited frequencies of the band's top 1.3 decades (above a
//             twentieth of its highest line: a slow mode's leftover transient moves the low lines'
//             phases, a clock the high lines' most) against the window's mean gives the delay
//             of the block, tau_b = -sum_k |Y_k|^2 w_k phi_bk / sum_k |Y_k|^2 w_k^2 (w in rad/s);
//             tau_b regressed on the block's time over every window gives the rate error
//             eps = d tau / dt (> 0: the channel's samples lag more and more, its clock runs
//             fast), pooled with the campaign's other runs' estimates of the channel that agree
//             (DataQualityOptions::other_runs; weights 1 / sigma^2), flagged where the pool is
//             beyond clock_sigmas times its sigma and above min_clock. Where a
//             multisine's lines stand far above the noise (the strongest period's power over
//             100 times what its non-excited lines give them), a period with less than half that
//             power (a clock moves phases, not power: dead or stuck for part of the period) is
//             left out; a sine window of fewer than four blocks is (its noise, from the blocks'
//             scatter, unknown).
//             Mended by reading sample n of the channel at n / (1 - eps) (linear interpolation; the
//             clocks taken as agreeing at sample 0: an offset between them is a delay the data
//             cannot tell from the plant's).
//   no response  a multisine period whose excited lines hold no more than the noise (power
//             below 4 times that of the non-excited lines) while the same excitation gives more
//             than 30 times in a quarter of the run's periods: a dead channel (to the end) or an
//             actuator stuck or its sensor silent (a span). Set aside with the period either
//             side (NaN in the mended series): the windows holding it give invalid points.
//             Within periods: a multisine's response repeats each period, so each eighth of a
//             measured period is compared with the same eighth of its window's other periods and
//             of the settle's last period (a reference only, where it is a whole period): an
//             eighth whose variance about its mean is within 1.5 times the noise's (half the
//             variance of its first differences; white noise gives 1) where another period's same
//             eighth varies over 30 times the noise is silent; two or more silent eighths in a
//             row (eighths no period shows are passed over) are a span without response, named
//             from its first silent eighth: a channel that died inside a period, or before the
//             first measured one (every measured period silent, the settle not). The periods
//             holding it are set aside whole.
// Faults the data alone cannot tell (a wiring sign, a units factor, two channels swapped) are
// the diagnosis' to name beside its findings (diagnose/data_faults.h).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "fralab/core/frd.h"
#include "fralab/core/json_util.h"
#include "fralab/exchange/schedule.h"
#include "fralab/exchange/time_series.h"

namespace fralab {

enum class DataFaultKind { kLost, kHeld, kClipping, kHum, kDrift, kClock, kNoResponse };
/// "lost_samples", "held_samples", "clipping", "hum", "drift", "clock", "no_response".
const char* to_string(DataFaultKind k);

struct DataFault {
  std::string channel;
  DataFaultKind kind = DataFaultKind::kLost;
  double from_s = 0.0, to_s = 0.0;  // the span it was seen in, s
  /// The kind's figure: lost/held/clipping the share of the channel's samples; hum the
  /// amplitude (channel units, peak); drift the rate (units/s); clock the rate error eps;
  /// no_response its length, s.
  double size = 0.0;
  double sigma = 0.0;         // drift, clock: the figure's standard deviation; else 0
  double frequency_hz = 0.0;  // hum: the line, Hz
  double phase_deg = 0.0;     // hum: A cos(2 pi f t + phase) on the sample clock, degrees
  double level = 0.0;         // clipping: the value clipped at; held/lost: samples mended
  bool mended = false;        // the analysis uses the series with it mended
  std::string action;         // what was done, one sentence
  std::string text;           // what was seen, one sentence
  /// held/lost: the runs of samples mended, [first, last] sample numbers (not in the JSON).
  std::vector<std::pair<int64_t, int64_t>> spans;
};

/// A channel's clock rate error eps as one run measured it (flagged or not), for pooling with the
/// campaign's other runs: the same recorder, the same rate.
struct ClockEstimate {
  std::string channel;
  double eps = 0.0, sigma = 0.0;
  double t_mid_s = 0.0;  // the middle of the windows it came from, s on the sample clock
  std::string run;       // the run's folder (the lab's label; "" from check_data_quality)
};

/// Per channel its estimates in `all` pooled with weights 1 / sigma^2: eps and sigma the pool's,
/// t_mid_s and run the first estimate's (estimates without a sigma left out).
std::map<std::string, ClockEstimate> pool_clocks(const std::vector<ClockEstimate>& all);

struct DataQualityOptions {
  double max_gap_s = 0.1;        // lost/held runs mended up to this length, s
  double mains_search_hz = 0.5;  // hum: around each multiple of 50 and 60 Hz, Hz
  int max_harmonic = 5;          // hum: multiples checked
  double hum_ratio = 100.0;      // hum: line power over the mean noise power there
  double drift_sigmas = 8.0;     // drift: slope over its sigma
  double clock_sigmas = 6.0;     // clock: rate error over its sigma
  double min_clock = 2e-6;       // clock: below this, not reported (2 ppm)
  /// A simulation without noise: a channel repeats exactly where nothing excites it, so held
  /// samples are not looked for.
  bool noise_free = false;
  /// The campaign's other runs' clock estimates (DataQuality::clocks of each): a channel's own
  /// estimate is pooled with those of it that agree, and the pool decides; a run without its own
  /// (a sine of two-cycle steps) takes the others'.
  std::vector<ClockEstimate> other_runs;
  /// Throws InputError naming the option.
  void validate() const;
};

struct DataQuality {
  std::vector<std::string> checked;  // channels checked
  std::vector<DataFault> faults;     // in channel order, then kind
  /// Each channel's own clock estimate where its windows give one (not in the JSON): what the
  /// campaign's other runs pool with (DataQualityOptions::other_runs).
  std::vector<ClockEstimate> clocks;
  bool any_mended() const;
  /// A fault mended, or one that widens the curves' sigmas (widen_for_mending): the run's curves
  /// are then analysed again.
  bool changes_curves() const;
};

/// The checks above on `s`, with the excitation of `schedule` (its integrate windows).
DataQuality check_data_quality(const TimeSeries& s, const Schedule& schedule,
                               const DataQualityOptions& o = {});
/// `s` with every fault of `q` marked mended undone (the tape itself is not touched); the
/// schedule's integration windows are where clipped samples are filled.
TimeSeries mend_series(const TimeSeries& s, const DataQuality& q, const Schedule& schedule);

/// The curves of a mended series with the uncertainty the faults leave added to each point's
/// sigma, for a pair with the fault's channel as E1 or E2: a mended clock error's sigma_eps is a
/// delay error up to sigma_eps to_s at the run's end, sigma^2 + (|G| w sigma_eps to_s)^2; a
/// clipping left unmended (a section read from a run recorded before the fill) biases the gain by
/// about its share p of the samples (a saturation's describing function over a multisine's rare
/// peaks), sigma^2 + (p |G|)^2.
void widen_for_mending(std::vector<Frd>& curves, const DataQuality& q);

/// docs/formats.md §13 "data_quality": {"checked": [...], "faults": [{"channel", "kind",
/// "from_s", "to_s", "size", "sigma", "frequency_hz", "phase_deg", "level", "mended", "action",
/// "text"}]}.
Json data_quality_to_json(const DataQuality& q);
/// InputError naming `where` for a malformed section.
DataQuality data_quality_from_json(const Json& j, const JsonWhere& where);

}  // namespace fralab
