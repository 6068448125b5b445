// The lock of a run's output folder: a run holds an OS lock (flock) on the file .mpsfsi.lock in its folder for
// its whole life, so a second run into the same folder is refused instead of mixing its files with the first
// one's. The kernel releases the lock when the process ends in any way (also SIGKILL), so no stale lock stays.
// The lock also tells whether the folder is still the one the run started in (removed or replaced mid-run).
#pragma once

#include <stdexcept>
#include <string>

#include <sys/types.h>

namespace mpsfsi {

/// Another process holds the lock of the folder; the message names its pid and host.
class OutputLocked : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The name of the lock file in an output folder.
inline constexpr const char* output_lock_name = ".mpsfsi.lock";

/// Whether `dir` holds no file other than the lock file (an existing folder; false if it cannot be read).
bool holds_only_lock(const std::string& dir);

class OutputLock {
 public:
  /// Locks the existing folder `dir`. Throws OutputLocked when another process holds the lock, OutputError
  /// when the lock file cannot be created.
  explicit OutputLock(const std::string& dir);
  ~OutputLock();
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

  /// "" while the folder and its lock file are the ones locked; else what happened to them (removed, replaced).
  std::string lost() const;

  const std::string& dir() const { return dir_; }

 private:
  std::string dir_, path_;
  int fd_ = -1;
  dev_t dir_dev_ = 0, file_dev_ = 0;
  ino_t dir_ino_ = 0, file_ino_ = 0;
};

}  // namespace mpsfsi
