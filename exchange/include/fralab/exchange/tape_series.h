// A run's tape as a time series and its schedule, and back (`fralab export --tape`, `fralab
// import`). Plain structs on both sides (core/block.h); the tape file itself is read and written
// by the LCM bridge (fralab/lcm/tape_file.h: read_tape_run, write_tape_file).
//
// Exact both ways: the series holds every sample of every tape channel on the tape's sample clock,
// the schedule every status event; a tape rebuilt from them analyses to the same frd, bit for bit
// (blocks may be cut at other places: the analyser follows the sample clock, not the blocks).
#pragma once

#include <vector>

#include "fralab/exchange/schedule.h"
#include "fralab/exchange/time_series.h"

namespace fralab {

/// The run's blocks (in seq order, contiguous samples, one channel set) as one series; InputError
/// naming the block for a sample gap or a channel set that changes.
TimeSeries blocks_to_series(const std::vector<Block>& blocks, const std::string& source);

/// The series cut into blocks of `block_samples` (the last one final), run id and sample rate of
/// the schedule. InputError when the schedule excites an input that the series has neither as
/// `u_<input>` nor as `<input>`, or names samples outside the series, or its rate is not the
/// series'.
std::vector<Block> series_to_blocks(const TimeSeries& s, const Schedule& schedule,
                                    int block_samples);

}  // namespace fralab
