// Messages <-> structs (fralab/lcm/codec.h): every field travels, tape blocks carry a checksum
// that names a damaged block, status events carry the measurement chain typed, and tapes recorded
// before checksums or before the chain had a field are still read.
#include "fralab/lcm/codec.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include "fralab/lcm/channels.h"

using namespace fralab;

// Every FrdPoint field travels on FRALAB_FRD (input, amplitude and nl_rel included).
TEST(LcmIo, FrdMessagesCarryEveryField) {
  Frd f;
  f.pair = "Wf:N";
  FrdPoint p;
  p.w = 2.0;
  p.mag = 0.3;
  p.phase_deg = -40;
  p.sigma = 0.001;
  p.coherence = 0.99;
  p.h2_rel = 0.01;
  p.h3_rel = 0.02;
  p.nl_rel = 0.003;
  p.sigma_noise = 0.004;
  p.sigma_nl = 0.005;
  p.realisations = 6;
  p.line_amplitude = 0.25;
  p.n_cycles = 9;
  p.step = 4;
  p.input = "Wf";
  p.amplitude = 60;
  p.valid = false;
  p.note = "missing seq 3";
  f.points = {p};
  const frd_t m = to_frd_msg(f, "run-1", 7, true);
  EXPECT_EQ(m.run_id, "run-1");
  EXPECT_TRUE(m.complete);
  const Frd g = from_frd_msg(m);
  ASSERT_EQ(g.points.size(), 1u);
  const FrdPoint& q = g.points[0];
  EXPECT_EQ(q.input, "Wf");
  EXPECT_EQ(q.amplitude, 60);
  EXPECT_EQ(q.nl_rel, 0.003);
  EXPECT_EQ(q.sigma_noise, 0.004);
  EXPECT_EQ(q.sigma_nl, 0.005);
  EXPECT_EQ(q.realisations, 6);
  EXPECT_EQ(q.line_amplitude, 0.25);
  EXPECT_EQ(q.h3_rel, 0.02);
  EXPECT_EQ(q.step, 4);
  EXPECT_FALSE(q.valid);
  EXPECT_EQ(q.note, "missing seq 3");
  frd_t bad = m;
  bad.n_points = 5;
  EXPECT_THROW(from_frd_msg(bad), InputError);
}

TEST(LcmIo, TfMessagesRoundTrip) {
  Tf t;
  t.gain = 2.86;
  t.zeros = {Root::Real(192)};
  t.poles = {Root::Real(-2.86), Root::Pair(49.6, 0.021)};
  t.delay_s = 0.011;
  const tf_t m = to_tf_msg(t, "Wf:N", "run-1", 0.004, "converged");
  EXPECT_EQ(m.status, "converged");
  EXPECT_EQ(m.fit_error, 0.004);
  const Tf u = from_tf_msg(m);
  EXPECT_EQ(u.gain, 2.86);
  EXPECT_EQ(u.delay_s, 0.011);
  ASSERT_EQ(u.poles.size(), 2u);
  EXPECT_TRUE(u.poles[1].pair);
  EXPECT_EQ(u.poles[1].wn, 49.6);
  EXPECT_EQ(u.zeros[0].real, 192);
  tf_t bad = m;
  bad.poles[0].kind = "complex";
  EXPECT_THROW(from_tf_msg(bad), InputError);
}

// Tape blocks carry a CRC-32 (zlib) of their encoding: one flipped byte anywhere is refused with
// the block named; a tape recorded without checksums (tape_block_v1_t, its own fingerprint) is
// still read.
namespace {

Block sample_block() {
  Block b;
  b.run_id = "r";
  b.seq = 7;
  b.start_sample = 700;
  b.sample_rate_hz = 1000;
  b.channels = {"u_Wf", "P3"};
  b.n_samples = 3;
  b.samples = {1, 2, 3, 0.00859, 0.00860, 0.00861};
  return b;
}

template <class Msg>
std::vector<uint8_t> bytes_of(const Msg& m) {
  std::vector<uint8_t> buf(size_t(m.getEncodedSize()));
  m.encode(buf.data(), 0, int(buf.size()));
  return buf;
}

}  // namespace

