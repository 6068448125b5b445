// A helper of the tests that write files: a fresh directory under the system's temporary directory whose name
// carries rank 0's process id, so that the same test run on 1-4 ranks at once (ctest -j) never shares one.
// Header-only; tests include it as "support/temp_dir.hpp".
#pragma once

#include <mpi.h>
#include <unistd.h>

#include <filesystem>
#include <string>

namespace mpsfsi::test {

/// Every rank of `comm` gets the same path, <tmp>/mpsfsi_test_<name>_<pid of rank 0>; rank 0 empties it and
/// the call returns once it has (collective).
inline std::filesystem::path fresh_temp_dir(const std::string& name, MPI_Comm comm = MPI_COMM_WORLD) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  long pid = static_cast<long>(::getpid());
  MPI_Bcast(&pid, 1, MPI_LONG, 0, comm);
  const auto dir = std::filesystem::temp_directory_path() / ("mpsfsi_test_" + name + "_" + std::to_string(pid));
  if (rank == 0) std::filesystem::remove_all(dir);
  MPI_Barrier(comm);
  return dir;
}

}  // namespace mpsfsi::test
