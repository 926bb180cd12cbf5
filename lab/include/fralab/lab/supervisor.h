// Process supervision for the lab launcher: start module executables as separate processes (their
// stdout/stderr to a log file each), wait for them, stop them, and turn any failure into one
// reason: "NAME exited with status S: <its last error line>". Used by `fralab run|measure`.
#pragma once

#include <sys/types.h>

#include <map>
#include <string>
#include <vector>

#include "fralab/core/error.h"

namespace fralab {

struct ProcessSpec {
  std::string name;
  std::vector<std::string> argv;  // argv[0] is the program (path or PATH name)
  std::string log_file;
};

class Supervisor {
 public:
  Supervisor() = default;
  Supervisor(const Supervisor&) = delete;
  ~Supervisor();  // SIGTERM to whatever still runs

  /// Starts a process; InputError when it cannot be started.
  void start(const ProcessSpec& spec);
  /// Waits until every process named has exited with status 0. If any supervised process exits
  /// non-zero (or is killed) meanwhile, throws InputError with its reason. Timeout throws too.
  void wait_for(const std::vector<std::string>& names, double timeout_s);
  /// Sends `sig` and waits up to timeout_s for the exit (then SIGKILL).
  void stop(const std::string& name, int sig, double timeout_s);
  bool running(const std::string& name) const;
  std::vector<std::string> names() const;

 private:
  struct Proc {
    ProcessSpec spec;
    pid_t pid = -1;
    bool exited = false;
    int status = 0;
  };
  void reap(bool block);
  std::string reason(const Proc& p) const;
  std::map<std::string, Proc> procs_;
};

/// The path of a fralab module executable: beside the running binary if there, else `name` (PATH).
std::string module_path(const std::string& name);

}  // namespace fralab
