// The analysers' shared samples (analyze/sample_store.h): each kept channel stored once from its
// blocks, NaN where no block brought it, a block's second copy refused, the front released only
// when every reader is past it; and pair analysers sharing one store give, point for point, the
// numbers each gives with a store of its own (a grouped analyser's curves are the per-pair ones).
#include "fralab/analyze/sample_store.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "fralab/analyze/pair_analyzer.h"
#include "fralab/plant/embedded_models.h"
#include "test_util.h"

namespace fralab {
namespace {

Block block(int64_t seq, int64_t start, int n) {
  Block b;
  b.seq = seq;
  b.start_sample = start;
  b.n_samples = n;
  b.sample_rate_hz = 1000;
  b.channels = {"a", "b", "c"};
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < n; ++k) b.samples.push_back(100.0 * c + double(start + k));
  return b;
}

TEST(SampleStore, KeepsEachChannelOnceFromItsBlocks) {
  SampleStore s;
  s.keep("a");
  s.keep("c");
  EXPECT_TRUE(s.add(block(0, 0, 10), 5000));
  EXPECT_FALSE(s.add(block(0, 0, 10), 5000));  // the same seq again
  EXPECT_TRUE(s.add(block(2, 20, 10), 5000));  // seq 1 (samples 10-19) not here
  EXPECT_EQ(s.base(), 0);
  EXPECT_EQ(s.end(), 30);
  ASSERT_NE(s.channel("a"), nullptr);
  EXPECT_EQ(s.channel("b"), nullptr);  // not kept
  EXPECT_DOUBLE_EQ((*s.channel("a"))[7], 7.0);
  EXPECT_DOUBLE_EQ((*s.channel("c"))[25], 225.0);
  EXPECT_TRUE(s.have(9));
  EXPECT_FALSE(s.have(10));
  EXPECT_TRUE(std::isnan((*s.channel("a"))[15]));
  s.keep("b");  // kept from now on: NaN before
  EXPECT_TRUE(std::isnan((*s.channel("b"))[3]));
  EXPECT_TRUE(s.add(block(1, 10, 10), 5000));
  EXPECT_DOUBLE_EQ((*s.channel("b"))[12], 112.0);
  EXPECT_TRUE(s.have(15));
}

TEST(SampleStore, AFirstBlockLateInTheRunIsKeptFromTheSlackBeforeIt) {
  SampleStore s;
  s.keep("a");
  s.add(block(70, 700000, 100), 5000);
  EXPECT_EQ(s.base(), 695000);
  EXPECT_FALSE(s.have(699999));
  EXPECT_TRUE(s.have(700000));
}

TEST(SampleStore, ReleasesOnlyWhatEveryReaderIsPast) {
  SampleStore s;
  s.keep("a");
  const int r0 = s.add_reader(), r1 = s.add_reader();
  for (int64_t q = 0; q < 300; ++q) s.add(block(q, q * 1000, 1000), 5000);
  s.release(r0, 200000);
  EXPECT_EQ(s.base(), 0);  // r1 has not said
  s.release(r1, 100000);
  EXPECT_EQ(s.base(), 0);  // 100000 could go, but 200000 would stay: not yet
  s.release(r1, 250000);
  EXPECT_EQ(s.base(), 200000);  // the lower of the two
  EXPECT_DOUBLE_EQ((*s.channel("a"))[0], 200000.0);
  EXPECT_TRUE(s.have(299999));
  EXPECT_FALSE(s.have(199999));
  s.remove_reader(r0);
  s.release(r1, 260000);
  EXPECT_EQ(s.base(), 200000);  // 60000: under 65536, kept
}

// A J85 two-input orthogonal multisine with noise, long enough for the store to drop its front
// (more than 2 x 65536 samples): the pairs of both inputs, one store shared as a grouped analyser
// shares it (every block to every pair in turn), give each pair's own-store points exactly.
TEST(SampleStore, PairsSharingAStoreGiveTheirOwnNumbers) {
  const Model m = load_model_or_embedded("j85_95");
  SteppedSineOptions so;
  so.f_lo_hz = 0.1;
  so.f_hi_hz = 20;
  so.points_per_decade = 3;
  so.slowest_time_constant_s = 1.0;
  const auto run = fralab::testing::simulate_tape(m, {"Wf", "A8"}, so, true, 4, 500, 2.0,
                                                  "multisine:orthogonal");
  const int64_t samples = run.blocks.back().start_sample + run.blocks.back().n_samples;
  ASSERT_GT(samples, 2 * 65536);
  const std::vector<std::string> pairs = {"Wf:N", "Wf:P3", "A8:N", "A8:T5", "u_Wf:Wf", "u_A8:N"};
  const std::vector<Frd> own = fralab::testing::analyse_run(run, pairs);

  const auto store = std::make_shared<SampleStore>();
  std::vector<std::unique_ptr<PairAnalyzer>> shared;
  for (const auto& p : pairs)
    shared.push_back(std::make_unique<PairAnalyzer>(p, AnalyzerOptions{}, store));
  for (const auto& e : run.events)
    for (auto& a : shared) a->on_status(e);
  for (const auto& b : run.blocks)
    for (auto& a : shared) a->on_block(b);
  EXPECT_GT(store->base(), 0) << "the front was never dropped";
  for (size_t i = 0; i < pairs.size(); ++i) {
    shared[i]->flush();
    const Frd f = shared[i]->frd();
    ASSERT_EQ(f.points.size(), own[i].points.size()) << pairs[i];
    int valid = 0;
    for (size_t k = 0; k < f.points.size(); ++k) {
      EXPECT_EQ(f.points[k].valid, own[i].points[k].valid) << pairs[i] << " " << k;
      EXPECT_EQ(f.points[k].value(), own[i].points[k].value()) << pairs[i] << " " << k;
      EXPECT_EQ(f.points[k].sigma, own[i].points[k].sigma) << pairs[i] << " " << k;
      valid += f.points[k].valid;
    }
    EXPECT_GT(valid, 5) << pairs[i];
  }
}

}  // namespace
}  // namespace fralab
