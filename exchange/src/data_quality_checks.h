// The data-quality checks' shared pieces (data_quality.cc drives them; data_quality.h is the
// contract): the schedule's windows cut into blocks, each block's values at the excited lines,
// the checks one room each (samples: lost, clipping, held; hum; drift and clock; spans without
// response) and the mending. Times are samples on the series' clock unless named _s; x is one
// channel's samples, x[0] at s.start_sample.
#pragma once

#include <complex>
#include <cstdint>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "fralab/core/text.h"
#include "fralab/exchange/data_quality.h"

namespace fralab::dq {

using Complex = std::complex<double>;
constexpr double kPi = std::numbers::pi;

inline std::string fmt(double v) { return significant(v, 4); }

/// The largest n <= N whose prime factors are 2, 3, 5 and 7 (FFTW's fast sizes).
int64_t smooth_size(int64_t N);
/// The median of v (the upper one of an even count); NaN for none.
double median(std::vector<double> v);

// One integration window of the schedule, cut into blocks: a multisine's periods, or a sine's
// blocks of whole cycles.
struct Window {
  int64_t from = 0, to = 0;  // first sample, one past the last (absolute)
  std::vector<int64_t> block_from, block_len;
  std::vector<double> freqs_hz;  // the excited frequencies
  bool multisine = false;
  int period = 0;
  std::vector<int> lines;  // multisine: excited bins of a period
  std::string signature;   // the excitation (inputs and amplitudes, lines): equal, equal response
  /// Multisine: the first sample of the settle's last period, just before `from` (the same
  /// excitation, its transient the least), or -1 when the series does not hold it.
  int64_t reference_from = -1;
};

/// The schedule's integration windows that the series holds whole, with at least two blocks.
std::vector<Window> windows_of(const Schedule& sch, const TimeSeries& s);

// Per block of a window: the channel's complex amplitude at each excited frequency (phase on the
// sample clock), its power there (the sum of |y|^2 over the excited frequencies), its mean, and
// the mean power on a period's non-excited bins in the excited band (multisine; NaN otherwise).
// A block holding a NaN sample has no values (empty, power 0).
struct BlockValues {
  std::vector<std::vector<Complex>> y;        // [block][frequency]
  std::vector<double> power, mean, t, noise;  // per block
};

/// Window w's blocks of x (x[0] at sample `start`, fs the sample rate in Hz).
BlockValues block_values(const Window& w, const double* x, int64_t start, double fs);

// Within-window regression of per-block values z_b on the blocks' times over every window:
// slope = sum_w W_w sum_b (t - tbar_w)(z - zbar_w) / sum_w W_w sum_b (t - tbar_w)^2, its sigma
// from the weights' information scaled by the residuals' reduced chi-square when above 1.
struct Slope {
  double value = 0, sigma = 0;
  int blocks = 0;
};
struct SlopeAccumulator {
  std::vector<std::vector<double>> t, z;
  std::vector<double> weight;
  void add(std::vector<double> tb, std::vector<double> zb, double W) {
    if (tb.size() < 2 || !(W > 0)) return;
    t.push_back(std::move(tb));
    z.push_back(std::move(zb));
    weight.push_back(W);
  }
  // `empirical`: sigma from the residual scatter alone (weights relative only).
  Slope solve(bool empirical) const;
};

// ---- the checks, each on one channel `ch` with samples x, appending what it finds to out ----

/// Whether the channel carries noise (repeats and flat tops are faults only then;
/// data_quality_samples.cc).
bool noisy(const double* x, int64_t N);
/// Samples that are NaN (a link that lost them).
void check_lost(const std::string& ch, const double* x, const TimeSeries& s,
                const DataQualityOptions& o, std::vector<DataFault>* out);
/// Clipping at the largest and the smallest value; returns them (held runs there are clipping).
std::pair<double, double> check_clipping(const std::string& ch, const double* x,
                                         const TimeSeries& s, std::vector<DataFault>* out);
/// Runs of identical samples away from the extremes hi and lo, beyond what the resolution makes
/// likely.
void check_held(const std::string& ch, const double* x, const TimeSeries& s, double hi, double lo,
                const DataQualityOptions& o, std::vector<DataFault>* out);
/// Lines at the mains frequency and its harmonics off the excitation's grid, over the channel's
/// first n_live samples (all by default: a channel that died keeps its hum only while it lives;
/// data_quality_hum.cc).
void check_hum(const std::string& ch, const double* x, const TimeSeries& s,
               const std::vector<Window>& windows, const DataQualityOptions& o,
               std::vector<DataFault>* out, int64_t n_live = -1);
/// A trend within the excitation's periods, and a phase that walks with time as a clock error
/// makes it (`values`: block_values of each of `windows` on x; data_quality_drift.cc).
void check_drift_and_clock(const std::string& ch, const double* x, const TimeSeries& s,
                           const std::vector<Window>& windows,
                           const std::vector<BlockValues>& values, const DataQualityOptions& o,
                           std::vector<DataFault>* out, std::vector<ClockEstimate>* clocks);
/// Spans where the channel holds no more than its noise at the excited lines, where the same
/// excitation gives a response elsewhere (data_quality_silence.cc).
void check_no_response(const std::string& ch, const TimeSeries& s,
                       const std::vector<Window>& windows, const std::vector<BlockValues>& values,
                       std::vector<DataFault>* out);
/// Eighths of periods at the noise where the same eighth of another period varies.
void check_silent_eighths(const std::string& ch, const double* x, const TimeSeries& s,
                          const std::vector<Window>& windows, std::vector<DataFault>* out);

// ---- the mending (data_quality_mend.cc) ----

/// The blocks overlapping a span set aside (spans of `faults`) emptied, as a block holding a NaN
/// sample is: the period comparisons pass them over.
void leave_out_spans(const std::vector<Window>& windows, const std::vector<DataFault>& faults,
                     std::vector<BlockValues>& values);
/// Every missing sample inside the windows filled from the excited lines: a multisine period by
/// period (a window's last, partial period from the whole one before it), a sine step over its
/// whole window.
void fill_missing(double* x, const TimeSeries& s, const std::vector<Window>& windows,
                  const std::vector<bool>& missing);
/// The samples of the series the fill treats as missing (x as recorded): those at the level of a
/// mended clipping of `faults`, and those of its mended gaps; empty when there are none.
std::vector<bool> missing_samples(const double* x, const TimeSeries& s,
                                  const std::vector<const DataFault*>& faults);
/// The mending of one channel in the documented order: gaps, hum, drift, clipping (given the
/// schedule's windows), clock, spans without response.
void mend_channel(double* x, const TimeSeries& s, const std::vector<const DataFault*>& faults,
                  const std::vector<Window>* windows = nullptr);

}  // namespace fralab::dq
