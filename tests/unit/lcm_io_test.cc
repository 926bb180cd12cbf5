// Tape files: reading whole, detecting truncation, and following a tape still being written.
#include "fralab/lcm_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

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

TEST(TapeFile, TruncationIsNamedWithItsOffset) {
  const std::string p = tmp("cut.lcmlog");
  auto ends = write_log(p, 4);
  fs::resize_file(p, ends[3] - 5);  // the last event loses its tail
  try {
    read_tape_file(p, [](const TapeEvent&) {});
    FAIL() << "a truncated tape was read without complaint";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("cut.lcmlog: truncated or corrupt tape: 3 events read, then unreadable bytes "
                     "from offset " +
                     std::to_string(ends[2])),
              std::string::npos)
        << m;
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
