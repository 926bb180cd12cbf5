// Fault injection (docs/robustness.md): the lab's real processes under the conditions a test cell
// meets.
// Every run is `fralab measure --engine j85_95 --input Wf --band 0.5:20 --points-per-decade 3`
// (177 s of engine time), and every completed run must give frd files, fits and transfer matrix
// byte-identical to an undisturbed run of the same seed:
//   - random UDP loss on every channel (scripts/lossy.sh: nftables in a private namespace),
//     1, 10 and 50 per mille;
//   - four CPU hogs while runs go as fast as the consumers keep up (--speed 0), N runs;
//   - SIGKILL of each process type mid-run, then `fralab measure --resume DIR`;
//   - SIGTERM / SIGINT to the launcher: no process left, the abort on the tape, resume;
//   - a stopped (SIGSTOP) analyser: the run fails naming it as silent;
//   - two runs sharing one port: neither takes the other's messages;
//   - a resume or a second run on a live run's folder: refused, the live run completes;
//   - a tape with a damaged stretch: read past it, and resume measures again what it held;
//   - an identifier that crashes after measuring: a partial run, diagnosed, then fitted by resume.
// FRALAB_FAULT_HOG_RUNS sets the number of runs under CPU hogs (default 20).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "fralab/core/json_util.h"
#include "shell.h"

