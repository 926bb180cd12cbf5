// Messages <-> plain structs, one place per message type: each generated type
// (lcmtypes/fralab/*.lcm) is copied to and from its core struct here and nowhere else, and decoding
// is checked (a message of the wrong type or with inconsistent sizes is an error naming the
// channel). Nothing here opens a socket or does mathematics; libraries below it never see LCM.
#pragma once

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>
#include <type_traits>

#include "fralab/command_block_t.hpp"
#include "fralab/core/block.h"
#include "fralab/core/frd.h"
#include "fralab/core/tf.h"
#include "fralab/excitation_status_t.hpp"
#include "fralab/excitation_status_v1_t.hpp"
#include "fralab/frd_t.hpp"
#include "fralab/tape_block_t.hpp"
#include "fralab/tape_block_v1_t.hpp"
#include "fralab/tf_t.hpp"

namespace fralab {

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
/// A status event; its measurement chain travels as the typed field (has_measurement_chain).
/// A chain that does not read leaves the event whole, with measurement_chain_error saying why.
excitation_status_t to_status_msg(const StatusEvent& e);
StatusEvent from_msg(const excitation_status_t& m);
/// A status event of a tape recorded before the chain had a field: a start event whose message is
/// "measurement_chain: {...}" (chain_from_message) gets it as measurement_chain, its message
/// kept; one that does not read, measurement_chain_error.
StatusEvent from_msg(const excitation_status_v1_t& m);
/// A status record (FRALAB_STATUS) as a StatusEvent: excitation_status_t, or the form tapes were
/// recorded in before the chain had a field (excitation_status_v1_t). InputError naming the channel
/// for any other bytes (the counts are checked against the bytes before decoding).
StatusEvent decode_status_event(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
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

/// Whether the counts in an excitation_status_t's bytes fit in them (checked before decoding:
/// LCM's generated decoders allocate what the counts say first).
bool status_wire_ok(const void* data, size_t size);

/// Decodes a message of type Msg from a raw buffer; InputError naming the channel and the expected
/// type when the bytes are not that type (fingerprint mismatch, truncated).
template <class Msg>
Msg decode_checked(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  static_assert(!std::is_same_v<Msg, tape_block_t>, "tape blocks: use decode_tape_block");
  static_assert(!std::is_same_v<Msg, excitation_status_t>, "status events: decode_status_event");
  Msg m;
  int n = m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size));
  if (n < 0 || static_cast<uint32_t>(n) != rbuf->data_size) {
    throw InputError("channel " + channel + ": message of " + std::to_string(rbuf->data_size) +
                     " bytes is not a fralab." + Msg::getTypeName() +
                     " (wrong type or corrupt): check what publishes on " + channel);
  }
  return m;
}

}  // namespace fralab
