// MPI start for every mpsfsi program (the solver, the tests that need MPI, the benchmarks). A process started
// without a launcher (no mpirun) is an MPI singleton; Open MPI would start a helper daemon (orted) for it, which
// only a process that spawns other processes needs. mpsfsi never spawns, so the singleton is told to run without
// one (the MCA parameter ess_singleton_isolated; a value the user set is kept, other MPI libraries ignore it).
#pragma once

#include <mpi.h>

#include <cstdlib>

namespace mpsfsi {

/// MPI_Init, with Open MPI's singleton set to start without its helper daemon unless the user said otherwise.
inline void start_mpi(int* argc, char*** argv) {
  setenv("OMPI_MCA_ess_singleton_isolated", "1", /*overwrite=*/0);
  MPI_Init(argc, argv);
}

}  // namespace mpsfsi
