// The progress line (lab/progress.h): from a run's status events, the input, step, frequency,
// engine time done and left, wall time left and blocks re-sent, on known events.
#include "fralab/lab/progress.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fralab {
namespace {

StatusEvent event(RunState s, int64_t sample, int step, double f) {
  StatusEvent e;
  e.state = s;
  e.sample = sample;
  e.sample_rate_hz = 1000;
  e.step = step;
  e.n_steps = 33;
  e.frequency_hz = f;
  e.inputs = {"Wf", "A8"};
  e.amplitudes = {0, 0.5};
  return e;
}

TEST(Progress, TheLineSaysWhereTheRunStandsAndWhatIsLeft) {
  ProgressLine p;
  EXPECT_EQ(p.line(0), "");
  StatusEvent start = event(RunState::kStart, 0, 0, 0.1);
  start.n_samples = 1000000;  // 1000 s of engine time
  p.on_status(start);
  p.on_status(event(RunState::kIntegrate, 250000, 11, 2.51));
  p.on_resent(2);
  p.on_resent(1);
  // 250 s of 1000 done in 10 s of wall time: 750 s left, 30 s of wall time left.
  EXPECT_EQ(p.line(10),
            "A8   step 12/33  2.51 Hz  engine 250/1000 s (750 s left)  wall 0:30 left"
            "  re-sent 3");
  StatusEvent both = event(RunState::kSettle, 500000, 12, 3.1);
  both.amplitudes = {1, 0.5};
  p.on_status(both);
  EXPECT_THAT(p.line(20), ::testing::StartsWith("all  step 13/33"));
  EXPECT_THAT(p.line(20), ::testing::HasSubstr("wall 0:20 left"));
  p.on_status(event(RunState::kDone, 1000000, 33, 0));
  EXPECT_THAT(p.line(40), ::testing::HasSubstr("engine 1000/1000 s (0 s left)  wall 0:00 left"));
}

}  // namespace
}  // namespace fralab
