// Tape files: reading whole, detecting truncation, and following a tape still being written.
#include "fralab/lcm_io.h"

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <set>

using namespace fralab;
namespace fs = std::filesystem;

namespace {

// Writes `n` events (channel "C", payload: k bytes of value k for event k = 1..n); returns their
// end offsets.
std::vector<int64_t> write_log(const std::string& path, int n) {
  std::vector<int64_t> ends;
  lcm::LogFile log(path, "w");
  for (int k = 1; k <= n; ++k) {
    std::vector<uint8_t> data(size_t(k) * 10, uint8_t(k));
    lcm::LogEvent ev{k - 1, 1000 * k, "C", int32_t(data.size()), data.data()};
    EXPECT_EQ(log.writeEvent(&ev), 0);
    std::fflush(log.getFilePtr());
    ends.push_back(std::ftell(log.getFilePtr()));
  }
  return ends;
}

// A UDP socket bound to an ephemeral port without SO_REUSEADDR, as LCM's own send sockets hold
// theirs (port 0: the bind failed). Closed at the end of the scope.
struct HeldPort {
  int fd = socket(AF_INET, SOCK_DGRAM, 0);
  int port = 0;
  HeldPort() {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_ANY);
    a.sin_port = 0;
    socklen_t len = sizeof a;
    if (fd >= 0 && bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
        getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
      port = ntohs(a.sin_port);
  }
  ~HeldPort() {
    if (fd >= 0) close(fd);
  }
  HeldPort(const HeldPort&) = delete;
  HeldPort& operator=(const HeldPort&) = delete;
};

std::string tmp(const std::string& name) {
  return (fs::temp_directory_path() / ("fralab_lcm_io_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

}  // namespace

TEST(TapeFile, ReadsEveryEventInOrder) {
  const std::string p = tmp("whole.lcmlog");
  write_log(p, 4);
  std::vector<int> sizes;
  EXPECT_EQ(read_tape_file(p, [&](const TapeEvent& e) { sizes.push_back(e.datalen); }), 4);
  EXPECT_EQ(sizes, (std::vector<int>{10, 20, 30, 40}));
  fs::remove(p);
}

TEST(TapeFile, ACutTapeIsReadUpToTheCutWithAWarning) {
  const std::string p = tmp("cut.lcmlog");
  auto ends = write_log(p, 4);
  fs::resize_file(p, ends[3] - 5);  // the last event loses its tail (a recorder killed mid-write)
  std::string warning;
  EXPECT_EQ(read_tape_file(
                p, [](const TapeEvent&) {}, &warning),
            3);
  EXPECT_THAT(warning, ::testing::HasSubstr("cut.lcmlog: the tape ends inside an event"));
  EXPECT_THAT(warning, ::testing::HasSubstr("read its 3 whole events, up to byte " +
                                            std::to_string(ends[2])));
  fs::resize_file(p, ends[2] + 10);  // cut inside the header of the fourth
  warning.clear();
  EXPECT_EQ(read_tape_file(
                p, [](const TapeEvent&) {}, &warning),
            3);
  EXPECT_FALSE(warning.empty());
  fs::remove(p);
}

// Headers are checked against the file before anything is read or allocated: an event claiming
// 0x7fffffff bytes (liblcm's own reader crashes on it) and garbage in the middle are damaged
// stretches, passed over to the next whole event and named by their bytes; a file with no event
// at all is refused.
TEST(TapeFile, ADamagedStretchIsPassedOverToTheNextWholeEventNamingItsBytes) {
  const std::string p = tmp("bad.lcmlog");
  auto ends = write_log(p, 4);
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(ends[0] + 24);  // the second event's data length
    const char huge[4] = {0x7f, char(0xff), char(0xff), char(0xff)};
    f.write(huge, 4);
  }
  std::vector<int> sizes;
  std::string warning;
  TapeDamage damage;
  EXPECT_EQ(read_tape_file(
                p, [&](const TapeEvent& e) { sizes.push_back(e.datalen); }, &warning, &damage),
            3);
  EXPECT_EQ(sizes, (std::vector<int>{10, 30, 40}));  // the second event is the damaged stretch
  EXPECT_THAT(warning,
              ::testing::HasSubstr("bad.lcmlog: damaged stretch: bytes " + std::to_string(ends[0]) +
                                   " to " + std::to_string(ends[1] - 1)));
  ASSERT_EQ(damage.skipped.size(), 1u);
  EXPECT_EQ(damage.skipped[0], std::make_pair(ends[0], ends[1]));

  write_log(p, 4);
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    // Garbage over the end of the second event's data (its header is whole: it is read, and a
    // tape block there would fail its checksum) and over the third's header.
    f.seekp(ends[1] - 5);
    const std::string junk(30, 'J');
    f.write(junk.data(), std::streamsize(junk.size()));
  }
  sizes.clear();
  warning.clear();
  EXPECT_EQ(read_tape_file(
                p, [&](const TapeEvent& e) { sizes.push_back(e.datalen); }, &warning, &damage),
            3);
  EXPECT_EQ(sizes, (std::vector<int>{10, 20, 40}));
  EXPECT_THAT(warning, ::testing::HasSubstr("damaged stretch: bytes " + std::to_string(ends[1]) +
                                            " to " + std::to_string(ends[2] - 1)));
  // Following the tape passes over it too.
  int64_t offset = 0;
  EXPECT_EQ(follow_tape_file(p, &offset, [](const TapeEvent&) {}), 3);
  EXPECT_EQ(offset, ends[3]);

  {
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f << std::string(200, 'x');
  }
  try {
    read_tape_file(p, [](const TapeEvent&) {});
    ADD_FAILURE() << "garbage was read";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("bad.lcmlog: corrupt tape: 0 events read, then no "
                                               "event at byte 0"));
  }
  fs::remove(p);
}

