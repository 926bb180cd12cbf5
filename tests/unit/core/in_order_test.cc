// In-order delivery (core/in_order.h): a stream offered with reordering, duplicates and gaps comes
// out in sequence, each item once; a gap given up lets the rest through; memory stays bounded.
#include "fralab/core/in_order.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

namespace fralab {
namespace {

std::vector<int> drain(InOrder<int>& q) {
  std::vector<int> out;
  while (auto v = q.pop()) out.push_back(*v);
  return out;
}

TEST(InOrder, ReorderedAndDuplicatedItemsComeOutOnceInSequence) {
  InOrder<int> q(0);
  EXPECT_EQ(q.offer(1, 10), InOrder<int>::Offer::kNew);
  EXPECT_TRUE(drain(q).empty());  // 0 is missing: 1 is held
  EXPECT_EQ(q.delivered(), -1);
  EXPECT_EQ(q.offer(1, 99), InOrder<int>::Offer::kDuplicate);  // held already: first copy counts
  EXPECT_EQ(q.offer(0, 0), InOrder<int>::Offer::kNew);
  EXPECT_EQ(drain(q), (std::vector<int>{0, 10}));
  EXPECT_EQ(q.offer(0, 5), InOrder<int>::Offer::kDuplicate);  // delivered already
  EXPECT_EQ(q.delivered(), 1);
  EXPECT_EQ(q.next(), 2);
}

TEST(InOrder, AGapGivenUpLetsTheRestThroughAndIsCounted) {
  InOrder<int> q(-1);
  q.offer(3, 3);
  q.offer(2, 2);
  EXPECT_TRUE(drain(q).empty());
  EXPECT_EQ(q.skip_gap(), 3);  // -1, 0, 1 never came
  EXPECT_EQ(drain(q), (std::vector<int>{2, 3}));
  EXPECT_EQ(q.skipped(), 3);
  EXPECT_EQ(q.skip_gap(), 0);  // nothing held
}

TEST(InOrder, HoldingIsBounded) {
  InOrder<int> q(0, 4);
  for (int s = 1; s <= 5; ++s) q.offer(s, s);  // the fifth held item gives the gap up
  EXPECT_EQ(q.held(), 5u);
  EXPECT_EQ(q.skipped(), 1);
  EXPECT_EQ(drain(q), (std::vector<int>{1, 2, 3, 4, 5}));
}

// A corrupt message's seq of the largest int64_t has no successor: refused, the stream unchanged
// (delivering it overflowed next(); found by the tape fuzzer).
TEST(InOrder, TheLargestSeqIsRefusedAndTheStreamGoesOn) {
  InOrder<int> q(0);
  const int64_t top = std::numeric_limits<int64_t>::max();
  EXPECT_EQ(q.offer(top, 1), InOrder<int>::Offer::kRefused);
  EXPECT_EQ(q.held(), 0u);
  EXPECT_EQ(q.skip_gap(), 0);
  EXPECT_EQ(q.offer(top - 1, 2), InOrder<int>::Offer::kNew);  // the one before is a seq like any
  EXPECT_EQ(q.offer(0, 3), InOrder<int>::Offer::kNew);
  EXPECT_EQ(drain(q), (std::vector<int>{3}));
  EXPECT_EQ(q.next(), 1);
}

}  // namespace
}  // namespace fralab
