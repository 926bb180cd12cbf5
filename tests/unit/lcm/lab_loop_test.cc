// The lab's loops in one process over memq:// (no network): the acquisition, the plant and an
// analyser and the identifier as the executables run them (acquire/lcm, plant/lcm, analyze/lcm,
// identify/lcm), dispatched in the caller's thread. Their curves must equal, bit for bit, the same
// run generated without LCM (tests/util simulate_tape, the same library code), and a consumer that
// never says ready is named.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>

#include "acquisition_node.h"
#include "analyzer_node.h"
#include "fralab/acquire/acquisition.h"
#include "fralab/lcm/channels.h"
#include "fralab/lcm/codec.h"
#include "fralab/lcm/tape_file.h"
#include "identifier_node.h"
#include "plant_node.h"
#include "recorder_node.h"
#include "test_util.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;

// What travels on FRALAB_FRD, pair by pair: the points of each growing curve's message, and the
// finished curves.
struct FrdTraffic {
  std::map<std::string, std::vector<std::vector<double>>> growing;  // per message, its points' w
  std::map<std::string, int> complete;                              // finished copies
  void on_frd(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    const Frd f = from_frd_msg(decode_checked<frd_t>(rb, ch));
    const bool done = decode_checked<frd_t>(rb, ch).complete;
    if (done) {
      ++complete[f.pair];
      return;
    }
    std::vector<double>& ws = growing[f.pair].emplace_back();
    for (const FrdPoint& p : f.points) ws.push_back(p.w);
  }
};

// Dispatches what is queued on a memq:// bus (handlers may publish more).
void drain(lcm::LCM& bus) {
  while (bus.handleTimeout(0) > 0) {
  }
}

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
  o.block = block_samples(m, o);
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
  IdentifierNode identifier(bus, "memq-run");
  FrdTraffic traffic;
  bus.subscribe(kFrdChannel, &FrdTraffic::on_frd, &traffic);
  AcquisitionLoopOptions lo;
  lo.run_id = "memq-run";
  lo.consumers = {"analyze", "recorder"};
  lo.acquire = o;
  AcquisitionNode acquisition(bus, bus, *camp, lo);
  plant.announce_ready();
  analyser.announce_ready();
  recorder.announce_ready();
  const AcquisitionSummary summary = acquisition.run();
  EXPECT_EQ(summary.samples, camp->total_samples());
  EXPECT_EQ(plant.error(), "");
  EXPECT_EQ(analyser.error(), "");
  EXPECT_TRUE(plant.done());
  ASSERT_TRUE(analyser.done());
  const std::vector<Frd> live = analyser.finish();
  EXPECT_EQ(recorder.error(), "");
  // The hand-over: the identifier takes each finished curve and acknowledges it.
  identifier.announce_ready();
  drain(bus);
  EXPECT_EQ(identifier.error(), "");
  EXPECT_TRUE(analyser.identifier_heard());
  EXPECT_TRUE(analyser.curves_taken());
  ASSERT_EQ(identifier.curves().size(), live.size());
  for (const Frd& f : live) {
    const Frd& got = identifier.curves().at(f.pair);
    ASSERT_EQ(got.points.size(), f.points.size()) << f.pair;
    for (size_t i = 0; i < f.points.size(); ++i)
      EXPECT_EQ(got.points[i].mag, f.points[i].mag) << f.pair << " " << i;
    // While growing, each message carried the points new since the last one: each point once,
    // never the curve again (the whole curve each time would carry 1 + 2 + ... + n points).
    std::set<double> seen;
    size_t carried = 0;
    for (const auto& ws : traffic.growing[f.pair]) {
      EXPECT_FALSE(ws.empty()) << f.pair;
      for (double w : ws) EXPECT_TRUE(seen.insert(w).second) << f.pair << " w " << w << " again";
      carried += ws.size();
    }
    EXPECT_LE(carried, f.points.size()) << f.pair;
    EXPECT_GE(carried, f.points.size() - 1) << f.pair;  // the last may come with the whole curve
    EXPECT_GE(traffic.complete[f.pair], 1) << f.pair;
  }
  // The identifier's fits: one per pair, written and published on FRALAB_TF.
  struct TfHeard {
    std::set<std::string> pairs;
    void on_tf(const lcm::ReceiveBuffer* rb, const std::string& ch) {
      pairs.insert(decode_checked<tf_t>(rb, ch).pair);
    }
  } tf_heard;
  bus.subscribe(kTfChannel, &TfHeard::on_tf, &tf_heard);
  const std::string fit_dir =
      (std::filesystem::temp_directory_path() / "lab_loop_test_identify").string();
  const std::vector<FitResult> fits = identifier.fit_and_publish(FitOptions{}, fit_dir, "memq");
  drain(bus);
  ASSERT_EQ(fits.size(), 2u);
  EXPECT_EQ(tf_heard.pairs, (std::set<std::string>{"u:y", "u_u:u"}));
  EXPECT_TRUE(std::filesystem::exists(fit_dir + "/tf/u_y.json"));
  EXPECT_TRUE(std::filesystem::exists(fit_dir + "/transfer_matrix.json"));
  // The path's fit follows the plant's own path (2 / (1 + s/5), 4 ms delay) as closely as the
  // data allow: within 3 sigma of each point plus 3 % (the sensor noise, 1 % of full scale,
  // drowns the top decade; six points leave the fit a choice between the delay and a second
  // pole, so it is judged by its response, not its roots).
  const FitResult& path = fits[0];
  const Tf& truth = m.paths.at(0).tf;
  for (const FrdPoint& p : identifier.curves().at("u:y").points) {
    ASSERT_GT(p.sigma, 0.0);
    EXPECT_LT(std::abs(path.tf.at(p.w) - truth.at(p.w)),
              3 * p.sigma + 0.03 * std::abs(truth.at(p.w)))
        << "w " << p.w << " sigma " << p.sigma << ": " << path.message;
  }
  std::filesystem::remove_all(fit_dir);
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
  o.block = block_samples(m, o);
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
  const AcquisitionSummary summary = acquisition.run();
  EXPECT_EQ(plant.error(), "");
  ASSERT_TRUE(analyser.done());
  const std::vector<Frd> live = analyser.finish();

  const auto offline = fralab::testing::simulate_campaign(m, o, true, 3);
  EXPECT_EQ(summary.samples, int64_t(offline.blocks.size()) * o.block);
  EXPECT_EQ(summary.adaptive, adaptive_steps_json(offline.adaptive));
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
  o.block = block_samples(m, o);
  const auto camp = make_campaign(m, o, "r");
  lcm::LCM bus("memq://");
  ASSERT_TRUE(bus.good());
  PlantNode plant(bus, bus, LockstepPlant(m, {}, "r"));
  AcquisitionLoopOptions lo;
  lo.run_id = "r";
  lo.consumers = {"analyze-silent"};
  lo.acquire = o;
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

// fralab-plant's loop refuses a free-running clock it cannot keep: no speed, no samples per
// tick, a negative jitter; a lockstep plant takes no clock and is not checked for one.
TEST(LabLoop, ThePlantsFreeRunningClockIsChecked) {
  ServeOptions o;
  o.free_running = true;
  EXPECT_NO_THROW(o.validate());
  for (auto bad : {+[](ServeOptions& x) { x.speed = 0; }, +[](ServeOptions& x) { x.tick = 0; },
                   +[](ServeOptions& x) { x.jitter_ms = -1; }}) {
    ServeOptions b = o;
    bad(b);
    EXPECT_THROW(b.validate(), InputError);
    b.free_running = false;
    EXPECT_NO_THROW(b.validate());
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