TEST(TapeChecksum, AFlippedByteIsRefusedNamingTheBlock) {
  const Block b = sample_block();
  std::vector<uint8_t> buf = bytes_of(to_tape_msg(b));
  lcm::ReceiveBuffer rb{buf.data(), uint32_t(buf.size()), 0};
  const Block ok = decode_tape_block(&rb, kTapeChannel);
  EXPECT_EQ(ok.samples, b.samples);
  EXPECT_EQ(ok.seq, 7);
  // Flipped: a byte of the P3 samples (before final_block, crc32 and two more samples), a byte
  // of the run id, the last byte (the checksum itself).
  for (size_t at : {buf.size() - 8 - 1 - 8 * 3 - 4, size_t(12), buf.size() - 1}) {
    std::vector<uint8_t> bad = buf;
    bad[at] ^= 0x10;
    lcm::ReceiveBuffer rb2{bad.data(), uint32_t(bad.size()), 0};
    try {
      decode_tape_block(&rb2, kTapeChannel);
      ADD_FAILURE() << "byte " << at << " flipped and accepted";
    } catch (const CorruptBlock& e) {
      EXPECT_EQ(e.seq, 7);
      EXPECT_THAT(e.what(), ::testing::HasSubstr("tape block seq 7 of run "));
      EXPECT_THAT(e.what(), ::testing::HasSubstr("failed its checksum"));
    } catch (const InputError& e) {
      // A flip in the fingerprint or a length: not a tape block at all, also refused.
      EXPECT_THAT(e.what(), ::testing::HasSubstr("FRALAB_TAPE")) << at;
    }
  }
}

TEST(TapeChecksum, TapesRecordedBeforeChecksumsAreStillRead) {
  // The fingerprint of tape_block_t without checksums (lcm-gen of that .lcm: base hash
  // 0x371122aab21e9704): such tapes decode as tape_block_v1_t.
  EXPECT_EQ(tape_block_v1_t::getHash(), int64_t(7935981726436503048LL));
  const Block b = sample_block();
  tape_block_v1_t old;
  old.run_id = b.run_id;
  old.seq = b.seq;
  old.start_sample = b.start_sample;
  old.sample_rate_hz = b.sample_rate_hz;
  old.n_channels = 2;
  old.channel_names = b.channels;
  old.n_samples = b.n_samples;
  old.n_values = 6;
  old.samples = b.samples;
  old.final_block = false;
  std::vector<uint8_t> buf = bytes_of(old);
  lcm::ReceiveBuffer rb{buf.data(), uint32_t(buf.size()), 0};
  const Block got = decode_tape_block(&rb, kTapeChannel);
  EXPECT_EQ(got.samples, b.samples);
  EXPECT_EQ(got.channels, b.channels);
  std::vector<uint8_t> junk(40, 0xab);
  lcm::ReceiveBuffer rj{junk.data(), uint32_t(junk.size()), 0};
  EXPECT_THROW(decode_tape_block(&rj, kTapeChannel), InputError);
}

namespace {

StatusEvent start_event() {
  StatusEvent e;
  e.run_id = "r";
  e.seq = -1;
  e.state = RunState::kStart;
  e.sample_rate_hz = 1000;
  e.n_samples = 123456;
  e.inputs = {"Wf", "A8"};
  e.amplitudes = {0.5, 1.5};
  MeasurementChain c;
  c.sample_rate_hz = 1000;
  c.hold = MeasurementChain::Hold::kZeroOrder;
  c.converter_delay_s = 0.0015;
  c.reheld_inputs = {"A8"};
  e.measurement_chain = c;
  return e;
}

lcm::ReceiveBuffer buffer_of(const std::vector<uint8_t>& bytes) {
  lcm::ReceiveBuffer rb{};
  rb.data = const_cast<uint8_t*>(bytes.data());
  rb.data_size = uint32_t(bytes.size());
  return rb;
}

}  // namespace

// The start event carries the measurement chain as a field of its own: every part of it travels,
// and an event without one stays without one.
TEST(StatusEvents, TheMeasurementChainTravelsAsATypedField) {
  const StatusEvent e = start_event();
  const std::vector<uint8_t> bytes = bytes_of(to_status_msg(e));
  const lcm::ReceiveBuffer rb = buffer_of(bytes);
  const StatusEvent back = decode_status_event(&rb, kStatusChannel);
  ASSERT_TRUE(back.measurement_chain.has_value());
  EXPECT_EQ(back.measurement_chain->sample_rate_hz, 1000);
  EXPECT_EQ(back.measurement_chain->hold, MeasurementChain::Hold::kZeroOrder);
  EXPECT_EQ(back.measurement_chain->converter_delay_s, 0.0015);
  EXPECT_EQ(back.measurement_chain->reheld_inputs, std::vector<std::string>{"A8"});
  EXPECT_EQ(back.message, "");
  EXPECT_EQ(back.n_samples, 123456);

  StatusEvent plain = e;
  plain.measurement_chain.reset();
  const std::vector<uint8_t> pb = bytes_of(to_status_msg(plain));
  const lcm::ReceiveBuffer prb = buffer_of(pb);
  EXPECT_FALSE(decode_status_event(&prb, kStatusChannel).measurement_chain.has_value());
}

