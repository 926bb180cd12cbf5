#include "fralab/core/block.h"

#include "fralab/core/text.h"

namespace fralab {
namespace {

constexpr std::pair<Excitation, const char*> kExcitationWords[] = {
    {Excitation::kStepped, "stepped_sine"},
    {Excitation::kSweep, "sweep"},
    {Excitation::kMultisine, "multisine"}};
constexpr std::pair<RunState, const char*> kStateWords[] = {{RunState::kStart, "start"},
                                                            {RunState::kSettle, "settle"},
                                                            {RunState::kIntegrate, "integrate"},
                                                            {RunState::kDone, "done"},
                                                            {RunState::kAbort, "abort"}};

}  // namespace

const char* status_word(Excitation e) { return enum_word(kExcitationWords, e); }

const char* to_string(RunState s) { return enum_word(kStateWords, s); }

Excitation excitation_from_status_word(const std::string& word) {
  if (const auto e = enum_from_word(kExcitationWords, word)) return *e;
  throw InputError("excitation \"" + word + "\": stepped_sine, sweep or multisine");
}

RunState run_state_from_string(const std::string& word) {
  if (const auto s = enum_from_word(kStateWords, word)) return *s;
  throw InputError("state \"" + word + "\": start, settle, integrate, done or abort");
}

int64_t HeldSamples::add(const Block& b) {
  const int c = b.channel_index(kUnderrunChannel);
  int64_t n = 0;
  for (int k = 0; c >= 0 && k < b.n_samples; ++k)
    if (b.at(c, k) != 0.0) {
      add_sample(b.start_sample + k);
      ++n;
    }
  return n;
}

void HeldSamples::add_sample(int64_t n) {
  auto next = runs_.upper_bound(n);  // the first run starting after n
  if (next != runs_.begin()) {
    auto prev = std::prev(next);
    if (prev->second >= n) return;  // held already (a block delivered twice)
    if (prev->second + 1 == n) {    // extends the run before it
      prev->second = n;
      if (next != runs_.end() && next->first == n + 1) {  // and joins the one after
        prev->second = next->second;
        runs_.erase(next);
      }
      ++count_;
      return;
    }
  }
  if (next != runs_.end() && next->first == n + 1) {  // extends the run after it backwards
    const int64_t last = next->second;
    runs_.erase(next);
    runs_[n] = last;
  } else {
    runs_[n] = n;
  }
  ++count_;
}

std::optional<std::pair<int64_t, int64_t>> HeldSamples::within(int64_t a, int64_t b) const {
  std::optional<std::pair<int64_t, int64_t>> out;
  auto it = runs_.upper_bound(a);
  if (it != runs_.begin()) --it;  // a run starting before a may reach into it
  for (; it != runs_.end() && it->first < b; ++it) {
    if (it->second < a) continue;
    const int64_t f = std::max(it->first, a), l = std::min(it->second, b - 1);
    if (!out) out = std::make_pair(f, l);
    out->second = l;
  }
  return out;
}

}  // namespace fralab
