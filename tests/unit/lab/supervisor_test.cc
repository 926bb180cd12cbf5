// Process supervision (lab/supervisor.h) on real child processes (sh): success, a failure named
// with its exit status and last log line, a timeout naming who is late, and a stop.
#include "fralab/lab/supervisor.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>

namespace fralab {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

std::string log_file(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("supervisor_test_" + name + ".log")).string();
}

ProcessSpec sh(const std::string& name, const std::string& script) {
  return {name, {"sh", "-c", script}, log_file(name), ""};
}

TEST(Supervisor, WaitsForProcessesThatSucceed) {
  Supervisor s;
  s.start(sh("a", "exit 0"));
  s.start(sh("b", "sleep 0.2"));
  EXPECT_NO_THROW(s.wait_for({"a", "b"}, 30));
  EXPECT_FALSE(s.running("b"));
}

TEST(Supervisor, AFailureIsNamedWithItsStatusAndLastLogLine) {
  Supervisor s;
  s.start(sh("good", "sleep 30"));
  s.start(sh("bad", "echo starting; echo 'the real reason' >&2; exit 3"));
  try {
    s.wait_for({"good"}, 30);
    ADD_FAILURE() << "a failed process went unnoticed";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("bad exited with status 3"),
                                HasSubstr(": the real reason"), HasSubstr(log_file("bad"))));
  }
}

TEST(Supervisor, ATimeoutNamesWhoIsLate) {
  Supervisor s;
  s.start(sh("slow", "sleep 30"));
  try {
    s.wait_for({"slow"}, 0.2);
    ADD_FAILURE() << "no timeout";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("waiting for slow"));
  }
  s.stop("slow", SIGTERM, 5);
  EXPECT_FALSE(s.running("slow"));
}

TEST(Supervisor, UnknownNamesAreRefused) {
  Supervisor s;
  EXPECT_THROW(s.wait_for({"nobody"}, 1), InputError);
}

}  // namespace
}  // namespace fralab