// A tape recorded before the chain had a field: its start event (excitation_status_v1_t, its own
// fingerprint) carried the chain as its message; it reads with the chain typed, the message kept.
// A chain in such a message that does not read is an error naming the event.
TEST(StatusEvents, TapesRecordedWithTheChainInTheMessageAreStillRead) {
  const StatusEvent e = start_event();
  const excitation_status_t now = to_status_msg(e);
  excitation_status_v1_t old;
  old.run_id = now.run_id;
  old.seq = now.seq;
  old.sample = now.sample;
  old.sample_rate_hz = now.sample_rate_hz;
  old.excitation = now.excitation;
  old.state = now.state;
  old.n_inputs = now.n_inputs;
  old.inputs = now.inputs;
  old.amplitudes = now.amplitudes;
  old.n_samples = now.n_samples;
  old.message = chain_to_message(*e.measurement_chain);
  old.n_lines = 0;
  const std::vector<uint8_t> bytes = bytes_of(old);
  const lcm::ReceiveBuffer rb = buffer_of(bytes);
  const StatusEvent back = decode_status_event(&rb, kStatusChannel);
  ASSERT_TRUE(back.measurement_chain.has_value());
  EXPECT_EQ(back.measurement_chain->hold, MeasurementChain::Hold::kZeroOrder);
  EXPECT_EQ(back.measurement_chain->converter_delay_s, 0.0015);
  EXPECT_EQ(back.measurement_chain->reheld_inputs, std::vector<std::string>{"A8"});
  EXPECT_EQ(back.message, old.message);
  EXPECT_EQ(back.n_samples, 123456);

  // A chain that does not read (status events carry no checksum) leaves the event whole, the
  // chain unknown and the reason named: what is recorded stays readable.
  old.message = "measurement_chain: {\"sample_rate_hz\": -5, \"hold\": \"zero_order\"}";
  const std::vector<uint8_t> bad = bytes_of(old);
  const lcm::ReceiveBuffer brb = buffer_of(bad);
  const StatusEvent kept = decode_status_event(&brb, kStatusChannel);
  EXPECT_FALSE(kept.measurement_chain.has_value());
  EXPECT_THAT(kept.measurement_chain_error, testing::HasSubstr("status event seq -1"));
  EXPECT_EQ(kept.n_samples, 123456);
  excitation_status_t typed = to_status_msg(start_event());
  typed.measurement_chain.hold = "no_hold";
  const std::vector<uint8_t> tb = bytes_of(typed);
  const lcm::ReceiveBuffer trb = buffer_of(tb);
  EXPECT_THAT(decode_status_event(&trb, kStatusChannel).measurement_chain_error,
              testing::HasSubstr("no_hold"));
}

// Bytes of neither form, and counts beyond the bytes (LCM's decoders would allocate what a count
// says first), are refused naming the channel.
TEST(StatusEvents, OtherBytesAndImpossibleCountsAreRefusedNamingTheChannel) {
  const std::vector<uint8_t> block = bytes_of(to_tape_msg(sample_block()));
  const lcm::ReceiveBuffer rb = buffer_of(block);
  EXPECT_THAT([&] { decode_status_event(&rb, kStatusChannel); },
              testing::ThrowsMessage<InputError>(testing::HasSubstr("channel FRALAB_STATUS")));
  // The reheld inputs' count (the int32 before the last string, "A8": its length and 3 bytes)
  // made absurd.
  excitation_status_t m = to_status_msg(start_event());
  std::vector<uint8_t> bytes = bytes_of(m);
  bytes[bytes.size() - 3 - 4 - 4] = 0x7f;
  EXPECT_FALSE(status_wire_ok(bytes.data(), bytes.size()));
  const lcm::ReceiveBuffer crb = buffer_of(bytes);
  EXPECT_THAT([&] { decode_status_event(&crb, kStatusChannel); },
              testing::ThrowsMessage<InputError>(testing::HasSubstr("channel FRALAB_STATUS")));
}
