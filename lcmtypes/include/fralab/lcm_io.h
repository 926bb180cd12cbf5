// The LCM edge: conversion between the generated message types and plain structs, checked
// decoding (a message of the wrong type or with inconsistent sizes is an error naming the channel),
// the URL policy (never leaves the host: udpm URLs must carry ttl=0) and reading a tape file.
// Nothing here does mathematics; libraries below it never see LCM.
#pragma once

#include <cstdint>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "fralab/ack_t.hpp"
#include "fralab/command_block_t.hpp"
#include "fralab/core/block.h"
#include "fralab/core/frd.h"
#include "fralab/core/json_util.h"
#include "fralab/core/tf.h"
#include "fralab/excitation_status_t.hpp"
#include "fralab/flow_t.hpp"
#include "fralab/frd_t.hpp"
#include "fralab/tape_block_t.hpp"
#include "fralab/tape_block_v1_t.hpp"
#include "fralab/tf_t.hpp"

namespace fralab {

inline constexpr const char* kCmdChannel = "FRALAB_CMD";
inline constexpr const char* kTapeChannel = "FRALAB_TAPE";
inline constexpr const char* kStatusChannel = "FRALAB_STATUS";
inline constexpr const char* kAckChannel = "FRALAB_ACK";
inline constexpr const char* kFrdChannel = "FRALAB_FRD";
inline constexpr const char* kTfChannel = "FRALAB_TF";
// On the data URL (not the control URL, whose every acknowledgement each listener would have to
// read: 28 analysers x 30 acknowledgements a block): the acquisition's flow requests, and the
// identifier's acknowledgements of complete curves.
inline constexpr const char* kFlowChannel = "FRALAB_FLOW";
inline constexpr const char* kFrdAckChannel = "FRALAB_FRD_ACK";

/// Publishes an acknowledgement (ack_t.lcm: consumer, stream, seq) on `channel` (kAckChannel on
/// the control instance; kFrdAckChannel on the data instance for the identifier's).
void publish_ack(lcm::LCM& lcm, const std::string& run_id, const std::string& consumer,
                 const std::string& stream, int64_t seq, const char* channel = kAckChannel);
/// Publishes a flow-control request (flow_t.lcm: "resend" or "close") on the data instance.
void publish_flow(lcm::LCM& data, const std::string& run_id, const std::string& kind,
                  const std::string& stream, int64_t from_seq, int64_t to_seq);

/// A tape block carrying its checksum (tape_block_t.lcm: crc32).
tape_block_t to_tape_msg(const Block& b);
command_block_t to_command_msg(const Block& b);
/// A tape block that failed its checksum (the block is named: seq, run, stored and computed CRC).
struct CorruptBlock : InputError {
  CorruptBlock(const std::string& what, int64_t seq) : InputError(what), seq(seq) {}
  int64_t seq;
};
/// Throws InputError when sizes disagree (n_values != n_channels * n_samples, ...), CorruptBlock
/// when the checksum does not match.
Block from_msg(const tape_block_t& m);
/// A tape record (FRALAB_TAPE) as a Block: tape_block_t with its checksum checked, or a tape
/// recorded before checksums (tape_block_v1_t). InputError naming the channel for any other bytes,
/// CorruptBlock for a failed checksum.
Block decode_tape_block(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
Block from_msg(const command_block_t& m);
excitation_status_t to_status_msg(const StatusEvent& e);
StatusEvent from_msg(const excitation_status_t& m);
/// A curve as published on FRALAB_FRD; every FrdPoint field travels.
frd_t to_frd_msg(const Frd& frd, const std::string& run_id, int64_t seq, bool complete);
/// Points sorted by w; InputError when n_points disagrees with the points carried.
Frd from_frd_msg(const frd_t& m);
/// A fitted transfer function as published on FRALAB_TF.
tf_t to_tf_msg(const Tf& tf, const std::string& pair, const std::string& run_id, double fit_error,
               const std::string& status);
/// InputError naming the pair for a root kind other than "real" or "pair".
Tf from_tf_msg(const tf_t& m);

/// The run id every fralab message begins with (after its 8-byte fingerprint); nullopt when the
/// bytes are too short or the length is absurd.
std::optional<std::string> peek_run_id(const void* data, size_t size);

/// Decodes a message of type Msg from a raw buffer; InputError naming the channel and the expected
/// type when the bytes are not that type (fingerprint mismatch, truncated).
/// Whether the counts in an excitation_status_t's bytes fit in them (checked before decoding:
/// LCM's generated decoders allocate what the counts say first).
bool status_wire_ok(const void* data, size_t size);

template <class Msg>
Msg decode_checked(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  if constexpr (std::is_same_v<Msg, excitation_status_t>) {
    if (!status_wire_ok(rbuf->data, rbuf->data_size))
      throw InputError("channel " + channel + ": a message of " + std::to_string(rbuf->data_size) +
                       " bytes whose counts exceed its bytes: not a fralab.excitation_status_t");
  }
  static_assert(!std::is_same_v<Msg, tape_block_t>, "tape blocks: use decode_tape_block");
  Msg m;
  int n = m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size));
  if (n < 0 || static_cast<uint32_t>(n) != rbuf->data_size) {
    throw InputError("channel " + channel + ": message of " + std::to_string(rbuf->data_size) +
                     " bytes is not a fralab." + Msg::getTypeName() +
                     " (wrong type or corrupt): check what publishes on " + channel);
  }
  return m;
}

