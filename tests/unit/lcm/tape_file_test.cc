// Tape files: read whole, up to a cut, past a damaged stretch, followed while still being written,
// and written as the recorder would have and read back (fralab/lcm/tape_file.h).
#include "fralab/lcm/tape_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

#include "fralab/lcm/channels.h"

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

std::string tmp(const std::string& name) {
  return (fs::temp_directory_path() /
          ("fralab_tape_file_" + std::to_string(::getpid()) + "_" + name))
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
