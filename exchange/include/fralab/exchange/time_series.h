// Time series recorded elsewhere, and written for use elsewhere (docs/exchange.md, `fralab import`
// and `fralab export --tape`): named channels sampled on one clock.
//
// The clock: row k of a series is sample n = start_sample + k, at time t = n / sample_rate_hz
// seconds (the tape's sample clock, docs/formats.md §3). Files that carry a time column are
// checked against it: times strictly increasing, each step within kClockTolerance of a sample
// period (a larger step is a gap, a smaller one a clock that is not the schedule's), first time on
// the clock within kClockTolerance of a period.
//
// File forms (readers name the file and the row, channel or variable of anything wrong):
//  - CSV: a header row naming the columns, one row per sample, comma separated; `#` lines are
//    comments (the writer puts the units there). The time column is named by `time_column`
//    (default "t", seconds). Every other column is a channel.
//  - WAV (PCM or float, any channel count): no time column; the clock is the file's sample rate,
//    channel names are given in order, each channel value = scale * sample + offset.
//  - MATLAB/Octave .mat v5 (read and written with matio): a time vector named `time_column` and
//    one real vector of the same length per channel, named as the channel; other variables (and
//    `units`, a struct of unit strings per channel, which the writer adds) are not channels.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fralab/core/text.h"

namespace fralab {

/// Largest departure of a time step from one sample period, in periods.
inline constexpr double kClockTolerance = 1e-3;

/// samples are channel-major, as in a tape Block: samples[c * n_samples + k].
struct TimeSeries {
  std::vector<std::string> channels;
  std::vector<std::string> units;  // per channel, "" when unknown
  double sample_rate_hz = 0.0;
  int64_t start_sample = 0;
  int64_t n_samples = 0;
  std::vector<double> samples;
  std::string source;  // the file it came from, for messages

  double at(size_t c, int64_t k) const { return samples[c * size_t(n_samples) + size_t(k)]; }
  int channel_index(const std::string& name) const { return index_of(channels, name); }
};

/// What a reader hands over before the clock is checked: columns by name and, except for WAV,
/// the time column.
struct RawSeries {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  std::vector<std::string> units;  // per name ("" unknown), or empty
  std::vector<double> time;        // empty: no time column (WAV)
  double sample_rate_hz = 0.0;     // WAV's header rate; 0 otherwise
  std::string source;
  int first_row_line = 0;  // CSV: the file line of the first data row (messages); 0: sample index
};

/// Where options of the import sit (flags of `fralab import`).
struct SeriesReadOptions {
  std::string time_column = "t";
  std::vector<std::string> wav_channels;  // WAV: the channel names, in order (required)
  std::vector<double> wav_scale;          // WAV: per channel (empty: 1)
  std::vector<double> wav_offset;         // WAV: per channel (empty: 0)
  void validate() const;                  // InputError naming the option
};

RawSeries read_csv_series(const std::string& path, const SeriesReadOptions& o);
RawSeries read_wav_series(const std::string& path, const SeriesReadOptions& o);
RawSeries read_mat_series(const std::string& path, const SeriesReadOptions& o);
/// By extension: .csv, .wav, .mat; InputError naming the file otherwise.
RawSeries read_series(const std::string& path, const SeriesReadOptions& o);

/// Puts a raw series on the sample clock of `sample_rate_hz` (0: the WAV header's rate, or the
/// time column's mean rate, rounded to a whole number of Hz within 1e-6). Checks
/// every sample is finite (a NaN names its channel, row and time), the time column increasing,
/// without gaps and on the clock (see the header comment), and for WAV that the rates agree.
TimeSeries to_time_series(const RawSeries& raw, double sample_rate_hz);

/// Writers (the time column "t" in seconds, t = n / sample_rate_hz written losslessly, so a series
/// read back lands on the same sample indices; values losslessly).
void write_csv_series(const std::string& path, const TimeSeries& s);
void write_mat_series(const std::string& path, const TimeSeries& s);

}  // namespace fralab
