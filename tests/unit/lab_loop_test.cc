// The lab's loops in one process over memq:// (no network): the acquisition, the plant and an
// analyser as the executables run them (acquire/lcm, plant/lcm, analyze/lcm), dispatched in the
// caller's thread. Their curves must equal, bit for bit, the same run generated without LCM
// (tests/util simulate_tape, the same library code), and a consumer that never says ready is named.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "acquisition_node.h"
#include "analyzer_node.h"
#include "fralab/acquire/acquisition.h"
#include "plant_node.h"
#include "recorder_node.h"
#include "test_util.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;

Model plant_model() {
  Tf path, act;
  path.gain = 2.0;
  path.poles = {Root::Real(-5.0)};
  path.delay_s = 0.004;
  act.poles = {Root::Real(-40.0)};
  return fralab::testing::siso_model(path, &act, nullptr, 0.01);
}

SteppedSineOptions schedule() {
  SteppedSineOptions so;
  so.f_lo_hz = 0.5;
  so.f_hi_hz = 20;
  so.points_per_decade = 3;
  so.min_integrate_s = 1.0;
  so.slowest_time_constant_s = 0.5;
  return so;
}

TEST(LabLoop, AcquisitionPlantAndAnalyserOverMemqGiveTheOfflineNumbers) {
  const Model m = plant_model();
  const SteppedSineOptions so = schedule();
  AcquireOptions o;
  o.band = "0.5:20";
  o.points_per_decade = so.points_per_decade;
  o.min_integrate_s = so.min_integrate_s;
  o.slowest_time_constant_s = so.slowest_time_constant_s;
  o.amplitude_pct = 2.0;
  const auto camp = make_campaign(m, o, "memq-run");

  lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  SimulatorOptions sim;
  sim.seed = 3;
  PlantNode plant(bus, bus, LockstepPlant(m, sim, "memq-run"));
  AnalyzerNode analyser(bus, bus, {"u:y", "u_u:u"}, {}, "analyze", "memq-run");
  const std::string tape =
      (std::filesystem::temp_directory_path() / "lab_loop_test.lcmlog").string();
  RecorderNode recorder(bus, bus, tape, "memq-run");
  AcquisitionLoopOptions lo;
  lo.run_id = "memq-run";
  lo.consumers = {"analyze", "recorder"};
  AcquisitionNode acquisition(bus, bus, *camp, lo);
  plant.announce_ready();
  analyser.announce_ready();
  recorder.announce_ready();
  const Json summary = acquisition.run();
  EXPECT_EQ(summary["samples"], camp->total_samples());
  EXPECT_EQ(plant.error(), "");
  EXPECT_EQ(analyser.error(), "");
  EXPECT_TRUE(plant.done());
  ASSERT_TRUE(analyser.done());
  const std::vector<Frd> live = analyser.finish();
  EXPECT_EQ(recorder.error(), "");
  // The recorder's tape, read back, gives the live numbers too (tape = live).
  const auto from_tape = analyze_tape_file(tape, {"u:y", "u_u:u"}, {});
  ASSERT_EQ(from_tape.size(), live.size());
  for (size_t k = 0; k < live.size(); ++k) {
    ASSERT_EQ(from_tape[k].points.size(), live[k].points.size());
    for (size_t i = 0; i < live[k].points.size(); ++i)
      EXPECT_EQ(from_tape[k].points[i].mag, live[k].points[i].mag);
  }

  const auto offline = fralab::testing::simulate_tape(m, {"u"}, so, true, 3);
  for (const Frd& f : live) {
    PairAnalyzer a(f.pair);
    for (const auto& e : offline.events) a.on_status(e);
    for (const auto& b : offline.blocks) a.on_block(b);
    a.flush();
    const Frd want = a.frd();
    ASSERT_EQ(f.points.size(), want.points.size()) << f.pair;
    ASSERT_EQ(f.points.size(), 6u) << f.pair;  // 0.5-20 Hz at 3 per decade
    for (size_t i = 0; i < want.points.size(); ++i) {
      EXPECT_TRUE(f.points[i].valid) << f.points[i].note;
      EXPECT_EQ(f.points[i].mag, want.points[i].mag) << f.pair << " " << i;  // bit for bit
      EXPECT_EQ(f.points[i].phase_deg, want.points[i].phase_deg) << f.pair << " " << i;
    }
  }
}

