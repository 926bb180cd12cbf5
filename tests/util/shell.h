// Shell helpers for the integration tests: run a command (stdout and stderr captured, exit status)
// and make a fresh scratch folder per test process.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

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

/// $TMPDIR/fralab_it_<name>_<pid>, emptied.
inline std::string tmpdir(const std::string& name) {
  namespace fs = std::filesystem;
  auto d = fs::temp_directory_path() / ("fralab_it_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

/// The whole file, bytes as they are ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace fralab::testing
