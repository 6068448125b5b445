// Writing result files safely: a whole file is written under a temporary name and renamed into place, so
// a reader never sees half of it; every write is checked, and a failure (disk full, no permission)
// removes the temporary file and throws OutputError naming the file and the reason.
#pragma once

#include <iosfwd>
#include <stdexcept>
#include <string>

namespace mpsfsi {

/// A result file could not be written (disk full, permissions, a path that is not a folder). The run
/// stops with exit code 4; what was written before stays complete.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Writes `bytes` to `path` through `path.tmp` and a rename (atomic on POSIX). Throws OutputError naming
/// `what` (e.g. "VTK frame") and `path`; no temporary file is left behind.
void write_file_atomically(const std::string& path, const std::string& bytes, const std::string& what);

/// Throws OutputError("cannot write <what> '<path>': <errno text>") for a stream in a failed state.
void check_written(const std::ostream& out, const std::string& path, const std::string& what);

}  // namespace mpsfsi
