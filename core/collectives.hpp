// Small collectives over an MPI communicator that several modules need: this rank's number and the rank count,
// one message agreed by all ranks (the lowest rank's finding) and an all-gather of variable-length arrays of
// numbers (double or int64).
#pragma once

#include <mpi.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mpsfsi {

/// This process's rank in `comm`.
inline int rank_of(MPI_Comm comm) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  return rank;
}

/// The number of ranks of `comm`.
inline int size_of(MPI_Comm comm) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  return size;
}

/// The lowest rank whose `local` message is not empty hands it to every rank; empty if no rank has one.
/// A collective.
inline std::string agreed_message(MPI_Comm comm, std::string local) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  if (size == 1) return local;
  int first = local.empty() ? size : rank;
  MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPI_INT, MPI_MIN, comm);
  if (first == size) return {};
  std::uint64_t n = local.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, first, comm);
  local.resize(n);
  if (n > 0) MPI_Bcast(local.data(), static_cast<int>(n), MPI_CHAR, first, comm);
  return local;
}

/// The MPI datatype of T (double, std::int64_t).
template <class T>
MPI_Datatype mpi_type();
template <>
inline MPI_Datatype mpi_type<double>() { return MPI_DOUBLE; }
template <>
inline MPI_Datatype mpi_type<std::int64_t>() { return MPI_INT64_T; }

/// Every rank's `mine`, concatenated in rank order, on every rank. A collective.
template <class T>
std::vector<T> all_gather(MPI_Comm comm, const std::vector<T>& mine) {
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size == 1) return mine;
  const int n_mine = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<std::size_t>(size)), displs(counts.size(), 0);
  MPI_Allgather(&n_mine, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  for (std::size_t r = 1; r < counts.size(); ++r) displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<T> all(static_cast<std::size_t>(displs.back() + counts.back()));
  MPI_Allgatherv(mine.data(), n_mine, mpi_type<T>(), all.data(), counts.data(), displs.data(), mpi_type<T>(), comm);
  return all;
}

}  // namespace mpsfsi
