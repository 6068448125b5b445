// Checked, atomic writing of result files (core/files.hpp).
#include "core/files.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace mpsfsi {

namespace {

std::string reason(const int err) { return err != 0 ? std::strerror(err) : std::string("write failed"); }

}  // namespace

void write_file_atomically(const std::string& path, const std::string& bytes, const std::string& what) {
  const std::string tmp = path + ".tmp";
  errno = 0;
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) throw OutputError(fmt::format("cannot write {} '{}': {}", what, path, reason(errno)));
  const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size() && std::fflush(f) == 0;
  const int err = errno;
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) {
    const int close_err = errno;
    std::remove(tmp.c_str());
    throw OutputError(fmt::format("cannot write {} '{}': {}", what, path, reason(written ? close_err : err)));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int rename_err = errno;
    std::remove(tmp.c_str());
    throw OutputError(fmt::format("cannot write {} '{}': renaming '{}' failed: {}", what, path, tmp, reason(rename_err)));
  }
}

void check_written(const std::ostream& out, const std::string& path, const std::string& what) {
  if (!out) throw OutputError(fmt::format("cannot write {} '{}': {}", what, path, reason(errno)));
}

}  // namespace mpsfsi
