#include "fralab/lab/supervisor.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "fralab/core/json_util.h"

extern char** environ;

namespace fralab {

namespace {
volatile std::sig_atomic_t g_stop_signal = 0;
void on_stop_signal(int sig) { g_stop_signal = sig; }
}  // namespace

void Supervisor::catch_stop_signals() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
}

int Supervisor::stop_signal() { return g_stop_signal; }

Supervisor::~Supervisor() { stop_all(); }

void Supervisor::stop_all(double timeout_s) {
  for (const auto& n : first_) stop(n, SIGTERM, timeout_s);
  for (auto& [n, p] : procs_) {
    if (!p.exited && p.pid > 0) kill(p.pid, SIGTERM);
    if (!p.exited && p.remote) remote_->stop(n);
  }
  for (auto& [n, p] : procs_) stop(n, SIGTERM, timeout_s);
}

void Supervisor::start(const ProcessSpec& spec) {
  if (procs_.count(spec.name)) throw InputError("process name \"" + spec.name + "\" used twice");
  if (!spec.host.empty()) {
    if (!remote_)
      throw InputError(spec.name + ": host \"" + spec.host + "\" given but no deputies in use");
    remote_->start(spec);
    Proc p;
    p.spec = spec;
    p.remote = true;
    procs_[spec.name] = p;
    return;
  }
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  if (!spec.log_file.empty()) {
    posix_spawn_file_actions_addopen(&fa, 1, spec.log_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
  }
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (const auto& a : spec.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid;
  int rc = posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) {
    throw InputError("cannot start " + spec.name + " (" + spec.argv[0] + "): " + std::strerror(rc));
  }
  Proc p;
  p.spec = spec;
  p.pid = pid;
  procs_[spec.name] = p;
}

void Supervisor::reap(bool block) {
  bool any_remote = false;
  for (auto& [n, p] : procs_) any_remote |= p.remote && !p.exited;
  if (any_remote) remote_->poll(0);
  for (auto& [n, p] : procs_) {
    if (p.exited) continue;
    if (p.remote) {
      if (auto e = remote_->exited(n)) {
        p.exited = true;
        p.status = e->status < 0 ? SIGKILL : (e->status & 0xff) << 8;  // as waitpid encodes it
        p.remote_reason = e->reason;
      }
      continue;
    }
    int st = 0;
    pid_t r = waitpid(p.pid, &st, block ? 0 : WNOHANG);
    if (r == p.pid) {
      p.exited = true;
      p.status = st;
    }
  }
}

std::optional<RemoteProcesses::Exit> Supervisor::exit_of(const std::string& name) const {
  auto it = procs_.find(name);
  if (it == procs_.end() || !it->second.exited) return std::nullopt;
  const int st = it->second.status;
  return RemoteProcesses::Exit{WIFEXITED(st) ? WEXITSTATUS(st) : -1,
                               (WIFEXITED(st) && WEXITSTATUS(st) == 0) ? "" : reason(it->second)};
}

std::string Supervisor::reason(const Proc& p) const {
  if (p.remote && !p.remote_reason.empty()) return p.remote_reason;
  std::string why = WIFEXITED(p.status)
                        ? "exited with status " + std::to_string(WEXITSTATUS(p.status))
                        : "was killed by signal " + std::to_string(WTERMSIG(p.status));
  std::string last;
  std::ifstream in(p.spec.log_file);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) last = line;
  }
  return p.spec.name + " " + why + (last.empty() ? "" : ": " + last) +
         (p.spec.log_file.empty() ? "" : " (log: " + p.spec.log_file + ")");
}

void Supervisor::wait_for(const std::vector<std::string>& names, double timeout_s,
                          const std::function<void()>& on_poll) {
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    if (const int sig = stop_signal())
      throw Interrupted("stopped by signal " + std::to_string(sig) + " (" + strsignal(sig) + ")");
    reap(false);
    for (auto& [n, p] : procs_) {
      if (!p.spec.essential && std::find(names.begin(), names.end(), n) == names.end()) continue;
      if (p.exited && !(WIFEXITED(p.status) && WEXITSTATUS(p.status) == 0))
        throw InputError(reason(p) + (p.remote ? " (on " + p.spec.host + ")" : ""));
    }
    if (remote_) {
      const std::string silent = remote_->silent_deputy();
      if (!silent.empty()) throw InputError(silent);
    }
    bool all = true;
    for (const auto& n : names) {
      auto it = procs_.find(n);
      if (it == procs_.end()) throw InputError("no process named " + n);
      all = all && it->second.exited;
    }
    if (all) return;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_s) {
      std::string who;
      for (const auto& n : names)
        if (!procs_[n].exited) who += (who.empty() ? "" : ", ") + n;
      throw InputError("timed out after " + std::to_string(int(timeout_s)) + " s waiting for " +
                       who);
    }
    if (on_poll) on_poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void Supervisor::stop(const std::string& name, int sig, double timeout_s) {
  auto it = procs_.find(name);
  if (it == procs_.end() || it->second.exited) return;
  if (it->second.remote) {  // its deputy sends SIGTERM (then SIGKILL) and reports the exit
    remote_->stop(name);
    const auto t0 = std::chrono::steady_clock::now();
    while (!it->second.exited && remote_->silent_deputy().empty() &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() <
               timeout_s + 2) {
      remote_->poll(20);
      reap(false);
    }
    if (!it->second.exited) {  // the deputy never confirmed: count it gone, say so
      it->second.exited = true;
      it->second.status = SIGKILL;
      it->second.remote_reason =
          name + " on " + it->second.spec.host + ": its deputy did not confirm the stop";
    }
    return;
  }
  kill(it->second.pid, sig);
  const auto t0 = std::chrono::steady_clock::now();
  while (!it->second.exited) {
    reap(false);
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > timeout_s) {
      kill(it->second.pid, SIGKILL);
      waitpid(it->second.pid, &it->second.status, 0);
      it->second.exited = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

bool Supervisor::running(const std::string& name) const {
  auto it = procs_.find(name);
  return it != procs_.end() && !it->second.exited;
}

std::vector<std::string> Supervisor::names() const {
  std::vector<std::string> v;
  for (const auto& [n, p] : procs_) v.push_back(n);
  return v;
}

std::string module_path(const std::string& name) {
  std::error_code ec;
  auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    auto p = self.parent_path() / name;
    if (std::filesystem::exists(p)) return p.string();
  }
  return name;
}

}  // namespace fralab
