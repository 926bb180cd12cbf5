// One writer per run folder (lab/run_lock.h): a folder in use is refused naming its holder, a lock
// whose holder is gone is taken over and said, and the lock file goes with its holder.
#include "fralab/lab/run_lock.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "fralab/core/error.h"

using namespace fralab;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {

std::string fresh_dir(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("fralab_run_lock_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  return d.string();
}

std::string slurp(const std::string& f) {
  std::ifstream in(f);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace

TEST(RunLock, AFreeFolderIsTakenWithTheHolderNamedAndReleasedAtTheEnd) {
  const std::string d = fresh_dir("free");
  {
    const RunLock lock(d, "fralab measure");
    EXPECT_TRUE(fs::is_directory(d));  // made when missing
    EXPECT_EQ(lock.taken_over(), "");
    EXPECT_EQ(lock.path(), d + "/run.lock");
    const std::string rec = slurp(d + "/run.lock");
    EXPECT_THAT(rec, HasSubstr("fralab measure, pid " + std::to_string(getpid()) + " on host "));
    EXPECT_THAT(rec, ::testing::MatchesRegex(".*since 20[0-9][0-9]-[0-9][0-9]-[0-9][0-9]T.*Z\n"));
  }
  EXPECT_FALSE(fs::exists(d + "/run.lock"));
  fs::remove_all(d);
}

TEST(RunLock, AFolderInUseIsRefusedNamingItsHolder) {
  const std::string d = fresh_dir("busy");
  const RunLock first(d, "fralab measure");
  try {
    const RunLock second(d, "fralab measure --resume");
    ADD_FAILURE() << "a second writer took a folder in use";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(d + ": the run folder is in use by fralab measure, pid " +
                                    std::to_string(getpid())));
  }
  EXPECT_TRUE(fs::exists(d + "/run.lock"));  // the refusal leaves the holder's lock alone
  fs::remove_all(d);
}

// A holder killed with SIGKILL (no destructor runs, its record stays): while it lives the folder
// is refused naming it; once it is gone its lock is taken over and its record reported.
TEST(RunLock, TheLockOfAKilledHolderIsTakenOverAndSaid) {
  const std::string d = fresh_dir("stale");
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(ready[0]);
    try {
      RunLock lock(d, "fralab measure");
      const char ok = 1;
      if (write(ready[1], &ok, 1) != 1) _exit(2);
      pause();  // until killed
    } catch (...) {
      _exit(3);
    }
    _exit(0);
  }
  close(ready[1]);
  char ok = 0;
  ASSERT_EQ(read(ready[0], &ok, 1), 1);
  close(ready[0]);
  const std::string holder = "fralab measure, pid " + std::to_string(child);
  try {
    const RunLock second(d, "fralab measure");
    ADD_FAILURE() << "the folder of a live holder was taken";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("in use by " + holder));
  }
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(fs::exists(d + "/run.lock"));  // left behind by the killed holder
  const RunLock taken(d, "fralab measure --resume");
  EXPECT_THAT(taken.taken_over(), HasSubstr(holder));
  EXPECT_THAT(slurp(d + "/run.lock"),
              HasSubstr("fralab measure --resume, pid " + std::to_string(getpid())));
  fs::remove_all(d);
}
