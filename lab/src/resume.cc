#include "fralab/lab/resume.h"

#include <filesystem>
#include <map>
#include <set>

#include "fralab/acquire/acquisition.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/tape_file.h"

namespace fralab {

int64_t cut_tape_to_whole_events(const std::string& path) {
  int64_t offset = 0;
  follow_tape_file(path, &offset, [](const TapeEvent&) {});
  const auto size = int64_t(std::filesystem::file_size(path));
  if (offset < size) std::filesystem::resize_file(path, uintmax_t(offset));
  return size - offset;
}

namespace {

// The run's status events on the tape (seq >= 0, each once, in seq order).
std::vector<StatusEvent> tape_status(const std::string& tape, const std::string& run_id) {
  std::map<int64_t, StatusEvent> by_seq;
  read_tape_file(tape, [&](const TapeEvent& ev) {
    if (ev.channel != kStatusChannel) return;
    lcm::ReceiveBuffer rb{const_cast<void*>(ev.data), uint32_t(ev.datalen), 0};
    try {
      const StatusEvent m = decode_status_event(&rb, ev.channel);
      if (m.run_id == run_id && m.seq >= 0) by_seq.emplace(m.seq, m);
    } catch (const InputError& e) {
      throw InputError(tape + ": event " + std::to_string(ev.eventnum) + ": " + e.what());
    }
  });
  std::vector<StatusEvent> v;
  for (auto& [seq, e] : by_seq) v.push_back(std::move(e));
  return v;
}

}  // namespace

ResumePoint plan_adaptive_resume(const std::string& tape, const std::string& run_id, const Model& m,
                                 AcquireOptions& o) {
  const std::vector<StatusEvent> st = tape_status(tape, run_id);
  std::vector<std::pair<int, int>> decided;
  std::set<int> seen_window;
  int open = 0;  // the first step not closed on the tape
  for (const StatusEvent& e : st) {
    if (e.state == RunState::kIntegrate && !seen_window.insert(e.step).second)
      decided.emplace_back(e.step, e.n_cycles);  // a window after the step's first
    if (e.state == RunState::kSettle) open = std::max(open, e.step);
    if (e.state == RunState::kDone) open = std::max(open, e.step);
  }
  o.adaptive_decided = format_decisions(decided);
  ResumePoint r = plan_resume(tape, run_id, *make_campaign(m, o, run_id), o.block);
  if (r.complete) return r;
  const int first = std::min(r.first_step, open);
  std::vector<std::pair<int, int>> before;
  for (const auto& d : decided)
    if (d.first < first) before.push_back(d);
  o.adaptive_decided = format_decisions(before);
  const auto c = make_campaign(m, o, run_id);
  const auto& ac = dynamic_cast<const AdaptiveSineCampaign&>(*c);
  if (first < ac.n_steps()) {
    r.first_step = first;
    r.first_block = std::min(ac.step_start(first) / o.block, r.blocks_on_tape);
    r.first_status = 0;
    while (r.first_status < int64_t(c->events().size()) &&
           c->events()[size_t(r.first_status)].sample < r.first_block * o.block)
      ++r.first_status;
  }
  return r;
}

ResumePoint plan_resume(const std::string& tape, const std::string& run_id, const Campaign& c,
                        int block) {
  require_sized_block(block, "resume");
  std::set<int64_t> seqs, status_seqs;
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
        const StatusEvent m = decode_status_event(&rb, ev.channel);
        done |= m.run_id == run_id && m.state == RunState::kDone;
        if (m.run_id == run_id && m.seq >= 0) status_seqs.insert(m.seq);
      }
    } catch (const InputError& e) {
      throw InputError(tape + ": event " + std::to_string(ev.eventnum) + ": " + e.what());
    }
  });
  ResumePoint r;
  while (seqs.count(r.blocks_on_tape)) ++r.blocks_on_tape;
  const int64_t nblocks = command_block_count(c, block);
  const auto& ev = c.events();
  int64_t end = std::min(c.total_samples(), r.blocks_on_tape * block);
  // A status event lost (a damaged stretch of tape) while the blocks around it are there: the run
  // stands no further than that event, so its step is measured again and the event sent again.
  int64_t first_missing_status = 0;
  while (status_seqs.count(first_missing_status)) ++first_missing_status;
  if (first_missing_status < int64_t(ev.size()) &&
      first_missing_status < int64_t(status_seqs.size()))
    end = std::min(end, ev[size_t(first_missing_status)].sample);
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
