// main() of the tests that need MPI (the pressure solver, the distribution): MPI is initialized around the
// GoogleTest run.
#include "core/mpi_start.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

int main(int argc, char** argv) {
  mpsfsi::start_mpi(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  const int result = RUN_ALL_TESTS();
  MPI_Finalize();
  return result;
}
