// Work that one rank does for all (files, checks of the output folder) with its outcome shared: an
// exception on rank 0 is thrown on every rank, with its kind kept (CaseError: bad input, exit 2;
// OutputError: a file could not be written, exit 4; anything else: exit 1), so that no rank waits in a
// collective for a rank that stopped.
#pragma once

#include "core/files.hpp"
#include "io/case.hpp"

#include <mpi.h>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace mpsfsi {

/// Runs `f` on rank 0 of `comm` and hands its outcome to every rank (a collective: all ranks call it).
template <class F>
void on_rank0(MPI_Comm comm, F&& f) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  int status = 0;  // 0 ok, 1 CaseError, 2 OutputError, 3 other error
  std::string message;
  if (rank == 0) {
    try {
      f();
    } catch (const CaseError& e) {
      status = 1;
      message = e.what();
    } catch (const OutputError& e) {
      status = 2;
      message = e.what();
    } catch (const std::exception& e) {
      status = 3;
      message = e.what();
    }
  }
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size > 1) {
    MPI_Bcast(&status, 1, MPI_INT, 0, comm);
    std::uint64_t n = message.size();
    MPI_Bcast(&n, 1, MPI_UINT64_T, 0, comm);
    message.resize(n);
    if (n > 0) MPI_Bcast(message.data(), static_cast<int>(n), MPI_CHAR, 0, comm);
  }
  if (status == 1) throw CaseError(message);
  if (status == 2) throw OutputError(message);
  if (status == 3) throw std::runtime_error(message);
}

}  // namespace mpsfsi