TEST(TapeFile, FollowingReadsOnlyWhatWasAddedAndWaitsForAPartEvent) {
  const std::string whole = tmp("src.lcmlog"), p = tmp("growing.lcmlog");
  auto ends = write_log(whole, 4);
  std::string bytes;
  {
    std::ifstream in(whole, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  auto write_prefix = [&](int64_t n) { std::ofstream(p, std::ios::binary).write(bytes.data(), n); };
  int64_t offset = 0;
  std::vector<int> seen;
  auto take = [&](const TapeEvent& e) { seen.push_back(e.datalen); };
  write_prefix(ends[1] + 7);  // two whole events and 7 bytes of the third
  EXPECT_EQ(follow_tape_file(p, &offset, take), 2);
  EXPECT_EQ(offset, ends[1]);
  write_prefix(ends[3]);  // the rest arrives
  EXPECT_EQ(follow_tape_file(p, &offset, take), 2);
  EXPECT_EQ(offset, ends[3]);
  EXPECT_EQ(follow_tape_file(p, &offset, take), 0);  // nothing new
  EXPECT_EQ(seen, (std::vector<int>{10, 20, 30, 40}));
  fs::remove(whole);
  fs::remove(p);
}

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

// The URL policy: the ttl option parsed (not a substring), ttl >= 1 only on the explicit opt-in.
TEST(LcmUrl, TtlIsParsedAndLeavingTheHostIsAnOptIn) {
  unsetenv("FRALAB_NETWORK");
  EXPECT_EQ(resolve_lcm_url("udpm://239.255.1.2:7667?ttl=0"), "udpm://239.255.1.2:7667?ttl=0");
  EXPECT_NO_THROW(resolve_lcm_url("udpm://239.255.1.2:7667?recv_buf_size=2097152&ttl=0"));
  EXPECT_NO_THROW(resolve_lcm_url("memq://"));
  for (const char* bad : {"udpm://239.255.1.2:7667?ttl=05", "udpm://239.255.1.2:7667?ttl=0x1",
                          "udpm://239.255.1.2:7667?ttl=", "udpm://239.255.1.2:7667?ttl=256"}) {
    try {
      resolve_lcm_url(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("is not a number 0-255")) << bad;
    }
  }
  EXPECT_THROW(resolve_lcm_url("udpm://239.255.1.2:7667"), InputError);         // ttl unstated
  EXPECT_THROW(resolve_lcm_url("udpm://239.255.1.2:7667?xttl=0"), InputError);  // not ttl
  try {
    resolve_lcm_url("udpm://239.255.1.2:7667?ttl=1");
    ADD_FAILURE() << "ttl=1 without the opt-in";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("set FRALAB_NETWORK=1"));
  }
  setenv("FRALAB_NETWORK", "1", 1);
  EXPECT_NO_THROW(resolve_lcm_url("udpm://239.255.1.2:7667?ttl=1"));
  unsetenv("FRALAB_NETWORK");
}

// Every port even, P and P + 1 outside the ephemeral range (Linux's default, a custom one, and
// the range this kernel reports), each used once over as many salts as there are ports.
TEST(LcmUrl, PrivateUrlsUseAnEvenPortOutsideTheEphemeralRangeAndThePeekFindsTheRunId) {
  auto port_of = [](const std::string& u) {
    const auto colon = u.rfind(':'), q = u.find('?');
    return std::stoi(u.substr(colon + 1, q - colon - 1));
  };
  const std::pair<int, int> ranges[] = {{32768, 60999}, {20001, 40000}, ephemeral_port_range()};
  for (const auto& [lo, hi] : ranges) {
    int expected = 0;  // counted directly, not by the implementation's segment arithmetic
    for (int p = 10000; p <= 65534; p += 2) expected += (p + 1 < lo || p > hi) ? 1 : 0;
    if (expected == 0) continue;  // a kernel range covering every port: nothing to keep clear of
    std::set<int> ports;
    for (uint64_t s = 0; s < uint64_t(expected); ++s) {
      const std::string u = private_lcm_url(s * 62500, {lo, hi});
      const int port = port_of(u);
      EXPECT_EQ(port % 2, 0) << u;
      EXPECT_GE(port, 10000) << u;
      EXPECT_LE(port, 65534) << u;
      EXPECT_TRUE(port + 1 < lo || port > hi) << u << " in the ephemeral range " << lo << "-" << hi;
      ports.insert(port);
      EXPECT_NO_THROW(resolve_lcm_url(u));
    }
    EXPECT_EQ(int(ports.size()), expected) << lo << "-" << hi;  // every port used once
  }
  EXPECT_EQ(port_of(private_lcm_url(0, {32768, 60999})), 10000);
  EXPECT_EQ(port_of(private_lcm_url(11384 * 62500, {32768, 60999})), 61000);
  ack_t a;
  a.run_id = "run-42";
  a.consumer = "c";
  a.seq = 1;
  a.stream = "tape";
  std::vector<uint8_t> buf(size_t(a.getEncodedSize()));
  a.encode(buf.data(), 0, int(buf.size()));
  EXPECT_EQ(peek_run_id(buf.data(), buf.size()), "run-42");
  EXPECT_EQ(peek_run_id(buf.data(), 10), std::nullopt);
  buf[8] = 0x7f;  // absurd length
  EXPECT_EQ(peek_run_id(buf.data(), buf.size()), std::nullopt);
}

// write_tape_file and read_tape_run: blocks and status events out and back, each field kept.
TEST(TapeFile, WrittenRunReadsBackWithItsBlocksAndEvents) {
  std::vector<Block> blocks(3);
  for (int i = 0; i < 3; ++i) {
    Block& b = blocks[size_t(i)];
    b.run_id = "r1";
    b.seq = i;
    b.start_sample = 500 + 4 * i;
    b.sample_rate_hz = 1000;
    b.channels = {"u_X", "Y"};
    b.n_samples = 4;
    for (int k = 0; k < 8; ++k) b.samples.push_back(0.1 * k + i + 1e-13 * k);
    b.final_block = i == 2;
  }
  StatusEvent start, integ;
  start.run_id = integ.run_id = "r1";
  start.seq = -1;
  start.state = RunState::kStart;
  integ.seq = 0;
  integ.state = RunState::kIntegrate;
  integ.sample = 505;
  integ.frequency_hz = 2.5;
  integ.ref_phase_rad = 0.25;
  integ.n_samples = 6;
  integ.inputs = {"X"};
  integ.amplitudes = {1.5};
  const std::string path = tmp("run.lcmlog");
  write_tape_file(path, blocks, {start, integ});
  const TapeRun run = read_tape_run(path);
  EXPECT_EQ(run.run_id, "r1");
  ASSERT_EQ(run.blocks.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(run.blocks[size_t(i)].samples, blocks[size_t(i)].samples);
    EXPECT_EQ(run.blocks[size_t(i)].start_sample, blocks[size_t(i)].start_sample);
    EXPECT_EQ(run.blocks[size_t(i)].final_block, i == 2);
  }
  ASSERT_EQ(run.events.size(), 2u);
  EXPECT_EQ(run.events[0].state, RunState::kStart);
  EXPECT_EQ(run.events[1].frequency_hz, 2.5);
  EXPECT_EQ(run.events[1].ref_phase_rad, 0.25);
  EXPECT_EQ(run.events[1].amplitudes, std::vector<double>{1.5});
  // The recorder's order: the integrate event (sample 505) is written before block 1 (504..507).
  std::vector<std::string> order;
  read_tape_file(path, [&](const TapeEvent& e) { order.push_back(e.channel); });
  EXPECT_THAT(order, testing::ElementsAre(kStatusChannel, kTapeChannel, kStatusChannel,
                                          kTapeChannel, kTapeChannel));
  // Another run's event of the same seq, earlier on the tape, does not hide this run's.
  StatusEvent other = integ;
  other.run_id = "r0";
  other.sample = 500;
  other.frequency_hz = 9;
  write_tape_file(path, blocks, {start, other, integ});
  const TapeRun mixed = read_tape_run(path, "r1");
  ASSERT_EQ(mixed.events.size(), 2u);
  EXPECT_EQ(mixed.events[1].frequency_hz, 2.5);
  // A run with a block missing is refused, naming the seq.
  write_tape_file(path, {blocks[0], blocks[2]}, {start});
  EXPECT_THAT([&] { read_tape_run(path); },
              testing::ThrowsMessage<InputError>(testing::HasSubstr("lacks tape block seq 1")));
  fs::remove(path);
}

// A port held by a socket without SO_REUSEADDR (as LCM's own send sockets hold their ephemeral
// ports) cannot be bound by LCM's receiver: require_lcm says so, naming the URL, where LCM 1.3
// printed "bind: Address already in use" and crashed the process at a later call. A memq:// LCM
// passes (its "socket" is a pipe).
TEST(RequireLcm, AReceivePortHeldByAnotherSocketIsAnErrorNamingTheUrl) {
  const HeldPort held_port;
  ASSERT_GT(held_port.port, 0);
  const std::string url = "udpm://239.255.201.7:" + std::to_string(held_port.port) + "?ttl=0";
  lcm::LCM held(url);
  try {
    require_lcm(held, "the test's LCM", url);
    ADD_FAILURE() << "no error for a held port";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("cannot receive on the test's LCM at " + url));
  }
  lcm::LCM memq("memq://");
  EXPECT_NO_THROW(require_lcm(memq, "memq", "memq://"));
}

// A lab process's two instances: the control URL is the data URL's port + 1 unless given, and a
// held control port is an error naming the control URL (not the data URL).
TEST(LabLcm, TheControlUrlIsTheNextPortUnlessGivenAndAHeldOneIsNamed) {
  const HeldPort held_port;
  const int held = held_port.port;
  ASSERT_GT(held, 1);
  auto url = [](int port) { return "udpm://239.255.201.8:" + std::to_string(port) + "?ttl=0"; };
  {
    const LabLcm io(url(held + 2), "");
    EXPECT_EQ(io.data_url, url(held + 2));
    EXPECT_EQ(io.control_url, url(held + 3));
  }
  {
    const LabLcm io(url(held + 2), url(held + 6));
    EXPECT_EQ(io.control_url, url(held + 6));
  }
  try {
    const LabLcm io(url(held - 1), "");  // its control port is the held one
    ADD_FAILURE() << "no error for a held control port";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(),
                ::testing::HasSubstr("cannot receive on the control LCM URL at " + url(held)));
  }
}
