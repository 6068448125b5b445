// The output folder's lock (core/output_lock.hpp).
#include "core/output_lock.hpp"

#include "core/files.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace mpsfsi {

bool holds_only_lock(const std::string& dir) {
  std::error_code ec;
  for (auto it = std::filesystem::directory_iterator(dir, ec); !ec && it != std::filesystem::directory_iterator();
       it.increment(ec))
    if (it->path().filename() != output_lock_name) return false;
  return !ec;
}

OutputLock::OutputLock(const std::string& dir) : dir_(dir), path_(dir + "/" + output_lock_name) {
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw OutputError(fmt::format("cannot create the lock file '{}': {}; expected a folder this user can write", path_,
                                  std::strerror(errno)));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char holder[256] = "";
    const ssize_t n = ::pread(fd_, holder, sizeof holder - 1, 0);
    holder[n > 0 ? n : 0] = '\0';
    std::string who(holder);
    while (!who.empty() && (who.back() == '\n' || who.back() == ' ')) who.pop_back();
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK)
      throw OutputLocked(fmt::format("the output folder {} is in use by another run ({}); wait for it to end, or choose "
                                     "another --output",
                                     dir, who.empty() ? "holder unknown" : who));
    throw OutputError(fmt::format("cannot lock '{}': {}", path_, std::strerror(err)));
  }
  char host[256] = "";
  ::gethostname(host, sizeof host - 1);
  const std::time_t now = std::time(nullptr);
  char date[64] = "";
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S %z", std::localtime(&now));
  const std::string text = fmt::format("pid {} on host {}, since {}\n", ::getpid(), host, date);
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, text.data(), text.size(), 0) != static_cast<ssize_t>(text.size()))
    throw OutputError(fmt::format("cannot write the lock file '{}': {}", path_, std::strerror(errno)));
  struct stat st = {};
  ::fstat(fd_, &st);
  file_dev_ = st.st_dev;
  file_ino_ = st.st_ino;
  if (::stat(dir_.c_str(), &st) == 0) {
    dir_dev_ = st.st_dev;
    dir_ino_ = st.st_ino;
  }
}

OutputLock::~OutputLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock; the file stays (removing it would race with a new locker)
}

std::string OutputLock::lost() const {
  struct stat st = {};
  if (::stat(dir_.c_str(), &st) != 0) return fmt::format("the output folder {} was removed", dir_);
  if (st.st_dev != dir_dev_ || st.st_ino != dir_ino_)
    return fmt::format("the output folder {} was removed and made anew (it is not the folder the run started in)", dir_);
  if (::stat(path_.c_str(), &st) != 0 || st.st_dev != file_dev_ || st.st_ino != file_ino_)
    return fmt::format("the lock file {} of the output folder was removed or replaced", path_);
  return {};
}

}  // namespace mpsfsi
