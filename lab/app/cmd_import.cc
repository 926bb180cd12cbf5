// `fralab import`: a time series recorded elsewhere (CSV, WAV, .mat) and its excitation schedule
// written as a fralab tape that `fralab analyze --log`, `fit` and `diagnose --measured` take as
// they take their own (exchange/time_series.h, schedule.h, tape_series.h; lcm/tape_file.h writes
// the tape).
#include <cstdio>
#include <memory>

#include "commands.h"
#include "fralab/exchange/data_quality.h"
#include "fralab/exchange/tape_series.h"
#include "fralab/lab/data_check.h"
#include "fralab/lcm/tape_file.h"

namespace fralab {

namespace {

struct ImportCommand {
  std::string series, schedule, out, schedule_out;
  SeriesReadOptions read;
  ReferenceScheduleOptions reference;
  double sample_rate_hz = 0;
  int block = 100;
};

void run(const ImportCommand& c) {
  // The schedule given, or found from the recorded reference channels.
  Schedule schedule;
  TimeSeries s;
  if (!c.schedule.empty()) {
    schedule = load_schedule(c.schedule);
    s = to_time_series(read_series(c.series, c.read), schedule.sample_rate_hz);
  } else {
    s = to_time_series(read_series(c.series, c.read), c.sample_rate_hz);
    schedule = schedule_from_reference(s, c.reference);
    std::printf("fralab: %zu steps found from the reference channels %s, %s\n",
                (schedule.events.size() - 2) / 2, c.reference.freq_channel.c_str(),
                c.reference.phase_channel.c_str());
  }
  if (!c.schedule_out.empty()) json_save_file(c.schedule_out, schedule_to_json(schedule));
  // The recording goes on the tape as it is; what its data show is said now (`fralab analyze`
  // mends it and writes the section beside the curves).
  print_data_quality(check_data_quality(s, schedule));
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
  c->add_option("--schedule", ic->schedule,
                "the excitation schedule (fralab-schedule/1 JSON); without it, the stepped-sine "
                "schedule is found from the recorded reference (--ref-freq, --ref-phase)");
  c->add_option("--ref-freq", ic->reference.freq_channel, "reference frequency channel, Hz")
      ->capture_default_str();
  c->add_option("--ref-phase", ic->reference.phase_channel, "reference phase channel, radians")
      ->capture_default_str();
  c->add_option("--min-cycles", ic->reference.min_cycles,
                "without --schedule: cycles per point, as the measurement used")
      ->capture_default_str();
  c->add_option("--min-integrate-s", ic->reference.min_integrate_s,
                "without --schedule: seconds per point at least, as the measurement used")
      ->capture_default_str();
  c->add_option("--run-id", ic->reference.run_id, "without --schedule: the tape's run id")
      ->capture_default_str();
  c->add_option("--sample-rate", ic->sample_rate_hz,
                "without --schedule: Hz (default: the WAV's, or the time column's)");
  c->add_option("--schedule-out", ic->schedule_out, "also write the schedule used (JSON)");
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
