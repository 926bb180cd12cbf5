#include "tape_analysis.h"

#include <algorithm>

namespace fralab {

TapeFeeder::TapeFeeder(const std::vector<std::string>& pairs, const AnalyzerOptions& opt,
                       std::string run_id)
    : run_id_(std::move(run_id)) {
  if (pairs.empty()) throw InputError("no --pair given: name at least one pair E1:E2");
  for (const auto& p : pairs) an_.push_back(std::make_unique<PairAnalyzer>(p, opt));
}

int64_t TapeFeeder::feed(const std::string& channel, const void* data, int size) {
  lcm::ReceiveBuffer rb{const_cast<void*>(data), static_cast<uint32_t>(size), 0};
  if (channel == kTapeChannel) {
    Block b = from_msg(decode_checked<tape_block_t>(&rb, channel));
    if (run_id_.empty()) run_id_ = b.run_id;
    if (b.run_id != run_id_) return -1;
    for (auto& a : an_) a->on_block(b);
    final_seen_ |= b.final_block;
    return b.seq;
  }
  if (channel == kStatusChannel) {
    StatusEvent e = from_msg(decode_checked<excitation_status_t>(&rb, channel));
    if (run_id_.empty()) run_id_ = e.run_id;
    if (e.run_id != run_id_) return -1;
    for (auto& a : an_) a->on_status(e);
  }
  return -1;
}

bool TapeFeeder::all_done() const {
  if (!final_seen_) return false;
  for (const auto& a : an_) {
    if (!a->done()) return false;
  }
  return true;
}

void TapeFeeder::flush() {
  for (auto& a : an_) a->flush();
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
