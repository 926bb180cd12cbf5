#include "fralab/lab/run_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <iostream>

#include "fralab/core/error.h"

namespace fralab {

namespace {

std::string read_all(int fd) {
  std::string s;
  char buf[512];
  if (lseek(fd, 0, SEEK_SET) < 0) return s;
  for (ssize_t n; (n = read(fd, buf, sizeof buf)) > 0;) s.append(buf, size_t(n));
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

}  // namespace

std::string run_lock_record(const std::string& command) {
  char host[256] = "unknown";
  gethostname(host, sizeof host - 1);
  host[sizeof host - 1] = 0;
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char when[32];
  std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return command + ", pid " + std::to_string(getpid()) + " on host " + host + ", since " + when;
}

RunLock::RunLock(const std::string& dir, const std::string& command) : path_(dir + "/run.lock") {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir + ": cannot create the run folder: " + ec.message());
  // The lock file may be removed by its holder between our open and our flock: the lock is ours
  // only when the file we locked is still the one at the path.
  for (int attempt = 0; attempt < 20; ++attempt) {
    const int fd = open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) throw InputError(path_ + ": cannot open the run's lock file: " + strerror(errno));
    if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      std::string holder = read_all(fd);
      close(fd);
      if (err != EWOULDBLOCK)
        throw InputError(path_ + ": cannot lock the run folder: " + strerror(err));
      if (holder.empty()) holder = "another process (its record not yet written)";
      throw InputError(dir + ": the run folder is in use by " + holder +
                       "; one run writes a folder at a time (wait for it to end, or stop it: "
                       "an interrupted run keeps what it measured and resumes)");
    }
    struct stat locked {
    }, at_path{};
    if (fstat(fd, &locked) != 0 || stat(path_.c_str(), &at_path) != 0 ||
        locked.st_ino != at_path.st_ino || locked.st_dev != at_path.st_dev) {
      close(fd);  // released and removed meanwhile: take the new file
      continue;
    }
    taken_over_ = read_all(fd);  // a record left by a holder that is gone
    if (!taken_over_.empty())
      std::cerr << "fralab: " << path_ << ": took over the lock of " << taken_over_
                << " (that process is gone)\n";
    const std::string rec = run_lock_record(command) + "\n";
    if (ftruncate(fd, 0) != 0 || lseek(fd, 0, SEEK_SET) < 0 ||
        write(fd, rec.data(), rec.size()) != ssize_t(rec.size())) {
      const int err = errno;
      unlink(path_.c_str());
      close(fd);
      throw InputError(path_ + ": cannot write the run's lock file: " + strerror(err));
    }
    fd_ = fd;
    return;
  }
  throw InputError(path_ + ": the lock file keeps being replaced; is another run starting?");
}

RunLock::~RunLock() {
  if (fd_ < 0) return;
  unlink(path_.c_str());  // while still held: nobody takes a file that is about to go
  close(fd_);
}

}  // namespace fralab
