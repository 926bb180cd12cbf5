// The free-running plant's command buffer (plant/command_buffer.h): stamped commands play at their
// samples whatever the order they came in; a dry buffer holds the last command and says so.
#include "fralab/plant/command_buffer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fralab/core/error.h"

using namespace fralab;

namespace {

// Command block `seq` of 4 samples: u_X = 10 * seq + k, ref_freq_hz = 2.
Block cmd(int64_t seq, bool final = false) {
  Block b;
  b.run_id = "r";
  b.seq = seq;
  b.start_sample = 4 * seq;
  b.sample_rate_hz = 100;
  b.channels = {"u_X", "ref_phase", "ref_freq_hz"};
  b.n_samples = 4;
  for (int k = 0; k < 4; ++k) b.samples.push_back(10.0 * double(seq) + k);
  for (int k = 0; k < 4; ++k) b.samples.push_back(0.1 * k);
  for (int k = 0; k < 4; ++k) b.samples.push_back(2.0);
  b.final_block = final;
  return b;
}

}  // namespace

TEST(CommandBuffer, StampedCommandsPlayAtTheirSamplesInAnyArrivalOrder) {
  CommandBuffer buf(3);
  EXPECT_FALSE(buf.next().has_value()) << "no clock before the first command";
  ASSERT_TRUE(buf.add(cmd(2, true)));  // arrives first: the clock starts at its first sample
  ASSERT_TRUE(buf.add(cmd(1)));        // earlier samples, arriving later: still in the future
  ASSERT_TRUE(buf.add(cmd(0)));
  std::vector<double> u, under;
  int64_t expect_start = 0;  // the earliest buffered sample
  while (auto t = buf.next()) {
    EXPECT_EQ(t->start_sample, expect_start);
    EXPECT_EQ(t->channels.back(), kUnderrunChannel);
    for (int k = 0; k < t->n_samples; ++k) {
      u.push_back(t->at(0, k));
      under.push_back(t->at(3, k));
    }
    expect_start += t->n_samples;
    if (t->final_block) break;
  }
  EXPECT_EQ(u, (std::vector<double>{0, 1, 2, 3, 10, 11, 12, 13, 20, 21, 22, 23}));
  EXPECT_EQ(under, std::vector<double>(12, 0.0));
  EXPECT_TRUE(buf.done());
  EXPECT_EQ(buf.underrun_samples(), 0);
  EXPECT_FALSE(buf.next().has_value());
}

TEST(CommandBuffer, ADryBufferHoldsTheLastCommandAndMarksTheUnderrun) {
  CommandBuffer buf(4);
  buf.add(cmd(0));
  auto t0 = buf.next();  // samples 0-3
  ASSERT_TRUE(t0);
  auto t1 = buf.next();  // samples 4-7: block 1 has not come
  ASSERT_TRUE(t1);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(t1->at(0, k), 3.0) << "held at block 0's last command";
    EXPECT_EQ(t1->at(2, k), 0.0) << "no reference frequency while held";
    EXPECT_EQ(t1->at(3, k), 1.0);
  }
  EXPECT_EQ(buf.underrun_samples(), 4);
  EXPECT_FALSE(buf.add(cmd(1))) << "block 1 came too late: its samples are played";
  EXPECT_EQ(buf.late_blocks(), 1);
  ASSERT_TRUE(buf.add(cmd(2, true)));
  auto t2 = buf.next();
  ASSERT_TRUE(t2);
  EXPECT_EQ(t2->at(0, 0), 20.0);
  EXPECT_EQ(t2->at(3, 0), 0.0);
  EXPECT_TRUE(t2->final_block);
  Block other = cmd(3);
  other.channels[1] = "phase";
  EXPECT_THROW(buf.add(other), InputError);
}
