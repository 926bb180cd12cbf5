// The analyser's LCM edge (analyze/lcm/tape_analysis.h): records decoded from encoded messages give
// the same points as the library fed directly (live = replay = offline rests on this), records of
// another run are ignored, and a wrong message type is refused naming the channel.
#include "tape_analysis.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/tape_file.h"
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

// A lossy network with retransmission: blocks and events arrive late, twice, and out of order
// (as the recorder writes them to the tape). The feeder puts them back in sequence: the same
// numbers bit for bit, and a block that never arrives makes invalid points naming the gap.
TEST(TapeAnalysis, ReorderedAndDuplicatedRecordsGiveTheInOrderNumbers) {
  const auto r = run();
  PairAnalyzer direct("u:y");
  for (const auto& e : r.events) direct.on_status(e);
  for (const auto& blk : r.blocks) direct.on_block(blk);
  direct.flush();
  std::vector<std::pair<std::string, std::vector<uint8_t>>> recs;
  for (const auto& e : r.events) recs.push_back({kStatusChannel, encode(to_status_msg(e))});
  for (const auto& blk : r.blocks) recs.push_back({kTapeChannel, encode(to_tape_msg(blk))});
  // Every 7th record is "lost" and retransmitted 5 records later, every 5th arrives twice.
  std::vector<std::pair<std::string, std::vector<uint8_t>>> wire;
  for (size_t i = 0; i < recs.size(); ++i) {
    if (i % 7 != 3) wire.push_back(recs[i]);
    if (i % 5 == 0) wire.push_back(recs[i]);
    if (i >= 5 && (i - 5) % 7 == 3) wire.push_back(recs[i - 5]);
  }
  for (size_t i = recs.size() - 5; i < recs.size(); ++i)
    if (i % 7 == 3) wire.push_back(recs[i]);
  AnalyzerOptions no_slack;  // the analyser alone would give up a window at once
  no_slack.reorder_slack_samples = 1;
  TapeFeeder feeder({"u:y"}, no_slack);
  int dups = 0;
  for (const auto& [ch, b] : wire) dups += feeder.feed(ch, b.data(), int(b.size())).duplicate;
  EXPECT_GT(dups, 10);
  EXPECT_EQ(feeder.tape_delivered(), r.blocks.back().seq);
  EXPECT_EQ(feeder.flush(), 0);  // nothing given up
  const Frd a = direct.frd(), f = feeder.analyzers()[0]->frd();
  ASSERT_EQ(a.points.size(), f.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_TRUE(f.points[i].valid);
    EXPECT_EQ(a.points[i].mag, f.points[i].mag);
    EXPECT_EQ(a.points[i].phase_deg, f.points[i].phase_deg);
  }

  // Tape block 40 never arrives: held blocks are released at the end, the window it cuts is
  // invalid and says where the gap is.
  TapeFeeder lossy({"u:y"}, {});
  for (const auto& [ch, b] : recs) {
    if (ch == kTapeChannel && from_msg([&] {
                                tape_block_t m;
                                m.decode(b.data(), 0, int(b.size()));
                                return m;
                              }())
                                      .seq == 40)
      continue;
    lossy.feed(ch, b.data(), int(b.size()));
  }
  EXPECT_EQ(lossy.tape_delivered(), 39);
  EXPECT_EQ(lossy.flush(), 1);
  int invalid = 0;
  for (const auto& p : lossy.analyzers()[0]->frd().points) {
    if (!p.valid) {
      ++invalid;
      EXPECT_THAT(p.note, HasSubstr("incomplete window"));
    }
  }
  EXPECT_EQ(invalid, 1);

  // Tape block 40 arrives with one byte flipped (silent corruption): refused, the window it cuts
  // is invalid and names it.
  TapeFeeder corrupt({"u:y"}, {});
  for (auto [ch, b] : recs) {
    if (ch == kTapeChannel) {
      tape_block_t m;
      m.decode(b.data(), 0, int(b.size()));
      if (m.seq == 40) b[b.size() / 2] ^= 0x01;
    }
    corrupt.feed(ch, b.data(), int(b.size()));
  }
  corrupt.flush();
  EXPECT_THAT(corrupt.corrupt(), ::testing::ElementsAre(40));
  invalid = 0;
  for (const auto& p : corrupt.analyzers()[0]->frd().points) {
    if (p.valid) continue;
    ++invalid;
    EXPECT_THAT(p.note, HasSubstr("tape block seq 40 failed its checksum"));
  }
  EXPECT_EQ(invalid, 1);
}

// A block whose seq is the largest int64_t (only corruption writes it; it overflowed the in-order
// stream, found by the tape fuzzer) is refused as corrupt; the curve is the one without it.
TEST(TapeAnalysis, ABlockAtTheLargestSeqIsCorruptAndChangesNothing) {
  const auto r = run();
  TapeFeeder clean({"u:y"}, {}), fed({"u:y"}, {});
  for (auto* f : {&clean, &fed}) {
    for (const auto& e : r.events) {
      const auto b = encode(to_status_msg(e));
      f->feed(kStatusChannel, b.data(), int(b.size()));
    }
    if (f == &fed) {
      Block bad = r.blocks[3];
      bad.seq = std::numeric_limits<int64_t>::max();
      const auto b = encode(to_tape_msg(bad));
      EXPECT_EQ(f->feed(kTapeChannel, b.data(), int(b.size())).kind, TapeFeeder::Kind::kTape);
    }
    for (const auto& blk : r.blocks) {
      const auto b = encode(to_tape_msg(blk));
      f->feed(kTapeChannel, b.data(), int(b.size()));
    }
    f->flush();
  }
  EXPECT_THAT(fed.corrupt(), ::testing::ElementsAre(std::numeric_limits<int64_t>::max()));
  EXPECT_TRUE(clean.corrupt().empty());
  const Frd a = clean.analyzers()[0]->frd(), f = fed.analyzers()[0]->frd();
  ASSERT_EQ(a.points.size(), f.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_TRUE(f.points[i].valid) << i;
    EXPECT_EQ(a.points[i].mag, f.points[i].mag);
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
