// Work that one rank (on_rank0) or every rank (on_every_rank) does, with its outcome shared: an exception
// is thrown on every rank, with its kind kept (CaseError: bad input, exit 2; OutputError: a file could not
// be written, exit 4; anything else: exit 1), so that no rank waits in a collective for a rank that
// stopped. agreed_message() (core/collectives.hpp) makes one message of the ranks' findings.
#pragma once

#include "core/collectives.hpp"
#include "core/files.hpp"
#include "io/case.hpp"

#include <mpi.h>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace mpsfsi {

namespace detail {
/// Runs f; returns 0, or the kind of its exception (1 CaseError, 2 OutputError, 3 other) with its message.
template <class F>
int run_caught(F&& f, std::string& message) {
  try {
    f();
  } catch (const CaseError& e) {
    message = e.what();
    return 1;
  } catch (const OutputError& e) {
    message = e.what();
    return 2;
  } catch (const std::exception& e) {
    message = e.what();
    return 3;
  }
  return 0;
}

/// Rank `root`'s status and message on every rank.
inline void share(MPI_Comm comm, const int root, int& status, std::string& message) {
  MPI_Bcast(&status, 1, MPI_INT, root, comm);
  std::uint64_t n = message.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, root, comm);
  message.resize(n);
  if (n > 0) MPI_Bcast(message.data(), static_cast<int>(n), MPI_CHAR, root, comm);
}

[[noreturn]] inline void rethrow(const int status, const std::string& message) {
  if (status == 1) throw CaseError(message);
  if (status == 2) throw OutputError(message);
  throw std::runtime_error(message);
}
}  // namespace detail

/// Runs `f` on rank 0 of `comm` and hands its outcome to every rank (a collective: all ranks call it).
template <class F>
void on_rank0(MPI_Comm comm, F&& f) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::string message;
  int status = rank == 0 ? detail::run_caught(f, message) : 0;
  if (size > 1) detail::share(comm, 0, status, message);
  if (status != 0) detail::rethrow(status, message);
}

/// Runs `f` on every rank of `comm`; if it threw on some rank, the lowest such rank's exception is thrown
/// on every rank (a collective: f itself must not call collectives that a failing rank would skip).
template <class F>
void on_every_rank(MPI_Comm comm, F&& f) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  std::string message;
  int status = detail::run_caught(f, message);
  if (size > 1) {
    int first = status != 0 ? rank : size;
    MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPI_INT, MPI_MIN, comm);
    if (first == size) return;
    detail::share(comm, first, status, message);
  }
  if (status != 0) detail::rethrow(status, message);
}

}  // namespace mpsfsi
