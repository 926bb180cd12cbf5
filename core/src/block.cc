#include "fralab/core/block.h"

#include <utility>

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

const char* status_word(Excitation e) {
  for (const auto& [k, w] : kExcitationWords)
    if (k == e) return w;
  return "?";
}

const char* to_string(RunState s) {
  for (const auto& [k, w] : kStateWords)
    if (k == s) return w;
  return "?";
}

Excitation excitation_from_status_word(const std::string& word) {
  for (const auto& [k, w] : kExcitationWords)
    if (word == w) return k;
  throw InputError("excitation \"" + word + "\": stepped_sine, sweep or multisine");
}

RunState run_state_from_string(const std::string& word) {
  for (const auto& [k, w] : kStateWords)
    if (word == w) return k;
  throw InputError("state \"" + word + "\": start, settle, integrate, done or abort");
}

}  // namespace fralab
