// Process supervision for the lab launcher: start module executables as separate processes (their
// stdout/stderr to a log file each), wait for them, stop them, and turn any failure into one
// reason: "NAME exited with status S: <its last error line>". Used by `fralab run|measure`.
#pragma once

#include <sys/types.h>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fralab/core/error.h"

namespace fralab {

/// Thrown by Supervisor::wait_for when the launcher was asked to stop by a signal.
struct Interrupted : InputError {
  using InputError::InputError;
};

struct ProcessSpec {
  std::string name;
  std::vector<std::string> argv;  // argv[0] is the program (path or PATH name)
  std::string log_file;
  std::string host;  // "" = this host; else the deputy (fralab-deputy --name HOST) that runs it
  /// An essential process's failure fails every wait_for; a non-essential one's (the identifier,
  /// whose failure leaves the measurement whole) fails only a wait_for that names it.
  bool essential = true;
};

/// Processes on other hosts, started and watched through their deputies (lab/deputy.h).
class RemoteProcesses {
 public:
  virtual ~RemoteProcesses() = default;
  virtual void start(const ProcessSpec& spec) = 0;
  virtual void stop(const std::string& name) = 0;
  /// Handles what arrived and repeats unanswered orders; waits up to `ms`.
  virtual void poll(int ms) = 0;
  /// The process's exit, once its deputy reported it: the status (-1: killed by a signal) and
  /// the one-line reason.
  struct Exit {
    int status;
    std::string reason;
  };
  virtual std::optional<Exit> exited(const std::string& name) const = 0;
  /// "" while every deputy in use answers; else which one is silent, and since when.
  virtual std::string silent_deputy() const = 0;
};

class Supervisor {
 public:
  Supervisor() = default;
  Supervisor(const Supervisor&) = delete;
  /// stop_all(): whatever still runs is stopped, the processes named first (set_stop_first) first.
  ~Supervisor();

  /// From now on SIGINT, SIGTERM and SIGHUP to this process do not kill it: they are recorded, and
  /// wait_for throws Interrupted naming the signal, so the caller stops its children in order.
  static void catch_stop_signals();
  /// The signal caught (0: none).
  static int stop_signal();
  /// Processes stopped before all others by stop_all() (the acquisition: the excitation stops
  /// first and commands the actuators back to their operating point).
  void set_stop_first(std::vector<std::string> names) { first_ = std::move(names); }
  /// SIGTERM to the processes named first, waiting up to timeout_s for each, then to every other
  /// one; SIGKILL to any still running after timeout_s.
  void stop_all(double timeout_s = 5.0);

  /// Starts a process (through its deputy when spec.host is set: set_remote first); InputError
  /// when it cannot be started.
  void start(const ProcessSpec& spec);
  /// The deputies' side for processes with a host (not owned; must outlive the supervisor).
  void set_remote(RemoteProcesses* remote) { remote_ = remote; }
  /// Notes exits without blocking or throwing.
  void poll() { reap(false); }
  /// The exit of a process that has exited: status (-1 when killed) and reason; nullopt while it
  /// runs.
  std::optional<RemoteProcesses::Exit> exit_of(const std::string& name) const;
  /// Waits until every process named has exited with status 0. If any essential process, or one
  /// named, exits non-zero (or is killed) meanwhile, throws InputError with its reason. Timeout
  /// throws too, and a stop signal caught (catch_stop_signals) throws Interrupted. `on_poll`
  /// (optional) is called on every poll (every 20 ms): a progress line, for instance.
  void wait_for(const std::vector<std::string>& names, double timeout_s,
                const std::function<void()>& on_poll = {});
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
    bool remote = false;
    std::string remote_reason;  // remote: as its deputy reported
  };
  void reap(bool block);
  std::string reason(const Proc& p) const;
  std::map<std::string, Proc> procs_;
  std::vector<std::string> first_;
  RemoteProcesses* remote_ = nullptr;
};

/// The path of a fralab module executable: beside the running binary if there, else `name` (PATH).
std::string module_path(const std::string& name);

}  // namespace fralab
