// Where a resumed run starts again (lab/resume.h), from tapes made by the same library code as the
// lab's processes (tests/util simulate_campaign): a whole tape is complete; a tape that lost a
// block, or a status event in a damaged stretch while the blocks around it are there, starts again
// at the step that needs it.
#include "fralab/lab/resume.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "fralab/lcm/tape_file.h"
#include "fralab/plant/embedded_models.h"
#include "test_util.h"

using namespace fralab;
using fralab::testing::simulate_campaign;

namespace {

struct Fixture {
  Model model = load_model_or_embedded("j85_95");
  AcquireOptions o;
  fralab::testing::TapeRun run;
  std::string tape = (std::filesystem::temp_directory_path() /
                      ("fralab_resume_" + std::to_string(getpid()) + ".lcmlog"))
                         .string();
  Fixture() {
    o.inputs = "Wf";
    o.band = "0.5:20";
    o.points_per_decade = 2;
    o.min_cycles = 2;
    o.min_integrate_s = 0;
    o.block = 100;  // blocks of 0.1 s: several to each step, so a lost one leaves others whole
    run = simulate_campaign(model, o, false, 1);
  }
  ~Fixture() { std::filesystem::remove(tape); }
  ResumePoint plan(const std::vector<Block>& blocks, const std::vector<StatusEvent>& events) {
    write_tape_file(tape, blocks, events);
    return plan_resume(tape, "test", *make_campaign(model, o, "test"), o.block);
  }
};

}  // namespace

TEST(Resume, AWholeTapeIsComplete) {
  Fixture f;
  const ResumePoint r = f.plan(f.run.blocks, f.run.events);
  EXPECT_TRUE(r.complete);
  EXPECT_EQ(r.blocks_on_tape, int64_t(f.run.blocks.size()));
}

TEST(Resume, ALostStatusEventMakesItsStepMeasuredAgain) {
  Fixture f;
  // The settle event of the third step (seq > 0) lost, every block there.
  size_t lost = 0;
  for (size_t i = 0; i < f.run.events.size(); ++i)
    if (f.run.events[i].state == RunState::kSettle && f.run.events[i].step == 2) lost = i;
  ASSERT_GT(lost, 0u);
  std::vector<StatusEvent> events = f.run.events;
  events.erase(events.begin() + long(lost));
  const ResumePoint r = f.plan(f.run.blocks, events);
  EXPECT_FALSE(r.complete);
  EXPECT_EQ(r.first_step, 2);
  EXPECT_EQ(r.first_status, int64_t(lost));  // the lost event is sent again
  EXPECT_EQ(r.first_block, f.run.events[lost].sample / f.o.block);
}

TEST(Resume, ALostBlockMakesItsStepMeasuredAgain) {
  Fixture f;
  const StatusEvent& settle = *std::find_if(
      f.run.events.begin(), f.run.events.end(),
      [](const StatusEvent& e) { return e.state == RunState::kSettle && e.step == 1; });
  const int64_t inside = settle.sample / f.o.block + 2;  // a block of the second step
  std::vector<Block> blocks = f.run.blocks;
  blocks.erase(blocks.begin() + long(inside));
  const ResumePoint r = f.plan(blocks, f.run.events);
  EXPECT_FALSE(r.complete);
  EXPECT_EQ(r.blocks_on_tape, inside);
  EXPECT_EQ(r.first_step, 1);
  EXPECT_EQ(r.first_block, settle.sample / f.o.block);
}
