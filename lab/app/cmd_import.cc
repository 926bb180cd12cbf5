// `fralab import`: a time series recorded elsewhere (CSV, WAV, .mat) and its excitation schedule
// written as a fralab tape that `fralab analyze --log`, `fit` and `diagnose --measured` take as
// they take their own (exchange/time_series.h, schedule.h, tape_series.h; lcm_io writes the tape).
#include <cstdio>
#include <memory>

#include "commands.h"
#include "fralab/exchange/tape_series.h"
#include "fralab/lcm_io.h"

namespace fralab {

namespace {

struct ImportCommand {
  std::string series, schedule, out;
  SeriesReadOptions read;
  int block = 100;
};

void run(const ImportCommand& c) {
  const Schedule schedule = load_schedule(c.schedule);
  const TimeSeries s = to_time_series(read_series(c.series, c.read), schedule.sample_rate_hz);
  const std::vector<Block> blocks = series_to_blocks(s, schedule, c.block);
  write_tape_file(c.out, blocks, schedule.events);
  std::printf(
      "fralab: %lld samples of %zu channels (t = %g .. %g s) and %zu status events to %s (run "
      "%s)\n",
      static_cast<long long>(s.n_samples), s.channels.size(),
      double(s.start_sample) / s.sample_rate_hz,
      double(s.start_sample + s.n_samples - 1) / s.sample_rate_hz, schedule.events.size(),
      c.out.c_str(), schedule.run_id.c_str());
}

}  // namespace

void add_import_command(CLI::App& app) {
  auto ic = std::make_shared<ImportCommand>();
  auto* c = app.add_subcommand("import",
                               "a time series recorded elsewhere (.csv, .wav, .mat) and its "
                               "excitation schedule, as a fralab tape");
  c->add_option("--series", ic->series, "the recording: .csv, .wav or .mat")->required();
  c->add_option("--schedule", ic->schedule, "the excitation schedule (fralab-schedule/1 JSON)")
      ->required();
  c->add_option("--out", ic->out, "the tape to write (LCM log)")->required();
  c->add_option("--time", ic->read.time_column, "CSV and .mat: the time column (seconds)");
  c->add_option("--channels", ic->read.wav_channels, "WAV: the channel names, in order")
      ->delimiter(',');
  c->add_option("--scale", ic->read.wav_scale, "WAV: value = scale * sample + offset, per channel")
      ->delimiter(',');
  c->add_option("--offset", ic->read.wav_offset, "WAV: per channel")->delimiter(',');
  c->add_option("--block", ic->block, "samples per tape block (default 100)");
  c->callback([ic] { run(*ic); });
}

}  // namespace fralab
