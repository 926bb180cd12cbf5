#include "tape_check.h"

#include <algorithm>
#include <chrono>
#include <thread>

namespace fralab {

int64_t TapeCheck::update(std::string* problem) {
  try {
    follow_tape_file(path_, &offset_, [&](const TapeEvent& ev) { take(ev); });
  } catch (const InputError& e) {
    *problem = e.what();
    return -1;  // cannot open it (yet): try again
  }
  if (!bad_.empty()) {  // a whole event that does not decode: no retry mends that
    *problem = bad_;
    return -2;
  }
  if (!final_tape_ || !done_) {
    *problem = "the tape does not yet hold the final block and the done status (read to byte " +
               std::to_string(offset_) + ")";
    return -1;
  }
  for (auto& [kind, v] : seqs_) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());  // retransmitted copies
    for (size_t i = 0; i < v.size(); ++i) {
      if (v[i] != int64_t(i)) {
        *problem = "the tape lost " + kind + (kind == "status" ? " event" : " block") + " seq " +
                   std::to_string(i);
        return -2;
      }
    }
  }
  return int64_t(seqs_["tape"].size());
}

void TapeCheck::take(const TapeEvent& ev) {
  if (!bad_.empty()) return;
  try {
    decode(ev);
  } catch (const InputError& e) {
    bad_ = "event " + std::to_string(ev.eventnum) + ": " + e.what();
  }
}

void TapeCheck::decode(const TapeEvent& ev) {
  lcm::ReceiveBuffer rb{const_cast<void*>(ev.data), uint32_t(ev.datalen), 0};
  if (ev.channel == kTapeChannel) {
    Block m;
    try {
      m = decode_tape_block(&rb, ev.channel);
    } catch (const CorruptBlock&) {  // a later copy (retransmitted) may be whole
      return;
    }
    if (m.run_id == run_id_ && m.seq >= 0) {  // seq -1: an aborted run's last block
      seqs_["tape"].push_back(m.seq);
      final_tape_ |= m.final_block;
    }
  } else if (ev.channel == kStatusChannel) {
    const StatusEvent m = decode_status_event(&rb, ev.channel);
    if (m.run_id != run_id_) return;
    if (m.seq >= 0) seqs_["status"].push_back(m.seq);
    done_ |= m.state == RunState::kDone;
  }
}

int64_t read_back_tape(const std::string& tape, const std::string& run_id, std::string* problem) {
  int64_t n = -1;
  TapeCheck check(tape, run_id);
  for (int i = 0; i < 200 && n < 0; ++i) {
    n = check.update(problem);
    if (n == -1) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (n == -2) break;
  }
  return n;
}

}  // namespace fralab