// The adaptive stepped sine: the acquisition decides on the tape it watches while the plant and an
// analyser run; the live curves, the decisions and the campaign's length equal, bit for bit, the
// same run decided offline (simulate_campaign, the same AutoIntegrator on the same samples).
TEST(LabLoop, TheAdaptiveAcquisitionDecidesAsTheOfflineRun) {
  Model m = plant_model();
  m.outputs[0].noise_rms = 0.002;
  AcquireOptions o;
  o.band = "0.5:20";
  o.points_per_decade = 5;
  o.min_integrate_s = 4.0;
  o.slowest_time_constant_s = 0.5;
  o.amplitude_pct = 2.0;
  o.adaptive.sigma_target = 0.01;
  const auto camp = make_campaign(m, o, "memq-run");
  const auto integrator = make_auto_integrator(*camp, m, o);
  ASSERT_NE(integrator, nullptr);

  lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  SimulatorOptions sim;
  sim.seed = 3;
  PlantNode plant(bus, bus, LockstepPlant(m, sim, "memq-run"));
  AnalyzerNode analyser(bus, bus, {"u:y", "u_u:u"}, {}, "analyze", "memq-run");
  AcquisitionLoopOptions lo;
  lo.run_id = "memq-run";
  lo.consumers = {"analyze"};
  lo.acquire = o;
  lo.auto_integrator = integrator.get();
  AcquisitionNode acquisition(bus, bus, *camp, lo);
  plant.announce_ready();
  analyser.announce_ready();
  const Json summary = acquisition.run();
  EXPECT_EQ(plant.error(), "");
  ASSERT_TRUE(analyser.done());
  const std::vector<Frd> live = analyser.finish();

  const auto offline = fralab::testing::simulate_campaign(m, o, true, 3);
  EXPECT_EQ(summary["samples"], int64_t(offline.blocks.size()) * o.block);
  EXPECT_EQ(summary["adaptive"], adaptive_steps_json(offline.adaptive));
  const auto want = fralab::testing::analyse_run(offline, {"u:y", "u_u:u"});
  ASSERT_EQ(live.size(), want.size());
  int extended = 0;
  for (size_t k = 0; k < live.size(); ++k) {
    ASSERT_EQ(live[k].points.size(), 9u) << live[k].pair;  // one per step, windows merged
    ASSERT_EQ(live[k].points.size(), want[k].points.size());
    for (size_t i = 0; i < want[k].points.size(); ++i) {
      EXPECT_EQ(live[k].points[i].mag, want[k].points[i].mag) << live[k].pair << " " << i;
      EXPECT_EQ(live[k].points[i].sigma, want[k].points[i].sigma) << live[k].pair << " " << i;
      extended += live[k].points[i].n_cycles > 4;
    }
  }
  EXPECT_GE(extended, 4);  // decisions were taken, not only pilots
}

TEST(LabLoop, AConsumerThatNeverSaysReadyIsNamed) {
  const Model m = plant_model();
  AcquireOptions o;
  o.band = "1:2";
  o.points_per_decade = 1;
  const auto camp = make_campaign(m, o, "r");
  lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  PlantNode plant(bus, bus, LockstepPlant(m, {}, "r"));
  AcquisitionLoopOptions lo;
  lo.run_id = "r";
  lo.consumers = {"analyze-silent"};
  lo.ready_timeout_s = 0.3;
  AcquisitionNode acquisition(bus, bus, *camp, lo);
  plant.announce_ready();
  try {
    acquisition.run();
    ADD_FAILURE() << "the acquisition ran without its consumer";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("consumer \"analyze-silent\" never said ready"));
  }
}

}  // namespace
}  // namespace fralab

namespace fralab {
namespace {

// Two runs sharing a port (Linux hands their datagrams to both): the recorder writes only its own.
TEST(LabLoop, TheRecorderKeepsOnlyItsRunOnASharedPort) {
  lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  const std::string tape =
      (std::filesystem::temp_directory_path() / "lab_loop_shared_port.lcmlog").string();
  {
    RecorderNode recorder(bus, bus, tape, "ours");
    Block b;
    b.run_id = "theirs";
    b.seq = 0;
    b.sample_rate_hz = 1000;
    b.channels = {"y"};
    b.n_samples = 1;
    b.samples = {1.0};
    tape_block_t m = to_tape_msg(b);
    bus.publish(kTapeChannel, &m);
    b.run_id = "ours";
    m = to_tape_msg(b);
    bus.publish(kTapeChannel, &m);
    while (bus.handleTimeout(10) > 0) {
    }
    EXPECT_EQ(recorder.error(), "");
  }
  std::vector<std::string> runs;
  read_tape_file(tape, [&](const TapeEvent& ev) {
    if (ev.channel == kTapeChannel) runs.push_back(*peek_run_id(ev.data, size_t(ev.datalen)));
  });
  EXPECT_THAT(runs, ::testing::ElementsAre("ours"));
}

}  // namespace
}  // namespace fralab
