// The exchange library (docs/exchange.md): time series in CSV, WAV and .mat read onto the sample
// clock, every malformed file refused naming what and where; schedules; a run's blocks as a series
// and back; the results written to .mat read back by matio.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <matio.h>
#include <sndfile.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "fralab/core/error.h"
#include "fralab/exchange/envelope_export.h"
#include "fralab/exchange/mat_file.h"
#include "fralab/exchange/schedule.h"
#include "fralab/exchange/tape_series.h"
#include "fralab/exchange/time_series.h"

using namespace fralab;
using testing::HasSubstr;
using testing::ThrowsMessage;
namespace fs = std::filesystem;

namespace {

std::string tmp(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("fralab_exchange_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return (d / name).string();
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// Two channels at 200 Hz from sample 40: values that are not short decimals (lossless writing).
TimeSeries known_series() {
  TimeSeries s;
  s.channels = {"u_X", "Y"};
  s.units = {"mm", "bar"};
  s.sample_rate_hz = 200;
  s.start_sample = 40;
  s.n_samples = 50;
  for (int c = 0; c < 2; ++c)
    for (int k = 0; k < 50; ++k) s.samples.push_back(std::sin(0.1 * k + c) / 3.0 + 1e-9 * k);
  return s;
}

std::string read_error(const std::string& csv, double fs = 100) {
  const std::string p = tmp("bad.csv");
  write_text(p, csv);
  try {
    to_time_series(read_csv_series(p, {}), fs);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(TimeSeriesCsv, WrittenSeriesReadsBackBitForBitOnTheSameSamples) {
  const TimeSeries s = known_series();
  const std::string p = tmp("s.csv");
  write_csv_series(p, s);
  const TimeSeries r = to_time_series(read_csv_series(p, {}), 200);
  EXPECT_EQ(r.channels, s.channels);
  EXPECT_EQ(r.units, s.units);
  EXPECT_EQ(r.start_sample, 40);
  EXPECT_EQ(r.n_samples, 50);
  EXPECT_EQ(r.samples, s.samples);  // exact: lossless text
}

TEST(TimeSeriesCsv, MalformedFilesAreRefusedNamingTheLineAndChannel) {
  EXPECT_THAT(read_error("time,y\n0,1\n"), HasSubstr("no time column 't' (columns: time, y"));
  EXPECT_THAT(read_error("t,y\n0,1\n0.01,2\n0.005,3\n"),
              HasSubstr("line 4: time goes back or stands still"));
  EXPECT_THAT(read_error("t,y\n0,1\n0.01,2\n0.04,3\n"),
              HasSubstr("line 4: a gap of 2 samples before t = 0.04 s"));
  EXPECT_THAT(read_error("t,y\n0,1\n0.01,NaN\n"),
              HasSubstr("line 3 (t = 0.01 s): channel 'y' is NaN"));
  EXPECT_THAT(read_error("t,y\n0,1\n0.0105,2\n"),
              HasSubstr("line 3: t = 0.0105 s is off the 100 Hz"));
  EXPECT_THAT(read_error("t,y\n0,1\n0.01,2,3\n"),
              HasSubstr("bad.csv:3: 3 fields, the header names 2"));
  EXPECT_THAT(read_error("t,y\n0,1\n0.01,abc\n"),
              HasSubstr("bad.csv:3: column 'y': 'abc' is not a number"));
  EXPECT_THAT(read_error("t,y,y\n0,1,1\n"), HasSubstr("column 'y' named twice"));
  EXPECT_THAT(read_error("# only a comment\n"), HasSubstr("no header row"));
  EXPECT_THAT(read_error("t,y\n"), HasSubstr("no data rows"));
  EXPECT_THAT(read_error("t,y\n1e300,1\n"), HasSubstr("line 2: time 1e+300 s is out of range"));
  EXPECT_EQ(read_error("t,y\n0,1\n0.01,2\n"), "(no error)");
}

TEST(TimeSeriesWav, ChannelsAreScaledAndOffsetOnTheFileClock) {
  const std::string p = tmp("s.wav");
  SF_INFO info{};
  info.samplerate = 1000;
  info.channels = 2;
  info.format = SF_FORMAT_WAV | SF_FORMAT_DOUBLE;
  SNDFILE* f = sf_open(p.c_str(), SFM_WRITE, &info);
  ASSERT_NE(f, nullptr);
  std::vector<double> frames;
  for (int k = 0; k < 300; ++k) {
    frames.push_back(0.5 * std::sin(0.01 * k));
    frames.push_back(-0.25 + 0.001 * k);
  }
  ASSERT_EQ(sf_writef_double(f, frames.data(), 300), 300);
  sf_close(f);

  SeriesReadOptions o;
  o.wav_channels = {"u_X", "Y"};
  o.wav_scale = {10.0, 4.0};
  o.wav_offset = {100.0, 0.0};
  const TimeSeries s = to_time_series(read_wav_series(p, o), 0);
  EXPECT_EQ(s.sample_rate_hz, 1000);
  ASSERT_EQ(s.n_samples, 300);
  for (int k = 0; k < 300; ++k) {
    EXPECT_NEAR(s.at(0, k), 100 + 5 * std::sin(0.01 * k), 1e-12) << k;
    EXPECT_NEAR(s.at(1, k), -1 + 0.004 * k, 1e-12) << k;
  }
  // The schedule's clock must be the file's.
  EXPECT_THAT([&] { to_time_series(read_wav_series(p, o), 2000); },
              ThrowsMessage<InputError>(HasSubstr("sampled at 1000 Hz, the schedule at 2000 Hz")));
  o.wav_channels = {"u_X"};
  o.wav_scale = o.wav_offset = {};
  EXPECT_THAT([&] { read_wav_series(p, o); },
              ThrowsMessage<InputError>(HasSubstr("2 channels in the file, 1 named")));
  o.wav_channels = {};
  EXPECT_THAT([&] { read_wav_series(p, o); },
              ThrowsMessage<InputError>(HasSubstr("names no channels")));
  write_text(p, "not a wav");
  o.wav_channels = {"a", "b"};
  EXPECT_THAT([&] { read_wav_series(p, o); }, ThrowsMessage<InputError>(HasSubstr("s.wav")));
}

TEST(TimeSeriesMat, WrittenSeriesReadsBackBitForBit) {
  const TimeSeries s = known_series();
  const std::string p = tmp("s.mat");
  write_mat_series(p, s);
  const TimeSeries r = to_time_series(read_mat_series(p, {}), 200);
  EXPECT_EQ(r.channels, s.channels);
  EXPECT_EQ(r.start_sample, 40);
  EXPECT_EQ(r.samples, s.samples);
  SeriesReadOptions o;
  o.time_column = "time";
  EXPECT_THAT([&] { read_mat_series(p, o); },
              ThrowsMessage<InputError>(HasSubstr("no time vector 'time' (vectors: t, u_X, Y")));
  write_text(p, "garbage");
  EXPECT_THAT([&] { read_mat_series(p, {}); },
              ThrowsMessage<InputError>(HasSubstr("not a .mat file matio can read")));
}

TEST(MatFile, ValuesReadBackThroughMatio) {
  const std::string p = tmp("v.mat");
  MatValue st = MatValue::structure();
  st.add("name", MatValue::str("Wf:P3"));
  st.add("H", MatValue::complex_column({{1, -2}, {0.5, 0.25}}));
  write_mat_file(
      p,
      {{"w", MatValue::column({1, 2, 4})}, {"names", MatValue::str_list({"a", "bc"})}, {"s", st}});
  std::vector<std::string> skipped;
  const auto v = read_mat_vectors(p, &skipped);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].first, "w");
  EXPECT_EQ(v[0].second, (std::vector<double>{1, 2, 4}));
  EXPECT_EQ(skipped, (std::vector<std::string>{"names", "s"}));
  EXPECT_THAT(
      [&] {
        write_mat_file(p, {{"1x", MatValue::scalar(1)}});
      },
      ThrowsMessage<InputError>(HasSubstr("'1x' is not a MATLAB name")));
}

// One value of a struct path ("findings", "finding_01", "value") in a .mat file, read by matio.
std::vector<double> mat_struct_doubles(const std::string& file,
                                       const std::vector<std::string>& path) {
  mat_t* m = Mat_Open(file.c_str(), MAT_ACC_RDONLY);
  if (!m) return {};
  matvar_t* top = Mat_VarRead(m, path[0].c_str());
  std::vector<double> out;
  matvar_t* v = top;
  for (size_t i = 1; v && i < path.size(); ++i)
    v = Mat_VarGetStructFieldByName(v, path[i].c_str(), 0);
  if (v && v->class_type == MAT_C_DOUBLE && v->data) {
    const double* d = static_cast<const double*>(v->data);
    out.assign(d, d + v->dims[0] * v->dims[1]);
  }
  Mat_VarFree(top);
  Mat_Close(m);
  return out;
}

// An envelope (envelope.json as fralab envelope writes it) to .mat: a real state's |root| is
// 1/tau, a finding's values and law read back; a document of another format is refused by name.
TEST(EnvelopeExport, TheEnvelopesTablesReadBackThroughMatio) {
  const fs::path d = fs::path(tmp("envelope"));
  fs::create_directories(d);
  Json env = Json::parse(R"({"format": "fralab-envelope/1", "schedule_by": "speed_pct",
    "points": [{"name": "speed_pct_70", "x": 70}, {"name": "speed_pct_95", "x": 95}],
    "states": [{"label": "plant", "kind": "real", "at_every_point": true, "monotone": true,
      "flags": "", "values": [
        {"point": "speed_pct_70", "x": 70, "tau_s": 1.25, "spread": [1.2, 1.3], "rel_sigma": 0.02,
         "scope": "plant", "paths": ["Wf:N"]},
        {"point": "speed_pct_95", "x": 95, "tau_s": 0.4, "spread": [0.4, 0.4],
         "scope": "plant", "paths": ["Wf:N"]}]}],
    "findings": [{"cause": "pole_shift", "scope": "input", "input": "A8", "output": "",
      "parameter": "to_rad_s", "text": "t", "missing_at": [],
      "law": {"form": "linear", "a": -16.8, "b": 0.44, "b_sigma": 0.01, "criterion": 1},
      "values": [{"point": "speed_pct_70", "x": 70, "value": 27.2, "sigma": 0.2, "simulated": 3.14},
                 {"point": "speed_pct_95", "x": 95, "value": 38.2, "sigma": 0.3}]}],
    "leave_one_out": []})");
  json_save_file((d / "envelope.json").string(), env);
  ASSERT_TRUE(is_envelope_dir(d.string()));
  const std::string out = (d / "e.mat").string();
  export_envelope_mat(d.string(), out);
  EXPECT_EQ(mat_struct_doubles(out, {"points", "x"}), (std::vector<double>{70, 95}));
  EXPECT_EQ(mat_struct_doubles(out, {"states", "state_01", "root_rad_s"}),
            (std::vector<double>{1 / 1.25, 1 / 0.4}));
  const auto sigma = mat_struct_doubles(out, {"states", "state_01", "rel_sigma"});
  ASSERT_EQ(sigma.size(), 2u);
  EXPECT_EQ(sigma[0], 0.02);
  EXPECT_TRUE(std::isnan(sigma[1])) << "unknown: NaN";
  EXPECT_EQ(mat_struct_doubles(out, {"findings", "finding_01", "value"}),
            (std::vector<double>{27.2, 38.2}));
  EXPECT_EQ(mat_struct_doubles(out, {"findings", "finding_01", "law", "b"}),
            (std::vector<double>{0.44}));
  env["format"] = "fralab-envelope/9";
  json_save_file((d / "envelope.json").string(), env);
  EXPECT_THAT(
      [&] { export_envelope_mat(d.string(), out); },
      ThrowsMessage<InputError>(HasSubstr("envelope.json: /format: not fralab-envelope/1")));
}

// The start event's measurement chain is a key of its own in a schedule and reads back typed; a
// schedule written when the chain was the start event's message still gives it.
TEST(Schedule, TheStartEventsMeasurementChainIsKeptAndOldSchedulesStillGiveIt) {
  Schedule s;
  s.sample_rate_hz = 1000;
  s.run_id = "r";
  StatusEvent e;
  e.seq = -1;
  e.state = RunState::kStart;
  e.inputs = {"A"};
  e.amplitudes = {0.5};
  MeasurementChain c;
  c.sample_rate_hz = 500;
  c.hold = MeasurementChain::Hold::kZeroOrder;
  c.converter_delay_s = 0.002;
  c.reheld_inputs = {"A"};
  e.measurement_chain = c;
  s.events = {e};
  Json j = schedule_to_json(s);
  ASSERT_TRUE(j["events"][0].contains("measurement_chain"));
  const Schedule r = schedule_from_json(j, "s.json");
  ASSERT_TRUE(r.events[0].measurement_chain.has_value());
  EXPECT_EQ(r.events[0].measurement_chain->sample_rate_hz, 500);
  EXPECT_EQ(r.events[0].measurement_chain->hold, MeasurementChain::Hold::kZeroOrder);
  EXPECT_EQ(r.events[0].measurement_chain->converter_delay_s, 0.002);
  EXPECT_EQ(r.events[0].measurement_chain->reheld_inputs, std::vector<std::string>{"A"});

  j["events"][0].erase("measurement_chain");
  j["events"][0]["message"] = chain_to_message(c);
  const Schedule old = schedule_from_json(j, "old.json");
  ASSERT_TRUE(old.events[0].measurement_chain.has_value());
  EXPECT_EQ(old.events[0].measurement_chain->converter_delay_s, 0.002);
  j["events"][0].erase("message");
  EXPECT_FALSE(schedule_from_json(j, "none.json").events[0].measurement_chain.has_value());
}

TEST(Schedule, JsonRoundTripKeepsEveryFieldAndErrorsNameThePath) {
  Schedule s;
  s.sample_rate_hz = 1000;
  s.run_id = "r";
  StatusEvent e;
  e.seq = 3;
  e.sample = 1234;
  e.excitation = Excitation::kMultisine;
  e.state = RunState::kIntegrate;
  e.frequency_hz = 0.1 + 1e-12;
  e.ref_phase_rad = 1.0 / 3.0;
  e.n_samples = 4000;
  e.inputs = {"A", "B"};
  e.amplitudes = {0.5, 0.25};
  e.period_samples = 2000;
  e.lines = {3, 5};
  e.line_input = {0, 1};
  s.events = {e};
  const std::string p = tmp("s.schedule.json");
  json_save_file(p, schedule_to_json(s));
  const Schedule r = load_schedule(p);
  ASSERT_EQ(r.events.size(), 1u);
  const StatusEvent& x = r.events[0];
  EXPECT_EQ(x.frequency_hz, e.frequency_hz);
  EXPECT_EQ(x.ref_phase_rad, e.ref_phase_rad);
  EXPECT_EQ(x.lines, e.lines);
  EXPECT_EQ(x.line_input, e.line_input);
  EXPECT_EQ(x.run_id, "r");
  EXPECT_EQ(x.sample_rate_hz, 1000);
  EXPECT_EQ(x.excitation, Excitation::kMultisine);

  Json j = schedule_to_json(s);
  j["events"][0]["state"] = "running";
  EXPECT_THAT([&] { schedule_from_json(j, "f.json"); },
              ThrowsMessage<InputError>(HasSubstr("running")));
  j = schedule_to_json(s);
  j["events"][0]["amplitudes"] = {1.0};
  EXPECT_THAT([&] { schedule_from_json(j, "f.json"); },
              ThrowsMessage<InputError>(HasSubstr("f.json: /events/0: 1 amplitudes for 2 inputs")));
  j = schedule_to_json(s);
  j["events"][0]["frequency_hz"] = 600;
  EXPECT_THAT([&] { schedule_from_json(j, "f.json"); },
              ThrowsMessage<InputError>(HasSubstr("/events/0/frequency_hz")));
  j = schedule_to_json(s);
  j["format"] = "other/1";
  EXPECT_THAT([&] { schedule_from_json(j, "f.json"); },
              ThrowsMessage<InputError>(HasSubstr("expected fralab-schedule/1")));
}

TEST(TapeSeries, BlocksToSeriesAndBackKeepEverySampleWhateverTheBlockSize) {
  const TimeSeries s = known_series();
  Schedule sched;
  sched.sample_rate_hz = 200;
  sched.run_id = "imp";
  StatusEvent e;
  e.state = RunState::kIntegrate;
  e.sample = 45;
  e.n_samples = 40;
  e.inputs = {"X"};
  e.amplitudes = {1.0};
  sched.events = {e};
  const auto blocks = series_to_blocks(s, sched, 7);
  ASSERT_EQ(blocks.size(), 8u);  // 7 x 7 + 1
  EXPECT_EQ(blocks.back().n_samples, 1);
  EXPECT_TRUE(blocks.back().final_block);
  EXPECT_FALSE(blocks[6].final_block);
  EXPECT_EQ(blocks[3].start_sample, 40 + 21);
  EXPECT_EQ(blocks[3].run_id, "imp");
  const TimeSeries back = blocks_to_series(blocks, "t");
  EXPECT_EQ(back.samples, s.samples);
  EXPECT_EQ(back.start_sample, 40);

  // Refusals: an excited input without a channel, integration beyond the series, another rate,
  // blocks with a gap.
  Schedule bad = sched;
  bad.events[0].inputs = {"Z"};
  EXPECT_THAT([&] { series_to_blocks(s, bad, 7); },
              ThrowsMessage<InputError>(
                  HasSubstr("excites Z but the series has neither a channel u_Z nor Z")));
  bad = sched;
  bad.events[0].n_samples = 80;
  EXPECT_THAT([&] { series_to_blocks(s, bad, 7); },
              ThrowsMessage<InputError>(
                  HasSubstr("integrates samples 45 .. 125, the series holds 40 .. 90")));
  bad = sched;
  bad.sample_rate_hz = 100;
  EXPECT_THAT([&] { series_to_blocks(s, bad, 7); },
              ThrowsMessage<InputError>(HasSubstr("sampled at 200 Hz, the schedule at 100 Hz")));
  auto gappy = blocks;
  gappy.erase(gappy.begin() + 2);
  EXPECT_THAT([&] { blocks_to_series(gappy, "t"); },
              ThrowsMessage<InputError>(HasSubstr(
                  "block seq 3: starts at sample 61, the previous block ended before 54")));
}

namespace {

// fs 100 Hz from sample 10: 300 samples at 1 Hz exciting u_A (amplitude 2), then 250 at 2 Hz
// exciting u_B (amplitude 0.5), then 20 idle; phase continuous, the reference recorded.
TimeSeries reference_series(double f2 = 2.0) {
  TimeSeries s;
  s.channels = {"u_A", "u_B", "ref_phase", "ref_freq_hz"};
  s.sample_rate_hz = 100;
  s.start_sample = 10;
  s.n_samples = 570;
  s.samples.assign(4 * 570, 0.0);
  double phi = 0.3;
  for (int64_t k = 0; k < 570; ++k) {
    const double f = k < 300 ? 1.0 : k < 550 ? f2 : 0.0;
    const size_t n = size_t(s.n_samples);
    s.samples[0 * n + size_t(k)] = 5 + (k < 300 ? 2 * std::sin(phi) : 0.0);
    s.samples[1 * n + size_t(k)] = -1 + (k >= 300 && k < 550 ? 0.5 * std::sin(phi) : 0.0);
    s.samples[2 * n + size_t(k)] = phi;
    s.samples[3 * n + size_t(k)] = f;
    phi += 2 * M_PI * f / 100;
  }
  return s;
}

}  // namespace

TEST(ReferenceSchedule, StepsWindowsInputsAndAmplitudesComeFromTheRecordedReference) {
  ReferenceScheduleOptions o;
  o.min_cycles = 2;
  o.min_integrate_s = 0;
  const TimeSeries s = reference_series();
  const Schedule sch = schedule_from_reference(s, o);
  ASSERT_EQ(sch.events.size(), 6u);  // start, 2 x (settle, integrate), done
  const StatusEvent& i0 = sch.events[2];
  EXPECT_EQ(sch.events[1].state, RunState::kSettle);
  EXPECT_EQ(sch.events[1].sample, 10);
  EXPECT_EQ(sch.events[1].n_samples, 100);
  EXPECT_EQ(i0.state, RunState::kIntegrate);
  EXPECT_EQ(i0.sample, 110);  // the last 2 cycles (200 samples) of the 1 Hz run
  EXPECT_EQ(i0.n_samples, 200);
  EXPECT_EQ(i0.n_cycles, 2);
  EXPECT_EQ(i0.inputs, (std::vector<std::string>{"A", "B"}));
  EXPECT_NEAR(i0.amplitudes[0], 2.0, 1e-12);
  EXPECT_EQ(i0.amplitudes[1], 0.0);
  EXPECT_NEAR(i0.ref_phase_rad, std::fmod(s.at(2, 100), 2 * M_PI), 1e-15);
  const StatusEvent& i1 = sch.events[4];
  EXPECT_EQ(i1.sample, 10 + 300 + 150);  // 2 cycles at 2 Hz: 100 samples, the run's last
  EXPECT_EQ(i1.n_samples, 100);
  EXPECT_EQ(i1.step, 1);
  EXPECT_EQ(i1.amplitudes[0], 0.0);
  EXPECT_NEAR(i1.amplitudes[1], 0.5, 1e-12);
  EXPECT_EQ(sch.events.back().state, RunState::kDone);
  EXPECT_EQ(sch.events.back().sample, 560);
  EXPECT_EQ(sch.events.front().seq, -1);
  for (size_t k = 1; k < sch.events.size(); ++k) EXPECT_EQ(sch.events[k].seq, int64_t(k - 1));

  // Refused: cycles that are not a whole number of samples; a run too short; no reference.
  EXPECT_THAT([&] { schedule_from_reference(reference_series(3.0), o); },
              ThrowsMessage<InputError>(HasSubstr("step 1 (3 Hz, t = 3.1 s): 2 cycles are")));
  o.min_cycles = 4;
  EXPECT_THAT(
      [&] { schedule_from_reference(s, o); },
      ThrowsMessage<InputError>(HasSubstr("300 samples at this frequency, 4 cycles need 400")));
  TimeSeries no_ref = s;
  no_ref.channels[3] = "other";
  EXPECT_THAT([&] { schedule_from_reference(no_ref, o); },
              ThrowsMessage<InputError>(HasSubstr("no reference channel ref_freq_hz")));
}
