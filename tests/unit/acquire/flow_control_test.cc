// The acquisition's flow control (acquire/flow_control.h), on a fake clock: cumulative
// acknowledgements per stream, retransmission of exactly what a consumer lacks after the wait
// (doubling without progress, reset by progress), and a stall message that tells a silent
// consumer from one whose datagrams are lost.
#include "fralab/acquire/flow_control.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fralab/core/error.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;

constexpr double kWait = 0.2;  // FlowOptions::retransmit_after_s set below

FlowControl lab() {
  FlowOptions o;
  o.retransmit_after_s = kWait;
  o.retransmit_max_s = 0.8;
  o.stall_timeout_s = 10;
  return FlowControl({"analyze-a", "recorder"}, o);  // "plant" is added
}

TEST(FlowControl, AcknowledgementsArePerStreamCumulativeAndNameTheSlowest) {
  FlowControl f = lab();
  std::string who;
  EXPECT_FALSE(f.all_ready(&who));
  EXPECT_EQ(f.acked(Stream::kTape, &who), -2);  // never heard
  for (const char* c : {"plant", "analyze-a", "recorder"}) f.on_ack(c, "ready", -1, 0);
  EXPECT_TRUE(f.all_ready(&who));
  EXPECT_EQ(f.acked(Stream::kTape), -1);  // ready, nothing held yet
  f.on_ack("plant", "command", 5, 1);
  f.on_ack("analyze-a", "tape", 4, 1);
  f.on_ack("recorder", "tape", 3, 1);
  f.on_ack("recorder", "tape", 2, 1);  // a late duplicate never moves a consumer back
  f.on_ack("stranger", "tape", 0, 1);  // not a consumer of this run: ignored
  EXPECT_EQ(f.acked(Stream::kCommand), 5);
  EXPECT_EQ(f.acked(Stream::kTape, &who), 3);
  EXPECT_EQ(who, "recorder");
  EXPECT_EQ(f.available(Stream::kTape), 5);  // the plant made tape blocks up to its command ack
  EXPECT_EQ(stream_from_string("status"), Stream::kStatus);
  EXPECT_EQ(stream_from_string("ready"), std::nullopt);
}

// A free-running plant makes tape on its own clock: what exists is what the plant was seen to make,
// and a consumer lacking it is served again, whatever the plant acknowledged of the commands.
TEST(FlowControl, FreeRunningTapeIsWhatThePlantMadeNotWhatItAcknowledged) {
  FlowControl f = lab();
  f.tape_on_plant_clock();
  for (const char* c : {"plant", "analyze-a", "recorder"}) f.on_ack(c, "ready", -1, 0);
  f.on_ack("plant", "command", 20, 0);  // commands buffered far ahead
  f.published(Stream::kTape, 7);        // tape blocks 0..7 made so far
  EXPECT_EQ(f.available(Stream::kTape), 7);
  f.on_ack("analyze-a", "tape", 7, 0);
  f.on_ack("recorder", "tape", 5, 0);
  EXPECT_FALSE(f.due(Stream::kTape, 0.1));
  const auto r = f.due(Stream::kTape, 0.1 + kWait);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->from, 6);
  EXPECT_EQ(r->to, 7);  // not 20
}

TEST(FlowControl, RetransmitsWhatIsMissingAfterTheWaitDoublingUntilProgress) {
  FlowControl f = lab();
  for (const char* c : {"plant", "analyze-a", "recorder"}) f.on_ack(c, "ready", -1, 0);
  for (int b = 0; b <= 3; ++b) f.published(Stream::kCommand, b);
  f.on_ack("plant", "command", 1, 0.0);  // commands 2 and 3 lost on the way to the plant
  EXPECT_FALSE(f.due(Stream::kCommand, 0.0));
  EXPECT_FALSE(f.due(Stream::kCommand, 0.19));
  auto r = f.due(Stream::kCommand, 0.21);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->from, 2);
  EXPECT_EQ(r->to, 3);
  EXPECT_FALSE(f.due(Stream::kCommand, 0.21 + 2 * kWait - 0.01));  // the wait doubled
  EXPECT_TRUE(f.due(Stream::kCommand, 0.21 + 2 * kWait + 0.01));
  f.on_ack("plant", "command", 3, 1.0);  // progress: caught up
  EXPECT_FALSE(f.due(Stream::kCommand, 1.0));
  f.published(Stream::kCommand, 4);
  EXPECT_FALSE(f.due(Stream::kCommand, 1.0 + kWait - 0.01));  // the wait is back to its start
  EXPECT_TRUE(f.due(Stream::kCommand, 1.0 + kWait + 0.01));
  EXPECT_EQ(f.retransmissions(), 3);
  EXPECT_EQ(f.items_retransmitted(), 2 + 2 + 1);

  // A tape block the recorder lacks is asked of the plant up to what the plant has made.
  f.on_ack("analyze-a", "tape", 4, 1.0);
  f.on_ack("recorder", "tape", 2, 1.0);
  f.on_ack("plant", "command", 4, 1.0);
  EXPECT_FALSE(f.due(Stream::kTape, 1.0));
  r = f.due(Stream::kTape, 1.0 + kWait + 0.01);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->from, 3);
  EXPECT_EQ(r->to, 4);
}

TEST(FlowControl, AStallTellsASilentConsumerFromOneThatLosesDatagrams) {
  FlowControl f = lab();
  for (const char* c : {"plant", "analyze-a", "recorder"}) f.on_ack(c, "ready", -1, 0);
  f.published(Stream::kStatus, 0);
  f.published(Stream::kStatus, 1);
  f.on_ack("recorder", "status", 1, 0);
  f.on_ack("analyze-a", "status", 0, 0);
  EXPECT_FALSE(f.due(Stream::kStatus, 0));
  EXPECT_EQ(f.stalled(Stream::kStatus, 9.9), "");
  // The analyser keeps answering (it acknowledges status 0 again on each copy) but never gets 1.
  for (double t = 0.5; t < 12; t += 0.5) {
    f.due(Stream::kStatus, t);
    f.on_ack("analyze-a", "status", 0, t);
  }
  const std::string lossy = f.stalled(Stream::kStatus, 12);
  EXPECT_THAT(lossy, HasSubstr("consumer \"analyze-a\" holds status events up to 0"));
  EXPECT_THAT(lossy, HasSubstr("does not receive them"));

  FlowControl g = lab();
  for (const char* c : {"plant", "analyze-a", "recorder"}) g.on_ack(c, "ready", -1, 0);
  g.published(Stream::kCommand, 0);
  g.due(Stream::kCommand, 0);
  for (double t = 0.5; t < 12; t += 0.5) g.due(Stream::kCommand, t);  // the plant says nothing
  const std::string silent = g.stalled(Stream::kCommand, 12);
  EXPECT_THAT(silent, HasSubstr("consumer \"plant\" holds command blocks up to -1"));
  EXPECT_THAT(silent, HasSubstr("hung, stopped or dead?"));
  EXPECT_THAT(silent, HasSubstr("retransmitted"));
}

TEST(FlowControl, OptionsAreChecked) {
  FlowOptions o;
  o.retransmit_after_s = 0;
  EXPECT_THROW(o.validate(), InputError);
  o = {};
  o.stall_timeout_s = 1;
  o.retransmit_max_s = 2;
  EXPECT_THROW(FlowControl({}, o), InputError);
}

}  // namespace
}  // namespace fralab