/// The LCM URL: `flag` when given, else $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0.
/// A udpm URL must state its ttl option (parsed from the query: "?a=1&ttl=0", a number 0-255
/// without leading zeros): ttl=0 keeps fralab traffic on this host; ttl >= 1 (reaching other
/// hosts) is refused unless the environment says FRALAB_NETWORK=1 (the explicit opt-in).
std::string resolve_lcm_url(const std::string& flag);

/// The kernel's ephemeral port range, inclusive (/proc/sys/net/ipv4/ip_local_port_range; Linux's
/// default 32768-60999 when it cannot be read).
std::pair<int, int> ephemeral_port_range();

/// A fresh private URL for one lab run: a multicast group and an even port P of 10000-65534 derived
/// from `salt`, P and P + 1 (the control URL's) outside the ephemeral range (13652 ports with
/// Linux's default; Linux separates runs by port, not group, and LCM's unbound send sockets take
/// ephemeral ports a receiver could then not bind), ttl=0, and a 2 MB receive buffer request
/// (granted up to net.core.rmem_max). The one-argument form reads the range from the kernel.
std::string private_lcm_url(uint64_t salt);
std::string private_lcm_url(uint64_t salt, std::pair<int, int> ephemeral);

/// Throws InputError naming `what` and `url` unless `lcm` can publish and receive there. LCM opens
/// its receive socket lazily (at the first subscription or getFileno()): a bind that fails there
/// (the port held by a socket without SO_REUSEADDR: "bind: Address already in use") is only
/// printed, and LCM 1.3 then crashed the process at a later call (fralab-acquire: signal 11). The
/// socket is opened here, once, and its failure is an error.
void require_lcm(lcm::LCM& lcm, const std::string& what, const std::string& url);

/// The control URL of a lab run: flow-control acknowledgements travel there, away from the tape
/// URL, so lcm-logger (whose subscription queue holds 30 messages) hears only the tape traffic.
/// Derived from the tape URL by adding 1 to its port ("" stays "").
std::string control_url_for(const std::string& tape_url);

/// The two LCM instances of a lab process: the tape's (data) and the control URL's, each opened
/// and checked with require_lcm. data_url: resolve_lcm_url(url); control_url: ctl_url resolved
/// when given, else control_url_for(data_url). Throws InputError naming the URL that fails.
struct LabLcm {
  LabLcm(const std::string& url, const std::string& ctl_url);
  std::string data_url, control_url;
  lcm::LCM data, control;
};

/// Waits up to timeout_ms for traffic on either instance and dispatches what arrived (a and b may
/// be the same instance).
void handle_either(lcm::LCM& a, lcm::LCM& b, int timeout_ms);

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
