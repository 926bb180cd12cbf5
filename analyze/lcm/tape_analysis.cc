#include "tape_analysis.h"

#include <algorithm>
#include <limits>

namespace fralab {

TapeFeeder::TapeFeeder(const std::vector<std::string>& pairs, const AnalyzerOptions& opt,
                       std::string run_id)
    : run_id_(std::move(run_id)) {
  if (pairs.empty()) throw InputError("no --pair given: name at least one pair E1:E2");
  // One store for all: each block reaches every analyser (deliver()), its channels kept once.
  const auto store = std::make_shared<SampleStore>();
  for (const auto& p : pairs) an_.push_back(std::make_unique<PairAnalyzer>(p, opt, store));
}

TapeFeeder::Fed TapeFeeder::feed(const std::string& channel, const void* data, int size) {
  lcm::ReceiveBuffer rb{const_cast<void*>(data), static_cast<uint32_t>(size), 0};
  Fed fed;
  if (channel == kTapeChannel) {
    Block b;
    try {
      b = decode_tape_block(&rb, channel);
    } catch (const CorruptBlock& c) {  // refused: as if lost (a live run gets it again)
      corrupt_.insert(c.seq);
      for (auto& a : an_) a->note_corrupt(c.seq);
      fed.kind = Kind::kTape;
      return fed;
    }
    if (run_id_.empty()) run_id_ = b.run_id;
    if (b.run_id != run_id_) return fed;
    fed.kind = Kind::kTape;
    const int64_t seq = b.seq;
    const auto offered = tape_.offer(seq, std::move(b));
    if (offered == InOrder<Block>::Offer::kRefused) {  // a seq no stream reaches: corrupt
      corrupt_.insert(seq);
      for (auto& a : an_) a->note_corrupt(seq);
      return fed;
    }
    fed.duplicate = offered == InOrder<Block>::Offer::kDuplicate;
  } else if (channel == kStatusChannel) {
    StatusEvent e = decode_status_event(&rb, channel);
    if (run_id_.empty()) run_id_ = e.run_id;
    if (e.run_id != run_id_) return fed;
    fed.kind = Kind::kStatus;
    if (e.seq < 0) {  // outside the sequence: the start (informative) or an abort (a resumed
      // run goes on after it): neither defines a window
      return fed;
    }
    const int64_t seq = e.seq;
    fed.duplicate = status_.offer(seq, std::move(e)) == InOrder<StatusEvent>::Offer::kDuplicate;
  }
  deliver();
  return fed;
}

void TapeFeeder::deliver() {
  // Status events first: the acquisition publishes a block's events before the block.
  while (auto e = status_.pop())
    for (auto& a : an_) a->on_status(*e);
  while (auto b = tape_.pop()) {
    for (auto& a : an_) a->on_block(*b);
    final_seen_ |= b->final_block;
  }
}

bool TapeFeeder::all_done() const {
  if (!final_seen_) return false;
  for (const auto& a : an_) {
    if (!a->done()) return false;
  }
  return true;
}

int64_t TapeFeeder::flush() {
  int64_t lost = 0;
  // Saturating sums: a corrupt status event (no checksum) may carry a seq near the largest
  // int64_t, and the gap before it with it.
  const auto add = [](int64_t a, int64_t b) {
    return b > std::numeric_limits<int64_t>::max() - a ? std::numeric_limits<int64_t>::max()
                                                       : a + b;
  };
  while (status_.held() || tape_.held()) {
    lost = add(lost, add(status_.skip_gap(), tape_.skip_gap()));
    deliver();
  }
  for (auto& a : an_) a->flush();
  return lost;
}

std::vector<Frd> analyze_tape_file(const std::string& path, const std::vector<std::string>& pairs,
                                   const AnalyzerOptions& opt) {
  TapeFeeder feeder(pairs, opt);
  read_tape_file(path, [&](const TapeEvent& ev) {
    try {
      feeder.feed(ev.channel, ev.data, ev.datalen);
    } catch (const InputError& e) {
      throw InputError(path + ": event " + std::to_string(ev.eventnum) + ": " + e.what());
    }
  });
  feeder.flush();
  std::vector<Frd> out;
  for (auto& a : feeder.analyzers()) out.push_back(a->frd());
  return out;
}

}  // namespace fralab
