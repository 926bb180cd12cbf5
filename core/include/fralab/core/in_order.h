// In-order delivery of a sequence-numbered stream that may arrive with gaps, duplicates and
// reordering (a lost datagram retransmitted later). Items are offered with their sequence number;
// they come out strictly in sequence order, each exactly once. Used by every consumer of a
// flow-controlled stream (the plant's commands, the analysers' and recorder's tape blocks and
// status events), so what they compute never depends on the order datagrams arrived in.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <utility>

namespace fralab {

template <class T>
class InOrder {
 public:
  /// `first`: the sequence number of the stream's first item. `max_held`: items held back waiting
  /// for a gap to be filled; beyond that the gap is given up (skip_gap) so memory stays bounded.
  explicit InOrder(int64_t first = 0, size_t max_held = 4096) : next_(first), max_held_(max_held) {}

  enum class Offer { kNew, kDuplicate, kRefused };
  /// Takes item `seq`. A seq already delivered or already held is a duplicate (the first copy
  /// counts) and is dropped. The largest int64_t has no successor to advance to: such a seq (only
  /// a corrupt message carries it) is refused and dropped, the stream unchanged.
  Offer offer(int64_t seq, T item) {
    if (seq == std::numeric_limits<int64_t>::max()) return Offer::kRefused;
    if (seq < next_ || held_.count(seq)) return Offer::kDuplicate;
    held_.emplace(seq, std::move(item));
    if (held_.size() > max_held_) skip_gap();
    return Offer::kNew;
  }
  /// The next item in sequence, when it has arrived.
  std::optional<T> pop() {
    auto it = held_.find(next_);
    if (it == held_.end()) return std::nullopt;
    T v = std::move(it->second);
    held_.erase(it);
    ++next_;
    return v;
  }
  /// Gives up waiting for the missing items before the lowest held one (end of a file, or too
  /// much held): the next pop() returns it. Returns the number of items skipped.
  int64_t skip_gap() {
    if (held_.empty()) return 0;
    const int64_t skipped = held_.begin()->first - next_;
    // Saturating: a corrupt status event (no checksum) may carry a seq near the largest int64_t.
    skipped_ = skipped > std::numeric_limits<int64_t>::max() - skipped_
                   ? std::numeric_limits<int64_t>::max()
                   : skipped_ + skipped;
    next_ = held_.begin()->first;
    return skipped;
  }
  /// The last sequence number delivered (first - 1 before any): what a consumer acknowledges.
  int64_t delivered() const { return next_ - 1; }
  int64_t next() const { return next_; }
  size_t held() const { return held_.size(); }
  int64_t skipped() const { return skipped_; }

 private:
  int64_t next_;
  size_t max_held_;
  int64_t skipped_ = 0;
  std::map<int64_t, T> held_;
};

}  // namespace fralab
