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

}  // namespace fralab
