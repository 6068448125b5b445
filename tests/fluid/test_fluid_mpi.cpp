// MPI test of the fluid (label mpi): the dam break advanced a few steps with the pressure matrix
// distributed over all ranks of MPI_COMM_WORLD must give the pressures of a one-rank solve (MPI_COMM_SELF)
// to solver tolerance, with the true residual of every distributed solve below the tolerance.
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

using namespace mpsfsi;

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int failures = 0;
  {
    const std::string preconditioner = argc > 1 ? argv[1] : "muelu";
    const Real tol = 1e-10;
    const CaseSpec spec = load_case(std::string(MPSFSI_SOURCE_DIR) + "/cases/dam_break.yaml",
                                    {"fluid.preconditioner=" + preconditioner, "fluid.tolerance=1e-10",
                                     "fluid.density_tolerance=0"});
    Scene serial_scene = build_scene(spec);
    Scene dist_scene = build_scene(spec);
    FluidSolver serial(fluid_setup(spec), serial_scene.particles, MPI_COMM_SELF);
    FluidSolver dist(fluid_setup(spec), dist_scene.particles, MPI_COMM_WORLD);
    Real t = 0;
    for (int step = 0; step < 5; ++step) {
      const Real dt = serial.stable_dt();
      serial.advance(t, dt);
      const FluidStepReport r = dist.advance(t, dt);
      t += dt;
      const auto& ps = serial_scene.particles.scalar_field("pressure");
      const auto& pd = dist_scene.particles.scalar_field("pressure");
      Real p_max = 0, diff = 0;
      for (std::size_t i = 0; i < ps.size(); ++i) {
        p_max = std::max(p_max, std::abs(ps[i]));
        diff = std::max(diff, std::abs(ps[i] - pd[i]));
      }
      const bool ok = r.residual <= 10 * tol && diff <= 1e-6 * p_max && serial_scene.particles.size() == dist_scene.particles.size();
      if (rank == 0)
        std::printf("ranks %d, %s, step %d: %d it, true residual %.2e, max |p_1 - p_%d| / max |p| = %.2e %s\n", size,
                    preconditioner.c_str(), step + 1, r.iterations, r.residual, size, diff / p_max, ok ? "ok" : "FAILED");
      failures += !ok;
    }
  }
  int any = 0;
  MPI_Allreduce(&failures, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any ? 1 : 0;
}
