// The analyser's LCM edge (analyze/lcm/tape_analysis.h): records decoded from encoded messages give
// the same points as the library fed directly (live = replay = offline rests on this), records of
// another run are ignored, and a wrong message type is refused naming the channel.
#include "tape_analysis.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_util.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> buf(m.getEncodedSize());
  m.encode(buf.data(), 0, int(buf.size()));
  return buf;
}

fralab::testing::TapeRun run() {
  SteppedSineOptions so;
  so.f_lo_hz = 1;
  so.f_hi_hz = 10;
  so.points_per_decade = 2;
  so.min_integrate_s = 1;
  Tf t;
  t.gain = 2;
  t.poles = {Root::Real(-5)};
  return fralab::testing::simulate_tape(fralab::testing::siso_model(t), {"u"}, so, false, 1);
}

TEST(TapeAnalysis, DecodedRecordsGiveTheLibrarysPointsExactly) {
  const auto r = run();
  PairAnalyzer direct("u:y");
  TapeFeeder feeder({"u:y"}, {});
  for (const auto& e : r.events) {
    direct.on_status(e);
    const auto b = encode(to_status_msg(e));
    feeder.feed(kStatusChannel, b.data(), int(b.size()));
  }
  for (const auto& blk : r.blocks) {
    direct.on_block(blk);
    const auto b = encode(to_tape_msg(blk));
    EXPECT_EQ(feeder.feed(kTapeChannel, b.data(), int(b.size())).kind, TapeFeeder::Kind::kTape);
    EXPECT_EQ(feeder.tape_delivered(), blk.seq);
  }
  direct.flush();
  feeder.flush();
  EXPECT_TRUE(feeder.all_done());
  const Frd a = direct.frd(), f = feeder.analyzers()[0]->frd();
  ASSERT_EQ(a.points.size(), f.points.size());
  ASSERT_GE(a.points.size(), 2u);
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].mag, f.points[i].mag);  // bit for bit
    EXPECT_EQ(a.points[i].phase_deg, f.points[i].phase_deg);
  }
}

TEST(TapeAnalysis, AnotherRunIsIgnoredAndAWrongTypeIsNamed) {
  const auto r = run();
  TapeFeeder feeder({"u:y"}, {}, "test");
  Block other = r.blocks[0];
  other.run_id = "someone-else";
  const auto b = encode(to_tape_msg(other));
  EXPECT_EQ(feeder.feed(kTapeChannel, b.data(), int(b.size())).kind, TapeFeeder::Kind::kOther);
  const auto s = encode(to_status_msg(r.events[0]));
  try {
    feeder.feed(kTapeChannel, s.data(), int(s.size()));
    ADD_FAILURE() << "a status message was taken for a tape block";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("channel FRALAB_TAPE"));
    EXPECT_THAT(e.what(), HasSubstr("is not a fralab.tape_block_t"));
  }
  EXPECT_THROW(TapeFeeder({}, {}), InputError);
}

}  // namespace
}  // namespace fralab
