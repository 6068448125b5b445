// Benchmark of the fluid step (seed 004 eq. 16-24) on the dam break of cases/dam_break.yaml at l0 = 1.6 mm
// (about 16,200 fluid particles; the 3D build: cases/3d/dam_break.yaml at its dp), on the ranks of mpirun with
// the particles distributed: milliseconds per step (the slowest rank) split into neighbour search, PPE
// assembly, preconditioner setup, solve (with iterations), halo (owners, ghosts, refreshes) and the rest; peak
// memory per rank and per particle; ghosts and halo bytes; each rank's phases and its share of the particles (by
// kind, the partition weight, the ghosts, the pressure rows).
// Usage: [mpirun -np R] bench_fluid_dam_break [preconditioner [n_steps [dp [extra --set overrides...]]]]
// Results go to docs/performance.md (## Fluid).
#include "core/distribution.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <fmt/format.h>
#include <mpi.h>
#include <sys/resource.h>

#include <chrono>
#include <numeric>
#include <string>

using namespace mpsfsi;

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  {
    int rank = 0, n_ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &n_ranks);
    const std::string prec = argc > 1 ? argv[1] : "jacobi";
    const int n_steps = argc > 2 ? std::stoi(argv[2]) : 200;
    const std::string dp = argc > 3 ? argv[3] : dim == 2 ? "0.0016" : "0.01";
    std::vector<std::string> overrides = {"dp=" + dp, "fluid.preconditioner=" + prec};
    for (int k = 4; k < argc; ++k) overrides.push_back(argv[k]);
    const CaseSpec spec =
        load_case(std::string(MPSFSI_SOURCE_DIR) + (dim == 2 ? "/cases/dam_break.yaml" : "/cases/3d/dam_break.yaml"), overrides);
    Scene scene = build_scene(spec);
    ParticleSet& p = scene.particles;
    const std::size_t n_particles = p.size(), n_fluid = p.n_of_kind(ParticleKind::fluid);
    DistributionSettings ds;
    ds.method = spec.parallel.partition;
    ds.skin = spec.parallel.skin * spec.dp;
    ds.halo_width = fluid_interaction_radius(fluid_setup(spec)) + ds.skin;
    Distribution dist(MPI_COMM_WORLD, ds);
    std::vector<Real> weights(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) weights[i] = fluid_work_weight(p.kind[i]);
    dist.distribute_replicated(p, weights);
    FluidSolver fluid(fluid_setup(spec), p, dist);
    FluidStepReport sum;
    long iterations = 0;
    Real t = 0;
    std::size_t halo_bytes = 0, ghosts = 0;
    MPI_Barrier(MPI_COMM_WORLD);
    const auto t0 = std::chrono::steady_clock::now();
    double t_balance = 0;  // the balance check after the second step (the first that leaves walls out), not timed
    for (int s = 0; s < n_steps; ++s) {
      const Real dt = fluid.stable_dt();
      const FluidStepReport r = fluid.advance(t, dt);
      t += dt;
      if (s == 1 && n_ranks > 1) {
        // As the run loop's balance check does: the weights now count the walls that take part.
        const auto tb = std::chrono::steady_clock::now();
        const std::vector<Real> w = fluid_work_weights(p, p.n_owned(), MPI_COMM_WORLD);
        if (dist.imbalance(p, w) > spec.parallel.imbalance) dist.partition(p, w);
        t_balance = std::chrono::duration<double>(std::chrono::steady_clock::now() - tb).count();
      }
      sum.t_neighbours += r.t_neighbours;
      sum.t_assembly += r.t_assembly;
      sum.t_setup += r.t_setup;
      sum.t_solve += r.t_solve;
      sum.t_halo += r.t_halo;
      sum.t_rest += r.t_rest;
      iterations += r.iterations;
      halo_bytes = dist.stats().halo_bytes;
      ghosts += p.n_ghost();
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() - t_balance;
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    // The slowest rank's phases, the largest peak memory; halo bytes and ghosts per rank and step (mean).
    double phases[7] = {sum.t_neighbours, sum.t_assembly, sum.t_setup, sum.t_solve, sum.t_halo, sum.t_rest, wall};
    {  // each rank's phases (the balance of the work)
      std::vector<double> all(7 * static_cast<std::size_t>(n_ranks));
      MPI_Gather(phases, 7, MPI_DOUBLE, all.data(), 7, MPI_DOUBLE, 0, MPI_COMM_WORLD);
      for (std::size_t q = 0; rank == 0 && n_ranks > 1 && q < static_cast<std::size_t>(n_ranks); ++q)
        fmt::print("rank {} ms/step: neighbours {:.2f}, assembly {:.2f}, setup {:.2f}, solve {:.2f}, halo {:.2f}, rest {:.2f}\n", q,
                   all[7 * q] * 1e3 / n_steps, all[7 * q + 1] * 1e3 / n_steps, all[7 * q + 2] * 1e3 / n_steps,
                   all[7 * q + 3] * 1e3 / n_steps, all[7 * q + 4] * 1e3 / n_steps, all[7 * q + 5] * 1e3 / n_steps);
    }
    MPI_Allreduce(MPI_IN_PLACE, phases, 7, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    long peak_kib = usage.ru_maxrss;
    MPI_Allreduce(MPI_IN_PLACE, &peak_kib, 1, MPI_LONG, MPI_MAX, MPI_COMM_WORLD);
    double halo[2] = {static_cast<double>(halo_bytes), static_cast<double>(ghosts)};
    MPI_Allreduce(MPI_IN_PLACE, halo, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    const double ms = 1e3 / n_steps;
    {  // each rank's share at the end: what the partition weighs (fluid_work_weights) against what it costs
      constexpr int n_counts = 14;
      const std::vector<Real> w = fluid_work_weights(p, p.n_owned(), MPI_COMM_WORLD);
      // owned: all, fluid, wall, dummy; pressure rows of fluid and of walls; walls and dummies that took part in
      // the last step; the weight; ghosts: fluid, wall, dummy; the matrix's entries and its single-entry rows
      unsigned long long mine[n_counts] = {p.n_owned()};
      for (std::size_t i = 0; i < p.n_owned(); ++i) {
        const int kind = std::min(2, static_cast<int>(p.kind[i]));
        ++mine[1 + kind];
        if (kind > 0 && fluid_takes_part(p, i)) ++mine[5 + kind];
      }
      for (const LocalIndex r : fluid.row_particles())  // the last step's pressure rows: fluid and wall particles
        ++mine[p.kind[static_cast<std::size_t>(r)] == ParticleKind::fluid ? 4 : 5];
      mine[8] = static_cast<unsigned long long>(std::accumulate(w.begin(), w.end(), 0.0));
      for (std::size_t i = p.n_owned(); i < p.size(); ++i) ++mine[9 + std::min(2, static_cast<int>(p.kind[i]))];
      const LocalRows& sys = fluid.last_system();
      mine[12] = sys.row_ptr.empty() ? 0 : sys.row_ptr.back();
      for (std::size_t r = 0; r + 1 < sys.row_ptr.size(); ++r) mine[13] += sys.row_ptr[r + 1] - sys.row_ptr[r] == 1;
      std::vector<unsigned long long> all(n_counts * static_cast<std::size_t>(n_ranks));
      MPI_Gather(mine, n_counts, MPI_UNSIGNED_LONG_LONG, all.data(), n_counts, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
      for (std::size_t q = 0; rank == 0 && q < static_cast<std::size_t>(n_ranks); ++q) {
        const unsigned long long* c = all.data() + n_counts * q;
        fmt::print("rank {}: {} owned ({} fluid, {} wall, {} dummy; taking part {} wall, {} dummy; weight {}); "
                   "ghosts {} fluid, {} wall, {} dummy; pressure rows {} fluid, {} wall ({} entries, {} single)\n",
                   q, c[0], c[1], c[2], c[3], c[6], c[7], c[8], c[9], c[10], c[11], c[4], c[5], c[12], c[13]);
      }
    }
    if (rank == 0) {
      fmt::print("dam break dp {} m, {} particles ({} fluid), {} rank(s), preconditioner {}, tolerance {:.0e}, {} steps to t = {:.4f} s\n",
                 dp, n_particles, n_fluid, n_ranks, prec, spec.fluid.tolerance, n_steps, t);
      fmt::print("owners and ghosts renewed {} times in {} steps ({} partition)\n", dist.stats().n_ghost_builds, n_steps,
                 name_of(partition_method_names(), ds.method));
      fmt::print("| ranks | particles | neighbours | assembly | prec. setup | solve (it) | halo | rest | total ms/step | peak MiB/rank | peak KiB/particle | ghosts/rank | halo KiB/rank/step |\n");
      fmt::print("| {} | {} | {:.2f} | {:.2f} | {:.2f} | {:.2f} ({:.1f}) | {:.2f} | {:.2f} | {:.2f} | {:.1f} | {:.2f} | {:.0f} | {:.1f} |\n", n_ranks,
                 n_particles, phases[0] * ms, phases[1] * ms, phases[2] * ms, phases[3] * ms,
                 static_cast<double>(iterations) / n_steps, phases[4] * ms, phases[5] * ms, phases[6] * ms,
                 static_cast<double>(peak_kib) / 1024.0, static_cast<double>(peak_kib) * n_ranks / static_cast<double>(n_particles),
                 halo[1] / n_steps / n_ranks, halo[0] / n_steps / n_ranks / 1024.0);
    }
  }
  MPI_Finalize();
  return 0;
}
