// The launcher's process plan (lab/process_plan.h): which processes a run of the embedded J85
// starts, in which order, with which arguments and on which host, for a fresh run, a resumed one
// and a multi-host one, without anything being started or written.
#include "fralab/lab/process_plan.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "fralab/acquire/acquire_flags.h"
#include "fralab/core/measurement_chain.h"
#include "fralab/core/text.h"
#include "fralab/plant/embedded_models.h"

namespace fralab {
namespace {

using ::testing::AllOf;
using ::testing::Contains;
using ::testing::ElementsAre;
using ::testing::ElementsAreArray;
using ::testing::IsEmpty;
using ::testing::Not;
using ::testing::SizeIs;

const std::string kUrl = "udpm://239.255.76.67:7667?ttl=0";
const std::string kRun = "run-42";
const std::string kDir = "/no/such/folder/run";

std::string program(const std::string& name) { return "/bin/" + name; }

// The plans below start one analyser process per pair (--analysers pair), whose names say which.
MeasureOptions options(const std::string& inputs) {
  MeasureOptions o;
  o.engine = "j85_95";
  o.out = kDir;
  o.seed = 3;
  o.acquire.inputs = inputs;
  o.analysers = AnalyserGrouping::parse("pair");
  return o;
}

ProcessPlan plan(const MeasureOptions& o, const ResumePoint& from = {}) {
  return plan_processes(load_model_or_embedded("j85_95"), o, kRun, kUrl, from, program);
}

std::vector<std::string> names(const ProcessPlan& p) {
  std::vector<std::string> n;
  for (const ProcessSpec& s : p.processes) n.push_back(s.name);
  return n;
}

const ProcessSpec& process(const ProcessPlan& p, const std::string& name) {
  for (const ProcessSpec& s : p.processes)
    if (s.name == name) return s;
  throw std::runtime_error("no process " + name);
}

// The analysers of input X of the J85 (outputs N, P3, DPP3, P5, T5): one per position-relative
// pair, then one for the command-relative pairs.
std::vector<std::string> analysers(const std::string& x) {
  return {"analyze-" + x + "_N",      "analyze-" + x + "_P3", "analyze-" + x + "_DPP3",
          "analyze-" + x + "_P5",     "analyze-" + x + "_T5", "analyze-u_" + x + "_" + x,
          "analyze-u_" + x + "_N-cmd"};
}

std::vector<std::string> concat(std::vector<std::vector<std::string>> parts) {
  std::vector<std::string> all;
  for (const auto& p : parts) all.insert(all.end(), p.begin(), p.end());
  return all;
}

TEST(ProcessPlan, AFreshRunStartsRecorderPlantAnalysersIdentifierThenTheAcquisition) {
  const ProcessPlan p = plan(options("Wf,A8"));
  EXPECT_THAT(
      names(p),
      ElementsAreArray(concat(
          {{"recorder", "plant"}, analysers("Wf"), analysers("A8"), {"identify", "acquire"}})));
  EXPECT_THAT(p.consumers,
              ElementsAreArray(concat({{"plant", "recorder"}, analysers("Wf"), analysers("A8")})));
  EXPECT_THAT(p.awaited,
              ElementsAreArray(concat({{"plant"}, analysers("Wf"), analysers("A8"), {"acquire"}})));
  for (const ProcessSpec& s : p.processes) {
    EXPECT_EQ(s.log_file, kDir + "/logs/" + s.name + ".log");
    EXPECT_EQ(s.host, "") << s.name;
    EXPECT_EQ(s.essential, s.name != "identify") << s.name;  // its failure leaves a partial run
  }
}

// A run whose curves its caller fits (the auto campaign's runs) starts no identifier.
TEST(ProcessPlan, ARunThatDoesNotFitStartsNoIdentifier) {
  MeasureOptions o = options("Wf,A8");
  o.fit = false;
  const ProcessPlan p = plan(o);
  EXPECT_THAT(names(p),
              ElementsAreArray(
                  concat({{"recorder", "plant"}, analysers("Wf"), analysers("A8"), {"acquire"}})));
}

// The analysers' pairs as the plan passes them (--pair after each name), every pair of the run.
std::vector<std::string> analysed_pairs(const ProcessPlan& p) {
  std::vector<std::string> pairs;
  for (const ProcessSpec& s : p.processes)
    for (size_t k = 0; k + 1 < s.argv.size(); ++k)
      if (s.argv[k] == "--pair") pairs.push_back(s.argv[k + 1]);
  return pairs;
}

// Grouped by input: one analyser per input holding all its pairs; in groups of N: N pairs each,
// input by input. Either way every measured pair is analysed exactly once, and the acquisition
// waits for every analyser.
TEST(ProcessPlan, AnalysersGroupedByInputOrByCountAnalyseEveryPairOnce) {
  const Model m = load_model_or_embedded("j85_95");
  const std::vector<std::string> all = measured_pairs(m, {0, 1});  // Wf, A8: 2 x 11 pairs
  ASSERT_EQ(all.size(), 22u);
  MeasureOptions o = options("Wf,A8");
  o.analysers = AnalyserGrouping::parse("input");
  ProcessPlan p = plan(o);
  EXPECT_THAT(names(p),
              ElementsAre("recorder", "plant", "analyze-Wf", "analyze-A8", "identify", "acquire"));
  EXPECT_THAT(analysed_pairs(p), ElementsAreArray(all));
  EXPECT_THAT(p.consumers, ElementsAre("plant", "recorder", "analyze-Wf", "analyze-A8"));

  o.analysers = AnalyserGrouping::parse("5");
  p = plan(o);
  EXPECT_THAT(names(p), ElementsAre("recorder", "plant", "analyze-1", "analyze-2", "analyze-3",
                                    "analyze-4", "analyze-5", "identify", "acquire"));
  EXPECT_THAT(analysed_pairs(p), ElementsAreArray(all));
  EXPECT_THAT(process(p, "analyze-5").argv, Contains("--pair").Times(2));  // 22 = 4 x 5 + 2
  EXPECT_THAT(p.awaited, Contains("analyze-5"));

  o.analysers = AnalyserGrouping::parse("pair");
  EXPECT_THAT(analysed_pairs(plan(o)), ElementsAreArray(all));

  // By default: one per input.
  o.analysers = MeasureOptions{}.analysers;
  EXPECT_THAT(names(plan(o)),
              ElementsAre("recorder", "plant", "analyze-Wf", "analyze-A8", "identify", "acquire"));
}

TEST(ProcessPlan, AnalyserGroupingWordsAreParsedAndOthersNamed) {
  EXPECT_EQ(AnalyserGrouping::parse("pair").by, AnalyserGrouping::By::kPair);
  EXPECT_EQ(AnalyserGrouping::parse("input").by, AnalyserGrouping::By::kInput);
  EXPECT_EQ(AnalyserGrouping::parse("7").pairs, 7);
  EXPECT_EQ(AnalyserGrouping::parse("7").str(), "7");
  for (const char* bad : {"0", "-2", "3x", "", "inputs"})
    EXPECT_THAT([&] { AnalyserGrouping::parse(bad); },
                testing::ThrowsMessage<InputError>(testing::HasSubstr(std::string("\"") + bad)))
        << bad;
}

TEST(ProcessPlan, EachProcessGetsTheRunsArguments) {
  const MeasureOptions o = options("Wf,A8");
  const ProcessPlan p = plan(o);
  EXPECT_THAT(process(p, "recorder").argv,
              ElementsAre("/bin/fralab-record", "--lcm-url", kUrl, "--run-id", kRun, "--out",
                          kDir + "/tape.lcmlog"));
  EXPECT_THAT(process(p, "plant").argv,
              ElementsAre("/bin/fralab-plant", "--model", kDir + "/engine.json", "--lcm-url", kUrl,
                          "--seed", "3", "--run-id", kRun, "--sample-rate", "1000"));
  EXPECT_THAT(
      process(p, "analyze-Wf_P3").argv,
      ElementsAre("nice", "-n", "5", "/bin/fralab-analyze", "--lcm-url", kUrl, "--run-id", kRun,
                  "--name", "analyze-Wf_P3", "--out", kDir, "--linger", "30", "--pair", "Wf:P3"));
  EXPECT_THAT(process(p, "analyze-u_A8_A8").argv,
              AllOf(Contains("--pair"), Contains("u_A8:A8"), Not(Contains("u_A8:N"))));
  EXPECT_THAT(process(p, "analyze-u_A8_N-cmd").argv,
              ElementsAre("nice", "-n", "5", "/bin/fralab-analyze", "--lcm-url", kUrl, "--run-id",
                          kRun, "--name", "analyze-u_A8_N-cmd", "--out", kDir, "--linger", "30",
                          "--pair", "u_A8:N", "--pair", "u_A8:P3", "--pair", "u_A8:DPP3", "--pair",
                          "u_A8:P5", "--pair", "u_A8:T5"));
  // 2 inputs x (5 X:O + u_X:X + 5 u_X:O) pairs.
  EXPECT_THAT(process(p, "identify").argv,
              ElementsAre("/bin/fralab-identify", "--lcm-url", kUrl, "--run-id", kRun, "--expect",
                          "22", "--out", kDir, "--delay", "auto", "--title",
                          "J85-13, 95 % N/Nmax (engine, Tables 1 and 4-23): measured transfer "
                          "matrix"));
  AcquireOptions ao = o.acquire;
  const Model m = load_model_or_embedded("j85_95");
  ao.block = 500;  // sized: half a second at 1 kHz, 15 tape channels under 60 kB
  std::vector<std::string> acq = {
      "/bin/fralab-acquire",
      "--engine",
      kDir + "/engine.json",
      "--lcm-url",
      kUrl,
      "--run-id",
      kRun,
      "--consumers",
      "plant,recorder," + join_list(concat({analysers("Wf"), analysers("A8")}), ","),
      "--stall-timeout",
      "60",
      "--first-block",
      "0",
      "--first-status",
      "0",
      "--summary",
      kDir + "/acquire.json",
      "--emulator-chain"};
  for (const std::string& f : acquire_flags(ao)) acq.push_back(f);
  EXPECT_THAT(process(p, "acquire").argv, ElementsAreArray(acq));
  EXPECT_THAT(process(p, "acquire").argv, Contains("Wf,A8"));  // --input, by name
}

TEST(ProcessPlan, NoInputsNamedMeansEveryInputByName) {
  const ProcessPlan p = plan(options(""));
  EXPECT_THAT(p.processes, SizeIs(2 + 4 * 7 + 2));
  EXPECT_THAT(process(p, "acquire").argv, Contains("Wf,A8,BLD,IGV"));
  EXPECT_THAT(process(p, "identify").argv, Contains("44"));
}

TEST(ProcessPlan, PlantOptionsReachThePlant) {
  MeasureOptions o = options("Wf");
  o.no_noise = true;
  o.acquire.free_running = true;
  o.acquire.speed = 4;
  o.plant_jitter_ms = 2.5;
  EXPECT_THAT(process(plan(o), "plant").argv,
              ElementsAre("/bin/fralab-plant", "--model", kDir + "/engine.json", "--lcm-url", kUrl,
                          "--seed", "3", "--run-id", kRun, "--sample-rate", "1000", "--no-noise",
                          "--free-running", "--speed", "4", "--tick", "500", "--jitter-ms", "2.5"));
  // (--tick: the block sized for the J85's 15 tape channels at 1 kHz, half a second.)
}

TEST(ProcessPlan, AResumedRunReplaysAppendsAndAnalysesAtTheEnd) {
  MeasureOptions o = options("Wf,A8");
  o.resume = true;
  ResumePoint from;
  from.blocks_on_tape = 12;
  from.first_block = 9;
  from.first_status = 4;
  from.first_step = 2;
  const ProcessPlan p = plan(o, from);
  EXPECT_THAT(names(p), ElementsAre("recorder", "plant", "acquire"));  // no analyser, identifier
  EXPECT_THAT(p.consumers, ElementsAre("plant", "recorder"));
  EXPECT_THAT(p.awaited, ElementsAre("plant", "acquire"));
  EXPECT_THAT(
      process(p, "recorder").argv,
      ElementsAre("/bin/fralab-record", "--lcm-url", kUrl, "--run-id", kRun, "--out",
                  kDir + "/tape.lcmlog", "--append", "--first-block", "9", "--first-status", "4"));
  EXPECT_THAT(process(p, "plant").argv,
              ElementsAre("/bin/fralab-plant", "--model", kDir + "/engine.json", "--lcm-url", kUrl,
                          "--seed", "3", "--run-id", kRun, "--sample-rate", "1000", "--replay",
                          kDir + "/tape.lcmlog", "--replay-blocks", "9"));
  const auto& acq = process(p, "acquire").argv;
  EXPECT_THAT(std::vector<std::string>(acq.begin() + 7, acq.begin() + 15),
              ElementsAre("--consumers", "plant,recorder", "--stall-timeout", "60", "--first-block",
                          "9", "--first-status", "4"));
}

TEST(ProcessPlan, AResumedRunWhoseTapeIsCompleteStartsNothing) {
  MeasureOptions o = options("Wf");
  o.resume = true;
  ResumePoint from;
  from.complete = true;
  const ProcessPlan p = plan(o, from);
  EXPECT_THAT(p.processes, IsEmpty());
  EXPECT_THAT(p.consumers, IsEmpty());
  EXPECT_THAT(p.awaited, IsEmpty());
}

TEST(ProcessPlan, EachKindRunsOnItsDeputysHost) {
  MeasureOptions o = options("Wf");
  o.hosts = {{"plant", "cell-1"}, {"analyze", "cell-2"}, {"identify", "cell-3"}};
  const ProcessPlan p = plan(o);
  EXPECT_EQ(process(p, "plant").host, "cell-1");
  for (const std::string& a : analysers("Wf")) EXPECT_EQ(process(p, a).host, "cell-2") << a;
  EXPECT_EQ(process(p, "identify").host, "cell-3");
  EXPECT_EQ(process(p, "recorder").host, "");  // no deputy named: this host
  EXPECT_EQ(process(p, "acquire").host, "");
}

TEST(ProcessPlan, IsPure) {
  const MeasureOptions o = options("Wf,A8");
  const ProcessPlan a = plan(o), b = plan(o);
  EXPECT_EQ(names(a), names(b));
  for (size_t k = 0; k < a.processes.size(); ++k)
    EXPECT_EQ(a.processes[k].argv, b.processes[k].argv) << a.processes[k].name;
  EXPECT_FALSE(std::filesystem::exists(kDir));  // nothing written
}

TEST(ProcessPlan, MeasuredPairsInputByInput) {
  const Model m = load_model_or_embedded("j85_95");
  EXPECT_THAT(measured_pairs(m, {1}),
              ElementsAre("A8:N", "A8:P3", "A8:DPP3", "A8:P5", "A8:T5", "u_A8:A8", "u_A8:N",
                          "u_A8:P3", "u_A8:DPP3", "u_A8:P5", "u_A8:T5"));
  EXPECT_THAT(measured_pairs(m, {0, 1}), SizeIs(22));
}

}  // namespace
}  // namespace fralab
