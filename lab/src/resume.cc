#include "fralab/lab/resume.h"

#include <filesystem>
#include <set>

#include "fralab/acquire/acquisition.h"
#include "fralab/lcm_io.h"

namespace fralab {

int64_t cut_tape_to_whole_events(const std::string& path) {
  int64_t offset = 0;
  follow_tape_file(path, &offset, [](const TapeEvent&) {});
  const auto size = int64_t(std::filesystem::file_size(path));
  if (offset < size) std::filesystem::resize_file(path, uintmax_t(offset));
  return size - offset;
}

ResumePoint plan_resume(const std::string& tape, const std::string& run_id, const Campaign& c,
                        int block) {
  std::set<int64_t> seqs;
  bool done = false;
  read_tape_file(tape, [&](const TapeEvent& ev) {
    lcm::ReceiveBuffer rb{const_cast<void*>(ev.data), uint32_t(ev.datalen), 0};
    try {
      if (ev.channel == kTapeChannel) {
        try {
          const Block b = decode_tape_block(&rb, ev.channel);
          if (b.run_id == run_id) seqs.insert(b.seq);
        } catch (const CorruptBlock&) {  // not on the tape: measured again
        }
      } else if (ev.channel == kStatusChannel) {
        const excitation_status_t m = decode_checked<excitation_status_t>(&rb, ev.channel);
        done |= m.run_id == run_id && from_msg(m).state == RunState::kDone;
      }
    } catch (const InputError& e) {
      throw InputError(tape + ": event " + std::to_string(ev.eventnum) + ": " + e.what());
    }
  });
  ResumePoint r;
  while (seqs.count(r.blocks_on_tape)) ++r.blocks_on_tape;
  const int64_t nblocks = command_block_count(c, block);
  const int64_t end = std::min(c.total_samples(), r.blocks_on_tape * block);
  const auto& ev = c.events();
  size_t e = 0;
  while (e < ev.size() &&
         !(ev[e].state == RunState::kIntegrate && ev[e].sample + ev[e].n_samples > end))
    ++e;
  if (e == ev.size()) {  // every window is on the tape
    r.complete = r.blocks_on_tape >= nblocks && done;
    // Not complete with every block there: the final block (with the done status) goes again.
    r.first_block = std::min(r.blocks_on_tape, r.complete ? nblocks : nblocks - 1);
    r.first_step = ev.empty() ? 0 : ev.back().step;
  } else {
    size_t s = e;
    while (s > 0 && ev[s - 1].step == ev[e].step) --s;
    r.first_step = ev[e].step;
    r.first_block = std::min(ev[s].sample / block, r.blocks_on_tape);
  }
  while (r.first_status < int64_t(ev.size()) &&
         ev[size_t(r.first_status)].sample < r.first_block * block)
    ++r.first_status;
  if (r.complete) r.first_status = int64_t(ev.size());
  return r;
}

}  // namespace fralab
