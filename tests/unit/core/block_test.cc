// The tape's records (core/block.h): a free-running plant's held samples, kept as runs whatever
// order the blocks arrive in.
#include "fralab/core/block.h"

#include <gtest/gtest.h>

using namespace fralab;

namespace {

// A block of 4 samples from `start` whose "underrun" channel is `held` (and a command channel).
Block block(int64_t start, std::vector<double> held) {
  Block b;
  b.start_sample = start;
  b.n_samples = 4;
  b.channels = {"u_X", kUnderrunChannel};
  b.samples = {1, 2, 3, 4};
  b.samples.insert(b.samples.end(), held.begin(), held.end());
  return b;
}

using Held = std::optional<std::pair<int64_t, int64_t>>;

}  // namespace

TEST(HeldSamples, RunsJoinInAnyArrivalOrderAndAreFoundWithinAWindow) {
  HeldSamples h;
  EXPECT_EQ(h.add(block(8, {1, 1, 0, 0})), 2);  // 8-9
  EXPECT_EQ(h.add(block(0, {0, 0, 1, 1})), 2);  // 2-3
  EXPECT_EQ(h.add(block(4, {1, 1, 1, 1})), 4);  // 4-7: joins 2-3 and 8-9 into 2-9
  EXPECT_EQ(h.add(block(4, {1, 1, 1, 1})), 4);  // delivered twice: nothing new
  EXPECT_EQ(h.count(), 8);
  EXPECT_EQ(h.within(0, 20), Held({2, 9}));
  EXPECT_EQ(h.within(5, 7), Held({5, 6}));  // [a, b): 7 is outside
  EXPECT_EQ(h.within(10, 20), std::nullopt);
  EXPECT_EQ(h.within(0, 2), std::nullopt);
  h.add(block(20, {0, 1, 0, 1}));  // 21 and 23: two runs
  EXPECT_EQ(h.within(0, 30), Held({2, 23}));
  EXPECT_EQ(h.within(22, 23), std::nullopt);
  Block plain = block(40, {1, 1, 1, 1});
  plain.channels = {"u_X", "other"};  // no "underrun" channel: nothing held
  EXPECT_EQ(h.add(plain), 0);
  EXPECT_EQ(h.count(), 10);
}