using fralab::Json;
using fralab::json_load_file;
using fralab::testing::sh;
using fralab::testing::shared_tmpdir;
using fralab::testing::slurp;
using fralab::testing::tmpdir;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {

const std::string kBin = FRALAB_BIN_DIR;
const std::string kScripts = FRALAB_SCRIPTS_DIR;
const std::string kRun =
    " measure --engine j85_95 --input Wf --band 0.5:20 --points-per-decade 3 --seed 3 ";

// The undisturbed run every other run is compared with.
const std::string& reference() {
  static const std::string dir = [] {
    const std::string d = shared_tmpdir("fault_ref");
    const auto c = sh(kBin + "/fralab" + kRun + "--out " + d);
    EXPECT_EQ(c.status, 0) << c.output;
    return d;
  }();
  return dir;
}

// Every frd and tf file and the transfer matrix of `dir` equal the reference's, byte for byte.
void expect_identical(const std::string& dir) {
  const std::string& ref = reference();
  int files = 0;
  for (const char* sub : {"frd", "tf"}) {
    for (const auto& f : fs::directory_iterator(ref + "/" + sub)) {
      const std::string name = std::string(sub) + "/" + f.path().filename().string();
      ASSERT_TRUE(fs::exists(dir + "/" + name)) << dir << ": no " << name;
      EXPECT_EQ(slurp(f.path().string()), slurp(dir + "/" + name)) << dir << ": " << name;
      ++files;
    }
  }
  EXPECT_EQ(files, 22);  // 11 pairs
  EXPECT_EQ(slurp(ref + "/transfer_matrix.json"), slurp(dir + "/transfer_matrix.json")) << dir;
}

int processes_of(const std::string& dir) {
  // "[f]ralab": the pattern does not match the shell that runs pgrep.
  const auto c = sh("pgrep -fc '[f]ralab-[a-z]*.*" + dir + "'");
  return std::atoi(c.output.c_str());
}

class Loss : public ::testing::TestWithParam<int> {};

TEST_P(Loss, EveryDatagramLostIsRetransmittedAndTheRunIsIdentical) {
  const int per_mille = GetParam();
  reference();
  const std::string d = tmpdir("loss" + std::to_string(per_mille));
  const auto c = sh(kScripts + "/lossy.sh " + std::to_string(per_mille) + " " + kBin + "/fralab" +
                    kRun + "--out " + d);
  ASSERT_EQ(c.status, 0) << c.output;
  expect_identical(d);
  const Json run = json_load_file(d + "/run.json");
  EXPECT_EQ(run["state"], "complete");
  std::cout << "[ figures  ] loss " << per_mille / 10.0 << " %: " << c.output.substr(0, 0)
            << run["retransmissions"] << " retransmissions of " << run["items_retransmitted"]
            << " blocks/events, wall " << run["wall_time_s"] << " s, engine time added 0 s\n"
            << c.output;
  if (per_mille >= 10) {
    EXPECT_GT(run["retransmissions"].get<int>(), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Faults, Loss, ::testing::Values(1, 10, 50));

TEST(Faults, FourCpuHogsAtFullSpeedEveryRunCompletesIdentical) {
  reference();
  const char* env = std::getenv("FRALAB_FAULT_HOG_RUNS");
  const int runs = env ? std::atoi(env) : 20;
  const std::string d = tmpdir("hogs");
  // (Output to /dev/null: a hog holding the pipe would keep sh() waiting.)
  sh("for i in 1 2 3 4; do (timeout 3600 sh -c 'while :; do :; done' >/dev/null 2>&1 &) ; done");
  int ok = 0;
  for (int i = 0; i < runs; ++i) {
    const std::string out = d + "/run" + std::to_string(i);
    const auto c = sh(kBin + "/fralab" + kRun + "--speed 0 --out " + out);
    EXPECT_EQ(c.status, 0) << c.output;
    if (c.status == 0) {
      expect_identical(out);
      ++ok;
    }
    fs::remove_all(out);
  }
  sh("pkill -f '[w]hile :; do :; done'");
  std::cout << "[ figures  ] four CPU hogs: " << ok << " of " << runs << " runs complete\n";
  EXPECT_EQ(ok, runs);
}

class Kill : public ::testing::TestWithParam<std::string> {};

// Paced at 50x so the kill lands mid-run (the run takes 3.5 s).
TEST_P(Kill, AKilledProcessFailsTheRunAndResumeGivesTheUninterruptedNumbers) {
  reference();
  const std::string who = GetParam();
  const std::string d = tmpdir("kill_" + who);
  const std::string first = d + "/first.out";
  auto c = sh("(" + kBin + "/fralab" + kRun + "--speed 50 --out " + d + " > " + first +
              " 2>&1 & lp=$!; sleep 1.5; " +
              (who == "launcher" ? std::string("kill -TERM $lp")
                                 : "pkill -KILL -f '[f]ralab-" + who + ".*" + d + "'") +
              "; wait $lp; echo exit=$?)");
  // The identifier works after everything is measured: its failure leaves a partial run (exit
  // status 3) whose curves are already the uninterrupted run's.
  const bool partial = who == "identify";
  EXPECT_THAT(c.output, HasSubstr(partial ? "exit=3" : "exit=1")) << slurp(first);
  sh("sleep 0.5");
  EXPECT_EQ(processes_of(d), 0) << "processes left after the run failed";
  Json run = json_load_file(d + "/run.json");
  EXPECT_EQ(run["state"], who == "launcher" ? "interrupted"
                          : partial         ? "partial"
                                            : "failed")
      << run.dump();
  if (partial) {
    EXPECT_EQ(run["failed_step"]["step"], "identify");
    EXPECT_THAT(run["failed_step"]["error"].get<std::string>(), HasSubstr("killed by signal 9"));
    EXPECT_THAT(slurp(first), HasSubstr("partial run: everything was measured"));
    for (const auto& f : fs::directory_iterator(reference() + "/frd"))
      EXPECT_EQ(slurp(f.path().string()), slurp(d + "/frd/" + f.path().filename().string()))
          << f.path().filename();
  } else if (who == "launcher") {
    EXPECT_THAT(slurp(first), HasSubstr("the excitation was stopped first"));
    const auto tape = sh(kBin + "/fralab tape --log " + d + "/tape.lcmlog");
    EXPECT_THAT(tape.output, HasSubstr("\"abort\"")) << "no abort status on the tape";
  } else {
    EXPECT_THAT(slurp(first), HasSubstr("killed by signal 9"));
  }
  c = sh(kBin + "/fralab measure --resume " + d);
  ASSERT_EQ(c.status, 0) << c.output;
  EXPECT_THAT(c.output, HasSubstr("resuming run"));
  expect_identical(d);
  run = json_load_file(d + "/run.json");
  EXPECT_EQ(run["state"], "complete");
  EXPECT_EQ(run["resumed"], 1);
  c = sh(kBin + "/fralab measure --resume " + d);
  EXPECT_NE(c.status, 0);
  EXPECT_THAT(c.output, HasSubstr("the run is complete; there is nothing to resume"));
}

INSTANTIATE_TEST_SUITE_P(Faults, Kill,
                         ::testing::Values("plant", "acquire", "analyze", "record", "identify",
                                           "launcher"));

// A run `run` (fralab flags before --out) measured undisturbed into REF and once more paced at
// `speed`, its acquisition killed after `kill_after_s` of wall time, then resumed into D: the
// resumed run must end identical to the undisturbed one (every frd and tf file, at least
// `min_files`, and the transfer matrix). Returns {REF, D}.
std::pair<std::string, std::string> kill_and_resume(const std::string& run, const std::string& name,
                                                    int speed, double kill_after_s, int min_files) {
  const std::string ref = tmpdir(name + "_ref"), d = tmpdir(name + "_kill");
  const std::string first = tmpdir(name + "_first") + "/output.txt";  // the killed run's output
  auto c = sh(kBin + "/fralab" + run + "--out " + ref);
  EXPECT_EQ(c.status, 0) << c.output;
  c = sh("(" + kBin + "/fralab" + run + "--speed " + std::to_string(speed) + " --out " + d + " > " +
         first + " 2>&1 & lp=$!; sleep " + std::to_string(kill_after_s) +
         "; pkill -KILL -f '[f]ralab-acquire.*" + d + "'; wait $lp; echo exit=$?)");
  EXPECT_THAT(c.output, HasSubstr("exit=1")) << slurp(first);
  c = sh(kBin + "/fralab measure --resume " + d);
  EXPECT_EQ(c.status, 0) << c.output;
  EXPECT_THAT(c.output, HasSubstr("resuming run"));
  int files = 0;
  for (const char* sub : {"frd", "tf"})
    for (const auto& f : fs::directory_iterator(ref + "/" + sub)) {
      const std::string file = std::string(sub) + "/" + f.path().filename().string();
      EXPECT_EQ(slurp(f.path().string()), slurp(d + "/" + file)) << file;
      ++files;
    }
  EXPECT_GE(files, min_files);
  EXPECT_EQ(slurp(ref + "/transfer_matrix.json"), slurp(d + "/transfer_matrix.json"));
  EXPECT_EQ(json_load_file(d + "/run.json")["state"], "complete");
  return {ref, d};
}

// A multisine run resumes as a stepped one does. The orthogonal multisine of Wf and A8
// (2 experiments of 2 periods, 18 s of engine time, paced at 5x), its acquisition killed mid-run,
// then resumed: identical to an undisturbed multisine run of the same seed.
TEST(Faults, AKilledMultisineRunResumesToTheUninterruptedNumbers) {
  kill_and_resume(
      " measure --engine j85_95 --input Wf,A8 --band 0.5:20 --points-per-decade"
      " 3 --seed 3 --excitation multisine --min-cycles 2 ",
      "multisine", 5, 1.5, 21);
}

// An adaptive stepped sine's campaign grows with the decisions it takes while
// running; killed mid-run and resumed, it reads them back from the tape, takes the open step's
// again on the same samples, and ends identical to an undisturbed run, each step's cycles
// included (Wf over 0.5-20 Hz: five of six steps extended; 210 s of engine time, paced at 10x).
TEST(Faults, AKilledAdaptiveRunResumesToTheUninterruptedDecisions) {
  const auto [ref, d] = kill_and_resume(
      " measure --engine j85_95 --input Wf --band 0.5:20 --points-per-decade 3 --seed 3"
      " --excitation stepped --sigma-target 0.01 --min-integrate-s 16 ",
      "adaptive", 10, 8, 11);
  const Json a = json_load_file(ref + "/run.json"), b = json_load_file(d + "/run.json");
  EXPECT_EQ(a["engine_time_s"], b["engine_time_s"]);
  EXPECT_EQ(a["adaptive"], b["adaptive"]);  // every step's cycles, sigma and state
  ASSERT_EQ(a["adaptive"]["steps"].size(), 6u);
  int extended = 0;
  for (const auto& s : a["adaptive"]["steps"]) extended += s["cycles"].get<int>() > 4;
  EXPECT_GE(extended, 3);  // the decisions the resumed run had to read back or take again
}

// Two runs forced onto one URL (one port: Linux hands both runs' datagrams to both): every process
// takes only its run's messages, and both runs come out identical to the undisturbed one.
TEST(Faults, TwoRunsSharingAPortNeverMix) {
  reference();
  const std::string d = tmpdir("shared_port");
  const std::string url = "'udpm://239.255.9.9:24680?ttl=0'";
  const auto c = sh("(" + kBin + "/fralab" + kRun + "--lcm-url " + url + " --out " + d + "/a & " +
                    kBin + "/fralab" + kRun + "--lcm-url " + url + " --out " + d +
                    "/b & wait %1; echo a=$?; wait %2; echo b=$?)");
  EXPECT_THAT(c.output, HasSubstr("a=0")) << c.output;
  EXPECT_THAT(c.output, HasSubstr("b=0")) << c.output;
  expect_identical(d + "/a");
  expect_identical(d + "/b");
}

// One writer per run folder: while a run measures, a resume of its folder and a second run into
// it are refused naming the run that holds it, and the live run completes identical to an
// undisturbed one.
TEST(Faults, AResumeOrASecondRunOnALiveRunFolderIsRefusedAndTheLiveRunCompletes) {
  reference();
  const std::string d = tmpdir("live_folder");
  const std::string first = tmpdir("live_folder_first") + "/output.txt";
  const auto c = sh("(" + kBin + "/fralab" + kRun + "--speed 20 --out " + d + " > " + first +
                    " 2>&1 & lp=$!; for i in $(seq 200); do [ -f " + d + "/run.lock ] && grep -q " +
                    "running " + d + "/run.json 2>/dev/null && break; sleep 0.05; done; " + kBin +
                    "/fralab measure --resume " + d + "; echo resume=$?; " + kBin + "/fralab" +
                    kRun + "--out " + d + "; echo second=$?; wait $lp; echo first=$?)");
  EXPECT_THAT(c.output, HasSubstr("resume=1")) << c.output;
  EXPECT_THAT(c.output, HasSubstr("second=1")) << c.output;
  EXPECT_THAT(c.output, HasSubstr("first=0")) << c.output << slurp(first);
  EXPECT_THAT(c.output, HasSubstr(d + ": the run folder is in use by fralab measure, pid "));
  EXPECT_EQ(json_load_file(d + "/run.json")["state"], "complete");
  EXPECT_FALSE(fs::exists(d + "/run.lock"));
  expect_identical(d);
}

// A tape with 1 kB overwritten by garbage in its middle: `fralab tape` reads every block outside
// the damaged stretch and names it with the blocks lost; `--resume` measures those again and the
// run ends identical to an undisturbed one.
TEST(Faults, ADamagedStretchOfTapeIsPassedOverAndResumeMeasuresItAgain) {
  const std::string& ref = reference();
  const std::string d = tmpdir("damaged_tape");
  fs::remove_all(d);
  fs::copy(ref, d, fs::copy_options::recursive);
  const std::string tape = d + "/tape.lcmlog";
  // 1 kB of garbage across the first event boundary (an LCM sync word) past the middle: the end
  // of one block's data (its checksum fails) and the next event's header (its framing is lost).
  const std::string bytes = slurp(tape);
  const size_t boundary = bytes.find("\xED\xA1\xDA\x01", bytes.size() / 2);
  ASSERT_NE(boundary, std::string::npos);
  const size_t at = boundary - 512;
  {
    std::fstream f(tape, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(std::streamoff(at));
    const std::string junk(1024, '\x5a');
    f.write(junk.data(), std::streamsize(junk.size()));
  }
  auto c = sh(kBin + "/fralab tape --log " + tape);
  ASSERT_EQ(c.status, 0) << c.output;
  const Json t = Json::parse(c.output.substr(c.output.find('{')));
  ASSERT_EQ(t["damaged"].size(), 1u) << c.output;
  EXPECT_EQ(t["damaged"][0]["from_byte"].get<int64_t>(), int64_t(boundary));
  EXPECT_GE(t["damaged"][0]["to_byte"].get<int64_t>(), int64_t(at + 1023));
  EXPECT_THAT(t["warning"].get<std::string>(), HasSubstr("damaged stretch: bytes "));
  // What the stretch held is named missing (or failed its checksum), unless it was a copy a
  // retransmission also wrote: how the tape is laid out depends on the machine's load.
  EXPECT_GE(
      t["missing_seqs"].size() + t["corrupt_seqs"].size() + t["retransmitted_copies"].get<size_t>(),
      1u)
      << c.output;
  // The run as it stood when the tape was damaged: not complete, its curves gone.
  Json run = json_load_file(d + "/run.json");
  run["state"] = "failed";
  fralab::json_save_file(d + "/run.json", run);
  fs::remove_all(d + "/frd");
  fs::remove_all(d + "/tf");
  c = sh(kBin + "/fralab measure --resume " + d);
  ASSERT_EQ(c.status, 0) << c.output;
  EXPECT_THAT(c.output, HasSubstr("damaged stretch: bytes "));
  EXPECT_THAT(c.output, HasSubstr("resuming run"));
  expect_identical(d);
}

// An identifier that crashes after everything is measured (a stand-in fralab-identify that kills
// itself with SIGSEGV, beside a copy of the driver: the launcher starts the modules beside itself):
// the diagnosis of an auto campaign still runs on the curves, the measurement ends partial with the
// crash named (exit status 3), and `--resume` with the real identifier fits it whole.
TEST(Faults, AnIdentifierThatCrashesAfterMeasuringLeavesAPartialRunThatIsDiagnosed) {
  const std::string bin = tmpdir("crashing_identifier_bin"), d = tmpdir("crashing_identifier");
  for (const char* m :
       {"fralab", "fralab-plant", "fralab-acquire", "fralab-analyze", "fralab-record"})
    fs::copy_file(kBin + "/" + m, bin + "/" + m);
  {
    std::ofstream f(bin + "/fralab-identify");
    f << "#!/bin/sh\nkill -SEGV $$\n";
  }
  fs::permissions(bin + "/fralab-identify", fs::perms::owner_all, fs::perm_options::add);
  auto c = sh("(" + bin +
              "/fralab diagnose --simulation j85_95_sim --engine j85_95 --input Wf,A8 --band 0.5:20"
              " --points-per-decade 3 --seed 3 --excitation auto --no-plots --out " +
              d + "; echo exit=$?)");
  EXPECT_THAT(c.output, HasSubstr("exit=3")) << c.output;
  EXPECT_THAT(c.output, HasSubstr(d + "/measure: partial run: everything was measured"));
  EXPECT_THAT(c.output, HasSubstr("identify was killed by signal 11"));
  const Json diagnosis = json_load_file(d + "/diagnosis.json");
  EXPECT_GE(diagnosis["findings"].size(), 2u)
      << "the curves were diagnosed";  // A8's pole, backlash
  Json run = json_load_file(d + "/measure/run.json");
  EXPECT_EQ(run["state"], "partial");
  EXPECT_EQ(run["failed_step"]["step"], "identify");
  EXPECT_FALSE(fs::exists(d + "/measure/transfer_matrix.json"));
  c = sh(kBin + "/fralab measure --resume " + d + "/measure");
  ASSERT_EQ(c.status, 0) << c.output;
  EXPECT_THAT(c.output, HasSubstr("fitting its"));
  run = json_load_file(d + "/measure/run.json");
  EXPECT_EQ(run["state"], "complete");
  EXPECT_FALSE(run.contains("failed_step"));
  EXPECT_TRUE(fs::exists(d + "/measure/transfer_matrix.json"));
  for (const auto& f : fs::directory_iterator(d + "/measure/frd"))
    EXPECT_TRUE(fs::exists(d + "/measure/tf/" + f.path().filename().string())) << f.path();
}

TEST(Faults, AStoppedAnalyserIsNamedAsSilent) {
  const std::string d = tmpdir("sigstop");
  const auto c =
      sh("(" + kBin + "/fralab" + kRun + "--speed 50 --stall-timeout 4 --out " + d +
         " & lp=$!; sleep 1; pkill -STOP -f '[f]ralab-analyze.*--name analyze-Wf --out " + d +
         "'; wait $lp; echo exit=$?; pkill -CONT -f '[f]ralab-analyze.*" + d + "')");
  EXPECT_THAT(c.output, HasSubstr("exit=1"));
  EXPECT_THAT(c.output, HasSubstr("consumer \"analyze-Wf\""));
  EXPECT_THAT(c.output, HasSubstr("hung, stopped or dead?"));
  sh("sleep 0.5");
  EXPECT_EQ(processes_of(d), 0);
}

}  // namespace
