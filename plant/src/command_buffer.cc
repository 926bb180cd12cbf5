#include "fralab/plant/command_buffer.h"

#include <algorithm>

#include "fralab/core/error.h"
#include "fralab/core/text.h"

namespace fralab {

CommandBuffer::CommandBuffer(int tick_samples) : tick_(tick_samples) {
  if (tick_ < 1) throw InputError("free-running plant: a tick of at least one sample is needed");
}

bool CommandBuffer::add(const Block& cmd) {
  if (!started_) {
    channels_ = cmd.channels;
    last_.assign(channels_.size(), 0.0);
    for (size_t c = 0; c < channels_.size() && cmd.n_samples > 0; ++c)
      last_[c] = cmd.at(int(c), 0);  // before anything played: the first command's values
    clock_ = cmd.start_sample;
    run_id_ = cmd.run_id;
    fs_ = cmd.sample_rate_hz;
    started_ = true;
  } else if (cmd.channels != channels_) {
    throw InputError("command block seq " + std::to_string(cmd.seq) +
                     ": its channels differ from the first block's");
  }
  if (cmd.final_block) final_end_ = cmd.start_sample + cmd.n_samples;
  if (ticks_ == 0) clock_ = std::min(clock_, cmd.start_sample);  // nothing played yet
  if (cmd.start_sample + cmd.n_samples <= clock_) {
    ++late_;
    return false;
  }
  blocks_[cmd.start_sample] = cmd;
  return true;
}

std::optional<Block> CommandBuffer::next() {
  if (!started_ || done_) return std::nullopt;
  int n = tick_;
  if (final_end_ >= 0 && clock_ < final_end_) n = int(std::min<int64_t>(n, final_end_ - clock_));
  Block out;
  out.run_id = run_id_;
  out.sample_rate_hz = fs_;
  out.seq = ticks_++;
  out.start_sample = clock_;
  out.n_samples = n;
  out.channels = channels_;
  out.channels.push_back(kUnderrunChannel);
  out.samples.assign(out.channels.size() * size_t(n), 0.0);
  const int ref_freq = index_of(channels_, "ref_freq_hz");
  const int nc = int(channels_.size());
  for (int k = 0; k < n; ++k) {
    const int64_t s = clock_ + k;
    // The buffered block holding sample s: the last one starting at or before it.
    auto it = blocks_.upper_bound(s);
    const Block* b = nullptr;
    if (it != blocks_.begin()) {
      --it;
      if (s < it->first + it->second.n_samples) b = &it->second;
    }
    if (b) {
      for (int c = 0; c < nc; ++c)
        last_[size_t(c)] = out.at(c, k) = b->at(c, int(s - b->start_sample));
    } else {
      for (int c = 0; c < nc; ++c) out.at(c, k) = last_[size_t(c)];
      if (ref_freq >= 0) out.at(ref_freq, k) = 0.0;
      out.at(nc, k) = 1.0;
      ++underrun_;
    }
  }
  clock_ += n;
  // Blocks wholly played are gone.
  while (!blocks_.empty() && blocks_.begin()->first + blocks_.begin()->second.n_samples <= clock_)
    blocks_.erase(blocks_.begin());
  if (final_end_ >= 0 && clock_ >= final_end_) {
    out.final_block = true;
    done_ = true;
  }
  return out;
}

}  // namespace fralab
