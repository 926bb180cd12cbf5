// Shell helpers for the integration tests: run a command (stdout and stderr captured, exit status)
// and make a fresh scratch folder per test process (removed after a test that passes).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fralab::testing {

struct Cmd {
  int status;  // the exit status; -1 when killed by a signal
  std::string output;
};

inline Cmd sh(const std::string& cmd) {
  std::string full = cmd + " 2>&1";
  FILE* p = popen(full.c_str(), "r");
  std::string out;
  char buf[4096];
  while (size_t n = fread(buf, 1, sizeof buf, p)) out.append(buf, n);
  int st = pclose(p);
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

/// Scratch folders made for the running test (removed when it passes, kept for a look when it
/// fails) and for the whole program (shared by several tests: removed at its end when every test
/// passed). A run of the integration suite writes some GB of tapes and reports.
inline std::vector<std::string>& test_scratch() {
  static std::vector<std::string> dirs;
  return dirs;
}
inline std::vector<std::string>& program_scratch() {
  static std::vector<std::string> dirs;
  return dirs;
}
class RemoveScratchOfPassedTests : public ::testing::EmptyTestEventListener {
  void OnTestEnd(const ::testing::TestInfo& info) override {
    std::error_code ec;
    if (info.result() && info.result()->Passed())
      for (const std::string& d : test_scratch()) std::filesystem::remove_all(d, ec);
    test_scratch().clear();
  }
  void OnTestProgramEnd(const ::testing::UnitTest& unit) override {
    std::error_code ec;
    if (unit.Passed())
      for (const std::string& d : program_scratch()) std::filesystem::remove_all(d, ec);
  }
};
inline const bool kScratchCleanerInstalled = [] {
  ::testing::UnitTest::GetInstance()->listeners().Append(new RemoveScratchOfPassedTests);
  return true;
}();

/// $TMPDIR/<prefix><name>_<pid>, emptied; removed after the test if it passes.
inline std::string tmpdir(const std::string& name, const std::string& prefix = "fralab_it_") {
  namespace fs = std::filesystem;
  auto d = fs::temp_directory_path() / (prefix + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  test_scratch().push_back(d.string());
  return d.string();
}

/// The same for a folder several tests share (made once, e.g. in a static): removed at the
/// program's end if every test passed.
inline std::string shared_tmpdir(const std::string& name) {
  const std::string d = tmpdir(name);
  test_scratch().pop_back();
  program_scratch().push_back(d);
  return d;
}

/// The whole file, bytes as they are ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace fralab::testing
