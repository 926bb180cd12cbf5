#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "fralab/core/error.h"
#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"
#include "fralab/exchange/schedule.h"
#include "fralab/exchange/time_series.h"

namespace fralab {

void ReferenceScheduleOptions::validate() const {
  if (min_cycles < 1) throw InputError("--min-cycles must be >= 1");
  if (!(min_integrate_s >= 0)) throw InputError("--min-integrate-s must be >= 0");
}

namespace {

// The runs of one frequency > 0 on channel cf, [a, b) as row indices.
std::vector<std::pair<int64_t, int64_t>> frequency_runs(const TimeSeries& s, int cf) {
  std::vector<std::pair<int64_t, int64_t>> runs;
  for (int64_t k = 0; k < s.n_samples;) {
    const double f = s.at(size_t(cf), k);
    if (!(f > 0)) {
      ++k;
      continue;
    }
    int64_t e = k + 1;
    while (e < s.n_samples && std::abs(s.at(size_t(cf), e) - f) <= 1e-9 * f) ++e;
    runs.push_back({k, e});
    k = e;
  }
  return runs;
}

// The whole cycles a step of f Hz integrates (the options' least) and their length in samples,
// which must be a whole number within the run's b - a samples; refused naming `where`.
std::pair<int, int64_t> integration_window(double f, double fs, int64_t run_samples,
                                           const ReferenceScheduleOptions& o,
                                           const std::string& where) {
  if (!(f <= fs / 2))
    throw InputError(where + ": above half the " + lossless(fs) + " Hz sample rate");
  const double cycles = std::max(double(o.min_cycles), std::ceil(o.min_integrate_s * f));
  if (!(cycles <= 1e9)) throw InputError(where + ": " + lossless(cycles) + " cycles per point");
  const int n = int(cycles);
  const double exact = n * fs / f;
  const int64_t L = std::llround(exact);
  if (std::abs(exact - double(L)) > 1e-6)
    throw InputError(where + ": " + std::to_string(n) + " cycles are " + lossless(exact) +
                     " samples, not a whole number: not a fralab stepped sine (give --schedule)");
  if (L < 2 || L > run_samples)
    throw InputError(where + ": " + std::to_string(run_samples) + " samples at this frequency, " +
                     std::to_string(n) + " cycles need " + std::to_string(L) +
                     " (--min-cycles, --min-integrate-s as the measurement's?)");
  return {n, L};
}

// The excited input over rows [b - L, b): the command that varies most, relative to its size;
// its index into cmds and its rms, or -1 where none varies.
std::pair<int, double> excited_command(const TimeSeries& s, const std::vector<int>& cmds, int64_t b,
                                       int64_t L) {
  int best = -1;
  double best_rel = 0, best_rms = 0;
  for (size_t i = 0; i < cmds.size(); ++i) {
    double mean = 0, ss = 0;
    for (int64_t k = b - L; k < b; ++k) mean += s.at(size_t(cmds[i]), k);
    mean /= double(L);
    for (int64_t k = b - L; k < b; ++k) ss += std::pow(s.at(size_t(cmds[i]), k) - mean, 2);
    const double rms = std::sqrt(ss / double(L));
    const double rel = rms / std::max(std::abs(mean), 1e-300);
    if (rms > 1e-12 * std::max(std::abs(mean), 1.0) && rel > best_rel) {
      best = int(i);
      best_rel = rel;
      best_rms = rms;
    }
  }
  return {best, best_rms};
}

}  // namespace

Schedule schedule_from_reference(const TimeSeries& s, const ReferenceScheduleOptions& o) {
  o.validate();
  const int cf = s.channel_index(o.freq_channel), cp = s.channel_index(o.phase_channel);
  if (cf < 0 || cp < 0)
    throw InputError(s.source + ": no reference channel " +
                     (cf < 0 ? o.freq_channel : o.phase_channel) +
                     " (the generator's frequency in Hz and phase in radians; or give --schedule)");
  std::vector<int> cmds;
  std::vector<std::string> inputs;
  for (size_t c = 0; c < s.channels.size(); ++c)
    if (const auto x = commanded_input(s.channels[c])) {
      cmds.push_back(int(c));
      inputs.push_back(*x);
    }
  if (cmds.empty()) throw InputError(s.source + ": no command channel u_<input>");
  const double fs = s.sample_rate_hz;
  Schedule out;
  out.sample_rate_hz = fs;
  out.run_id = o.run_id;
  const std::vector<std::pair<int64_t, int64_t>> runs = frequency_runs(s, cf);
  if (runs.empty())
    throw InputError(s.source + ": " + o.freq_channel + " is never above 0: no step");
  int64_t seq = 0;
  for (size_t r = 0; r < runs.size(); ++r) {
    const auto [a, b] = runs[r];
    const double f = s.at(size_t(cf), a);
    const std::string where = s.source + ": step " + std::to_string(r) + " (" + lossless(f) +
                              " Hz, t = " + lossless(double(s.start_sample + a) / fs) + " s)";
    const auto [n, L] = integration_window(f, fs, b - a, o, where);
    const auto [best, best_rms] = excited_command(s, cmds, b, L);
    if (best < 0) throw InputError(where + ": no command channel varies: which input is excited?");
    StatusEvent e;
    e.run_id = o.run_id;
    e.sample_rate_hz = fs;
    e.excitation = Excitation::kStepped;
    e.step = int(r);
    e.n_steps = int(runs.size());
    e.frequency_hz = f;
    e.n_cycles = n;
    e.inputs = inputs;
    e.amplitudes.assign(inputs.size(), 0.0);
    e.amplitudes[size_t(best)] = std::sqrt(2.0) * best_rms;
    e.seq = seq++;
    e.state = RunState::kSettle;
    e.sample = s.start_sample + a;
    e.ref_phase_rad = std::fmod(s.at(size_t(cp), a), 2 * std::numbers::pi);
    e.n_samples = (b - a) - L;
    out.events.push_back(e);
    e.seq = seq++;
    e.state = RunState::kIntegrate;
    e.sample = s.start_sample + b - L;
    e.ref_phase_rad = std::fmod(s.at(size_t(cp), b - L), 2 * std::numbers::pi);
    e.n_samples = L;
    out.events.push_back(e);
  }
  StatusEvent start = out.events.front(), done = out.events.back();
  start.seq = -1;
  start.state = RunState::kStart;
  start.sample = s.start_sample;
  start.n_samples = s.n_samples;
  done.seq = seq;
  done.state = RunState::kDone;
  done.sample = done.sample + done.n_samples;
  done.n_samples = 0;
  done.step = done.n_steps;
  done.amplitudes.assign(inputs.size(), 0.0);
  out.events.insert(out.events.begin(), start);
  out.events.push_back(done);
  return out;
}

}  // namespace fralab
