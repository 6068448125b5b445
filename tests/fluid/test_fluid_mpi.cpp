// MPI test of the fluid (label mpi): the dam break advanced a few steps with its particles distributed over
// all ranks of MPI_COMM_WORLD (core/distribution.hpp) must give, particle by particle (matched by global id),
// the pressures and positions of a one-rank run (MPI_COMM_SELF) to solver tolerance, keep every particle
// owned exactly once, and reach the true residual of the tolerance in every distributed solve. After its fifth
// step the distributed set is partitioned anew (with the fluid's weights, where the first partition had none):
// the particles that move come after the others on their new rank, and the fluid's next step puts them back
// in cell order.
#include "core/distribution.hpp"
#include "core/neighbours.hpp"
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
    const Real tol = argc > 2 ? std::stod(argv[2]) : 1e-10;
    std::vector<std::string> overrides = {"fluid.preconditioner=" + preconditioner,
                                          "fluid.tolerance=" + std::string(argc > 2 ? argv[2] : "1e-10"),
                                          "fluid.density_tolerance=0"};
    // Optional: the bounds of max |p_1 - p_N| / max |p| and of max |x_1 - x_N| [m], then more case overrides.
    const Real p_bound = argc > 3 ? std::stod(argv[3]) : 1e-8;
    const Real x_bound = argc > 4 ? std::stod(argv[4]) : 1e-12;
    for (int a = 5; a < argc; ++a) overrides.emplace_back(argv[a]);
    const CaseSpec spec = load_case(std::string(MPSFSI_SOURCE_DIR) + "/cases/dam_break.yaml", overrides);
    Scene serial_scene = build_scene(spec);
    Scene dist_scene = build_scene(spec);
    ParticleSet& ps = serial_scene.particles;
    ParticleSet& pd = dist_scene.particles;
    Distribution self(MPI_COMM_SELF, {});
    DistributionSettings settings;
    settings.skin = 0.02 * spec.dp;  // small: owners and ghosts renewed every few steps, refreshed in between
    settings.halo_width = fluid_interaction_radius(fluid_setup(spec)) + settings.skin;
    Distribution world(MPI_COMM_WORLD, settings);
    world.distribute_replicated(pd);
    FluidSolver serial(fluid_setup(spec), ps, self);
    FluidSolver dist(fluid_setup(spec), pd, world);
    Real t = 0;
    unsigned long long moved = 0;  // particles the partition after step 5 moved to another rank
    for (int step = 0; step < 20; ++step) {
      const Real dt = serial.stable_dt();
      const Real dt_dist = dist.stable_dt();
      serial.advance(t, dt);
      const FluidStepReport r = dist.advance(t, dt);
      t += dt;
      // Compare every owned particle with the one-rank run's particle of the same global id.
      const auto& p1 = ps.scalar_field("pressure");
      const auto& pn = pd.scalar_field("pressure");
      Real p_max = 0;
      for (const Real v : p1) p_max = std::max(p_max, std::abs(v));
      Real diff[2] = {0, 0};  // pressure, position
      int missing = 0;
      for (std::size_t i = 0; i < pd.n_owned(); ++i) {
        const LocalIndex k = ps.local_index(pd.global_id[i]);
        if (k < 0) {
          ++missing;
          continue;
        }
        diff[0] = std::max(diff[0], std::abs(p1[static_cast<std::size_t>(k)] - pn[i]));
        diff[1] = std::max(diff[1], (ps.position[static_cast<std::size_t>(k)] - pd.position[i]).norm());
      }
      unsigned long long n_owned = pd.n_owned();
      MPI_Allreduce(MPI_IN_PLACE, diff, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
      MPI_Allreduce(MPI_IN_PLACE, &missing, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
      MPI_Allreduce(MPI_IN_PLACE, &n_owned, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
      const bool ok = r.residual <= 10 * tol && diff[0] <= p_bound * p_max && diff[1] <= x_bound && missing == 0 &&
                      n_owned == ps.size() && dt_dist == dt;
      if (rank == 0)
        std::printf("ranks %d, %s, step %d: %d it, true residual %.2e, max |p_1 - p_%d| / max |p| = %.2e, max |x_1 - x_%d| "
                    "= %.2e m, %llu particles owned (%zu on one rank) %s\n",
                    size, preconditioner.c_str(), step + 1, r.iterations, r.residual, size, diff[0] / p_max, size,
                    diff[1], n_owned, ps.size(), ok ? "ok" : "FAILED");
      failures += !ok;
      if (step == 5) {  // the step after the partition below: the owned particles are in cell order again
        const std::vector<Vec> x(pd.position.begin(), pd.position.begin() + static_cast<std::ptrdiff_t>(pd.n_owned()));
        const std::vector<LocalIndex> order = cell_order(x, dist.cell_size());
        // How far each particle is from its place in cell order, as a fraction of the rank's particles: in
        // cell order up to the cells the particles crossed in the step; a particle that a partition appended
        // is about half the rank's particles away from its place.
        double shift = 0;
        for (std::size_t k = 0; k < order.size(); ++k)
          shift = std::max(shift, std::abs(static_cast<double>(order[k]) - static_cast<double>(k)) / static_cast<double>(order.size()));
        MPI_Allreduce(MPI_IN_PLACE, &shift, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        const bool ordered = shift < 0.05 && (size == 1 || moved > 0);
        if (rank == 0)
          std::printf("after the partition: %llu particles moved between ranks; the owned particles at most %.4f of a rank's "
                      "count from their place in cell order %s\n", moved, shift, ordered ? "ok" : "FAILED");
        failures += !ordered;
      }
      if (step == 4) {
        world.partition(pd, fluid_work_weights(pd, pd.n_owned(), MPI_COMM_WORLD));
        moved = world.stats().n_migrated_out;
        MPI_Allreduce(MPI_IN_PLACE, &moved, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
      }
    }
  }
  int any = 0;
  MPI_Allreduce(&failures, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any ? 1 : 0;
}
