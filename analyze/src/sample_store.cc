#include "fralab/analyze/sample_store.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fralab {

void SampleStore::keep(const std::string& channel) {
  ch_.emplace(channel, std::vector<double>(have_.size(), NAN));
}

const std::vector<double>* SampleStore::channel(const std::string& name) const {
  const auto it = ch_.find(name);
  return it == ch_.end() ? nullptr : &it->second;
}

bool SampleStore::add(const Block& b, int64_t slack) {
  if (!seqs_.insert(b.seq).second) return false;
  if (have_.empty() && seqs_.size() == 1)
    base_ =
        b.start_sample > 2 * slack ? b.start_sample - slack : std::min<int64_t>(b.start_sample, 0);
  const int64_t last = b.start_sample + b.n_samples;
  if (last - base_ > int64_t(have_.size())) {
    for (auto& [name, v] : ch_) v.resize(size_t(last - base_), NAN);
    have_.resize(size_t(last - base_), 0);
  }
  const int64_t off = b.start_sample - base_;     // sample k of the block at index off + k
  const int64_t k0 = std::max<int64_t>(0, -off);  // before base: dropped
  for (size_t c = 0; c < b.channels.size(); ++c) {
    const auto it = ch_.find(b.channels[c]);
    if (it == ch_.end()) continue;
    std::vector<double>& v = it->second;
    for (int64_t k = k0; k < b.n_samples; ++k) v[size_t(off + k)] = b.at(int(c), int(k));
  }
  for (int64_t k = k0; k < b.n_samples; ++k) have_[size_t(off + k)] = 1;
  return true;
}

int SampleStore::add_reader() {
  keep_[next_reader_] = std::numeric_limits<int64_t>::min();
  return next_reader_++;
}

void SampleStore::remove_reader(int reader) { keep_.erase(reader); }

void SampleStore::release(int reader, int64_t keep) {
  keep_[reader] = keep;
  int64_t needed = std::numeric_limits<int64_t>::max();
  for (const auto& [r, k] : keep_) needed = std::min(needed, k);
  // (A reader that has not said holds the lowest int64: nothing goes, and no arithmetic on it.)
  const int64_t upto = std::min(needed, end());
  if (upto <= base_ || upto - base_ <= int64_t(1) << 16) return;
  const int64_t drop = upto - base_;
  if (drop < int64_t(have_.size()) - drop) return;
  for (auto& [name, v] : ch_) v.erase(v.begin(), v.begin() + drop);
  have_.erase(have_.begin(), have_.begin() + drop);
  base_ += drop;
}

}  // namespace fralab
