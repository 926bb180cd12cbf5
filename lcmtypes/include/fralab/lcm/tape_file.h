// Tape files (LCM logs lcm-logger writes and lcm-logplayer replays): read with explicit bounds and
// past damaged stretches, followed while still being written, a run's blocks and events collected,
// written as the recorder would have, and summarised (`fralab tape`).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "fralab/core/block.h"
#include "fralab/core/json_util.h"

namespace fralab {

/// One event of a tape file.
struct TapeEvent {
  int64_t eventnum;
  int64_t timestamp;
  std::string channel;
  const void* data;
  int32_t datalen;
};

/// The damaged stretches a tape reader passed over: [first byte, end byte) of each run of bytes
/// that were not LCM log events.
struct TapeDamage {
  std::vector<std::pair<int64_t, int64_t>> skipped;
};

/// Reads every event of an LCM log file in order, calling `fn`, with explicit bounds (a header
/// is checked against the bytes the file holds before anything is read or allocated). Bytes that
/// are not an event (a bad sync word, an impossible length: a damaged stretch) are passed over to
/// the next whole event (a sync word whose header is possible, whose event ends inside the file
/// and whose channel name is printable), as LCM's own log reader resynchronises; what follows is
/// trusted block by block (every tape block carries its CRC32: decode_tape_block). Each stretch
/// passed over, and a tape cut inside its last event (a recorder killed mid-write, read up to the
/// cut), is said in *warning (else on stderr) naming the file and the bytes; `damage` (optional)
/// gets the stretches. InputError naming the file and byte when no event at all can be read.
/// Returns the number of events read.
int64_t read_tape_file(const std::string& path, const std::function<void(const TapeEvent&)>& fn,
                       std::string* warning = nullptr, TapeDamage* damage = nullptr);

/// Follows a tape still being written: reads the whole events from byte *offset on, calling `fn`,
/// and leaves *offset after the last of them (a partly written last event is read on a later
/// call). A damaged stretch followed by a whole event is passed over as read_tape_file does; one
/// with nothing whole after it yet is left for a later call. Start with *offset = 0. Returns the
/// number of events read by this call. Throws InputError when the file cannot be opened, or holds
/// no event from its start.
int64_t follow_tape_file(const std::string& path, int64_t* offset,
                         const std::function<void(const TapeEvent&)>& fn);

/// The tape blocks of run `run_id` with seq < `below` from a tape file, in seq order, each once
/// (retransmitted copies dropped); InputError naming the file and the first missing seq when they
/// are not all there, or for an event that does not decode.
std::vector<Block> read_tape_blocks(const std::string& path, const std::string& run_id,
                                    int64_t below);

/// One run of a tape file: its tape blocks in seq order (each once, retransmitted copies dropped;
/// the abort's operating-point block, seq -1, left out) and its status events in tape order (each
/// seq once; the start and abort events, seq -1, kept). `run_id` "" takes the first tape block's
/// run. InputError naming the file when the run has no blocks, a block is missing or an event does
/// not decode.
struct TapeRun {
  std::string run_id;
  std::vector<Block> blocks;
  std::vector<StatusEvent> events;
};
TapeRun read_tape_run(const std::string& path, const std::string& run_id = "");

/// Writes a tape file (an LCM log lcm-logplayer replays) as the recorder would have recorded the
/// run: the start event, then each block preceded by the status events that take effect before
/// its last sample, then the remaining events; blocks on FRALAB_TAPE with their checksum, events
/// on FRALAB_STATUS, timestamps on the sample clock (microseconds). InputError naming the file
/// when it cannot be written.
void write_tape_file(const std::string& path, const std::vector<Block>& blocks,
                     const std::vector<StatusEvent>& events);

/// `fralab tape`: per LCM channel the event count, the tape's channels, block sequence with the
/// missing seqs named, excitation states, samples and engine time. Errors name the file and event.
Json tape_summary(const std::string& path);

}  // namespace fralab
