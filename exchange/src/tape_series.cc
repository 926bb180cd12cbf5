#include "fralab/exchange/tape_series.h"

#include <cmath>

#include "fralab/core/error.h"
#include "fralab/core/pair_id.h"
#include "fralab/core/text.h"

namespace fralab {

TimeSeries blocks_to_series(const std::vector<Block>& blocks, const std::string& source) {
  if (blocks.empty()) throw InputError(source + ": no tape blocks");
  TimeSeries s;
  s.source = source;
  s.channels = blocks[0].channels;
  s.units.assign(s.channels.size(), "");
  s.sample_rate_hz = blocks[0].sample_rate_hz;
  s.start_sample = blocks[0].start_sample;
  int64_t next = s.start_sample;
  for (const Block& b : blocks) {
    const std::string where = source + ": block seq " + std::to_string(b.seq);
    if (b.channels != s.channels) throw InputError(where + ": its channels differ from block 0's");
    if (b.sample_rate_hz != s.sample_rate_hz)
      throw InputError(where + ": sample rate " + lossless(b.sample_rate_hz) + " Hz, block 0's " +
                       lossless(s.sample_rate_hz) + " Hz");
    if (b.start_sample != next)
      throw InputError(where + ": starts at sample " + std::to_string(b.start_sample) +
                       ", the previous block ended before " + std::to_string(next));
    next += b.n_samples;
  }
  s.n_samples = next - s.start_sample;
  s.samples.resize(s.channels.size() * size_t(s.n_samples));
  int64_t k0 = 0;
  for (const Block& b : blocks) {
    for (size_t c = 0; c < s.channels.size(); ++c)
      for (int k = 0; k < b.n_samples; ++k)
        s.samples[c * size_t(s.n_samples) + size_t(k0 + k)] = b.at(int(c), k);
    k0 += b.n_samples;
  }
  return s;
}

std::vector<Block> series_to_blocks(const TimeSeries& s, const Schedule& schedule,
                                    int block_samples) {
  if (block_samples < 1 || block_samples > 1000000)
    throw InputError("block size " + std::to_string(block_samples) + ": 1 .. 1000000 samples");
  if (std::abs(schedule.sample_rate_hz - s.sample_rate_hz) > 1e-9 * s.sample_rate_hz)
    throw InputError(s.source + ": sampled at " + lossless(s.sample_rate_hz) +
                     " Hz, the schedule at " + lossless(schedule.sample_rate_hz) + " Hz");
  const int64_t end = s.start_sample + s.n_samples;
  for (size_t i = 0; i < schedule.events.size(); ++i) {
    const StatusEvent& e = schedule.events[i];
    const std::string where = "schedule event " + std::to_string(i) + " (seq " +
                              std::to_string(e.seq) + ", " + to_string(e.state) + ")";
    for (size_t k = 0; k < e.inputs.size(); ++k) {
      if (e.amplitudes[k] <= 0) continue;
      if (s.channel_index(command_channel(e.inputs[k])) < 0 && s.channel_index(e.inputs[k]) < 0)
        throw InputError(s.source + ": " + where + " excites " + e.inputs[k] +
                         " but the series has neither a channel u_" + e.inputs[k] + " nor " +
                         e.inputs[k]);
    }
    if (e.state == RunState::kIntegrate &&
        (e.sample < s.start_sample || e.sample + e.n_samples > end))
      throw InputError(s.source + ": " + where + " integrates samples " + std::to_string(e.sample) +
                       " .. " + std::to_string(e.sample + e.n_samples) + ", the series holds " +
                       std::to_string(s.start_sample) + " .. " + std::to_string(end));
  }
  std::vector<Block> out;
  for (int64_t k0 = 0; k0 < s.n_samples; k0 += block_samples) {
    Block b;
    b.run_id = schedule.run_id;
    b.seq = int64_t(out.size());
    b.start_sample = s.start_sample + k0;
    b.sample_rate_hz = s.sample_rate_hz;
    b.channels = s.channels;
    b.n_samples = int(std::min<int64_t>(block_samples, s.n_samples - k0));
    b.samples.resize(b.channels.size() * size_t(b.n_samples));
    for (size_t c = 0; c < b.channels.size(); ++c)
      for (int k = 0; k < b.n_samples; ++k) b.at(int(c), k) = s.at(c, k0 + k);
    b.final_block = k0 + block_samples >= s.n_samples;
    out.push_back(std::move(b));
  }
  return out;
}

}  // namespace fralab
