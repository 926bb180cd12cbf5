// Resuming an interrupted or failed `fralab measure` run (`--resume DIR`): where to start again.
//
// The tape holds the run's tape blocks 0..C without a gap (later ones may be missing: the run
// stopped). The first integrate window not wholly inside those blocks belongs to the first
// incomplete step; the run starts again at that step's first status event (its settle), at the
// command block B = min(floor(sample / block), C + 1) that holds it, so every block before B is on
// the tape: the plant replays them (LockstepPlant::replay) to stand exactly where the run stood,
// the acquisition sends blocks B.. and the status events from the first at or after sample
// B * block, and the recorder appends them to the same tape. Blocks B..C come again bit for bit
// (the emulator is deterministic), so the tape reads as one uninterrupted run.
#pragma once

#include <cstdint>
#include <string>

#include "fralab/acquire/acquisition.h"
#include "fralab/acquire/campaign.h"

namespace fralab {

struct ResumePoint {
  int64_t blocks_on_tape = 0;  // C + 1: tape blocks 0..C present without a gap
  int64_t first_block = 0;     // B
  int64_t first_status = 0;    // index of the first status event sent again
  int first_step = 0;          // the first incomplete step
  bool complete = false;       // every block and the done status are on the tape
};

/// Cuts a tape at its last whole event (a recorder killed mid-write leaves a partial one); returns
/// the bytes removed. InputError naming the file when it is not an LCM log.
int64_t cut_tape_to_whole_events(const std::string& path);

/// The resume point of run `run_id` on `tape`, for the campaign it ran (`block` samples per
/// command block). InputError naming the tape when it holds nothing of that run.
ResumePoint plan_resume(const std::string& tape, const std::string& run_id, const Campaign& c,
                        int block);

/// The same for an adaptive stepped sine (acquire/adaptive_sine.h), whose campaign grew with the
/// decisions taken while it ran: they are read back from the tape's integrate statuses (a step's
/// windows after its first), the resume point planned on the campaign they make, and moved back
/// to the first step not closed on the tape (no later step's settle there: its last decision may
/// not have been taken). `o.adaptive_decided` is set to the decisions before that step (the
/// resumed acquisition takes the others again, on the same samples: the same decisions).
ResumePoint plan_adaptive_resume(const std::string& tape, const std::string& run_id, const Model& m,
                                 AcquireOptions& o);

}  // namespace fralab
