// One writer per run folder. A run (`fralab measure`, its `--resume`, the auto campaign, `fralab
// diagnose --engine`) takes its folder before it writes anything there, and holds it until it
// ends: an advisory lock (flock(2), exclusive) on DIR/run.lock, whose text names the holder
// (command, pid, host, start time in UTC). A second run on a folder in use is refused naming the
// holder; a lock file whose holder is gone (the kernel releases a flock when its process ends, a
// crash included) is taken over, and the taking over is said on stderr and kept in
// RunLock::taken_over().
//
// The lock file stays while the run holds it and is removed when the holder releases it; the
// holder's record (an ordinary text file) is never the authority, the flock is. The descriptor is
// close-on-exec, so the run's child processes do not hold the folder after the run ends.
#pragma once

#include <string>

namespace fralab {

class RunLock {
 public:
  /// Takes DIR (created if missing) for `command` (e.g. "fralab measure"). InputError naming the
  /// folder and the holder ("in use by fralab measure, pid 4242 on host cell-3, since
  /// 2026-11-26T03:41:07Z") when another process holds it, or when the lock file cannot be made.
  RunLock(const std::string& dir, const std::string& command);
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;
  /// Releases the folder (removes DIR/run.lock).
  ~RunLock();

  /// "" when the folder was free; else the record of the holder whose lock was taken over (its
  /// process gone), e.g. "fralab measure, pid 4242 on host cell-3, since 2026-11-26T03:41:07Z".
  const std::string& taken_over() const { return taken_over_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string taken_over_;
  int fd_ = -1;
};

/// The holder record RunLock writes for this process: "<command>, pid <pid> on host <host>, since
/// <UTC time>".
std::string run_lock_record(const std::string& command);

}  // namespace fralab
