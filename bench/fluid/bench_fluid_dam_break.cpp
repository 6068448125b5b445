// Benchmark of the fluid step (seed 004 eq. 16-24) on the dam break of cases/dam_break.yaml at l0 = 1.6 mm
// (about 16,200 fluid particles): milliseconds per step split into neighbour search, PPE assembly,
// preconditioner setup, solve (with iterations) and the rest, and peak memory per particle.
// Usage: bench_fluid_dam_break [preconditioner [n_steps [dp [extra --set overrides...]]]]
// Results go to docs/performance.md (## Fluid).
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <fmt/format.h>
#include <mpi.h>
#include <sys/resource.h>

#include <chrono>
#include <string>

using namespace mpsfsi;

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  {
    const std::string prec = argc > 1 ? argv[1] : "jacobi";
    const int n_steps = argc > 2 ? std::stoi(argv[2]) : 200;
    const std::string dp = argc > 3 ? argv[3] : "0.0016";
    std::vector<std::string> overrides = {"dp=" + dp, "fluid.preconditioner=" + prec};
    for (int k = 4; k < argc; ++k) overrides.push_back(argv[k]);
    const CaseSpec spec = load_case(std::string(MPSFSI_SOURCE_DIR) + "/cases/dam_break.yaml", overrides);
    Scene scene = build_scene(spec);
    ParticleSet& p = scene.particles;
    FluidSolver fluid(fluid_setup(spec), p, MPI_COMM_WORLD);
    FluidStepReport sum;
    long iterations = 0;
    Real t = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (int s = 0; s < n_steps; ++s) {
      const Real dt = fluid.stable_dt();
      const FluidStepReport r = fluid.advance(t, dt);
      t += dt;
      sum.t_neighbours += r.t_neighbours;
      sum.t_assembly += r.t_assembly;
      sum.t_setup += r.t_setup;
      sum.t_solve += r.t_solve;
      sum.t_rest += r.t_rest;
      iterations += r.iterations;
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const double peak = static_cast<double>(usage.ru_maxrss) * 1024.0;
    const double ms = 1e3 / n_steps;
    fmt::print("dam break dp {} m, {} particles ({} fluid), preconditioner {}, tolerance {:.0e}, {} steps to t = {:.4f} s\n",
               dp, p.size(), p.n_of_kind(ParticleKind::fluid), prec, spec.fluid.tolerance, n_steps, t);
    fmt::print("| particles | neighbours | assembly | prec. setup | solve (it) | rest | total ms/step | peak KB/particle | fluid arrays KB/particle |\n");
    fmt::print("| {} | {:.2f} | {:.2f} | {:.2f} | {:.2f} ({:.1f}) | {:.2f} | {:.2f} | {:.2f} | {:.2f} |\n", p.size(),
               sum.t_neighbours * ms, sum.t_assembly * ms, sum.t_setup * ms, sum.t_solve * ms,
               static_cast<double>(iterations) / n_steps, sum.t_rest * ms, wall * ms, peak / 1024.0 / static_cast<double>(p.size()),
               static_cast<double>(fluid.memory_bytes() + p.memory_bytes()) / 1024.0 / static_cast<double>(p.size()));
  }
  MPI_Finalize();
  return 0;
}
