// The recording's faults told from the plant's response: a run's channels, as recorded, checked
// against what a clean recording of a periodic excitation looks like, before anything is fitted.
// In: the series and its schedule (the integrate windows). Out: each fault with its channel, kind,
// time span and figure; what can be mended is mended in a copy (mend_series; the tape stays as
// recorded). Checked: every channel but the commands u_<input>, the reference (ref_*) and the
// underrun flag. Times are seconds on the sample clock (t = n / fs); hum in Hz, phases degrees.
//   lost, held  NaN samples; runs of repeats a noisy channel's resolution makes improbable. Both
//               interpolated up to max_gap_s, then filled inside the windows as clipped ones are.
//   clipping    samples at the channel's extreme; inside the windows refilled by least squares on
//               the kept ones, x[n] ~ c0 + sum_k (a_k cos 2 pi k n / P + b_k sin 2 pi k n / P),
//               k the excited bins (a sine: its frequency, 2nd and 3rd harmonics, a straight line).
//   hum         a lasting line at m 50 or m 60 Hz off the excited lines, fitted and subtracted.
//   drift       block means sloping within windows (> drift_sigmas): rate (t - t_mid) subtracted.
//   clock       rate eps = d tau_b / dt (> 0: the channel's clock runs fast), from block delays
//               tau_b = -sum_k |Y_k|^2 w_k phi_bk / sum_k |Y_k|^2 w_k^2 (w in rad/s); mended by
//               reading sample n at n / (1 - eps).
//   no response periods, or eighths of them, holding only noise where the excitation gives more.
// Left NaN: gaps over max_gap_s, stretches too clipped to fit, spans without response (with the
// period either side); the analyser makes the windows they cut invalid, naming the gap. A wiring
// sign, a units factor or swapped channels are the diagnosis' to name (diagnose/data_faults.h).
// Method: docs/method/data-quality.md ("The checks", "Each test").
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
