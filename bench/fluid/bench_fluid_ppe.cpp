// Benchmark of pressure-solve variants on the same sequence of PPE systems: the dam break of
// cases/dam_break.yaml at l0 = 1.6 mm is advanced with the case's own solver (the physics), and after
// every step this rank's rows of that step's system (FluidSolver::last_system) are solved again by each
// variant, warm-started from the previous step's pressure like the fluid does. Each variant keeps its own
// PressureSolver over the whole run, so preconditioner reuse across steps is measured as it would run.
// Prints one table row per variant: mean setup and solve ms per step, mean / max iterations, the largest
// true residual, and whether every solve converged.
// Usage: mpirun -np R bench_fluid_ppe n_steps dp variant...
//   variant = label:preconditioner[:key=value[,key=value...]]
//   keys: rebuild_every, rebuild_growth, tolerance, solver, max_iterations, coarse (0: the sgs / ssor
//   without the fluid's coarse groups, fluid.coarse_size); any other key is passed to
//   the preconditioner (PressureSolverSettings::parameters, MueLu / Ifpack2 names; ' ' may be written '_' in keys and values).
// Example: bench_fluid_ppe 100 0.0016 jac:jacobi sgs:sgs mu5:muelu:rebuild_every=5
// Results go to docs/performance.md (## Fluid, ### Pressure solve).
#include "core/distribution.hpp"
#include "fluid/fluid_solver.hpp"
#include "fluid/pressure_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <fmt/format.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace mpsfsi;

namespace {

struct Variant {
  std::string label;
  PressureSolverSettings settings;
  std::unique_ptr<PressureSolver> solver;
  double setup = 0, solve = 0, matrix = 0, max_residual = 0;
  long iterations = 0;
  int max_iterations = 0, failures = 0;
  bool one_level = false;  ///< coarse=0: the system without its coarse groups (sgs / ssor on one level)
};

std::vector<std::string> split(const std::string& s, const char sep) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, sep)) out.push_back(item);
  return out;
}

Variant parse_variant(const std::string& text, const CaseSpec& spec) {
  // label:preconditioner[:parameters] (parameter names may hold ':' themselves)
  std::vector<std::string> parts;
  const auto c1 = text.find(':'), c2 = c1 == std::string::npos ? c1 : text.find(':', c1 + 1);
  if (c1 != std::string::npos) {
    parts = {text.substr(0, c1), text.substr(c1 + 1, c2 == std::string::npos ? std::string::npos : c2 - c1 - 1)};
    if (c2 != std::string::npos) parts.push_back(text.substr(c2 + 1));
  }
  if (parts.size() < 2) throw std::invalid_argument("variant '" + text + "': expected label:preconditioner[:k=v,...]");
  Variant v;
  v.label = parts[0];
  v.settings.solver = spec.fluid.solver;
  v.settings.tolerance = spec.fluid.tolerance;
  v.settings.max_iterations = spec.fluid.max_iterations;
  const auto preconditioner = value_of(preconditioner_names(), parts[1]);
  if (!preconditioner)
    throw std::invalid_argument("variant '" + text + "': unknown preconditioner '" + parts[1] + "' (expected one of: " +
                                join_names(preconditioner_names()) + ")");
  v.settings.preconditioner = *preconditioner;
  if (parts.size() > 2)
    for (const auto& kv : split(parts[2], ',')) {
      const auto eq = kv.find('=');
      if (eq == std::string::npos) throw std::invalid_argument("variant '" + text + "': expected key=value");
      std::string key = kv.substr(0, eq);
      const std::string value = kv.substr(eq + 1);
      if (key == "rebuild_every") v.settings.rebuild_every = std::stoi(value);
      else if (key == "coarse") v.one_level = value == "0";
      else if (key == "rebuild_growth") v.settings.rebuild_growth = std::stod(value);
      else if (key == "tolerance") v.settings.tolerance = std::stod(value);
      else if (key == "max_iterations") v.settings.max_iterations = std::stoi(value);
      else if (key == "solver") {
        const auto solver = value_of(krylov_solver_names(), value);
        if (!solver)
          throw std::invalid_argument("variant '" + text + "': unknown solver '" + value + "' (expected one of: " +
                                      join_names(krylov_solver_names()) + ")");
        v.settings.solver = *solver;
      } else {
        std::replace(key.begin(), key.end(), '_', ' ');
        std::string text_value = value;
        std::replace(text_value.begin(), text_value.end(), '_', ' ');
        v.settings.parameters[key] = text_value;
      }
    }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  {
    const int n_steps = argc > 1 ? std::stoi(argv[1]) : 100;
    const std::string dp = argc > 2 ? argv[2] : "0.0016";
    const CaseSpec spec = load_case(std::string(MPSFSI_SOURCE_DIR) + "/cases/dam_break.yaml", {"dp=" + dp});
    std::vector<Variant> variants;
    for (int k = 3; k < argc; ++k) variants.push_back(parse_variant(argv[k], spec));
    for (auto& v : variants) v.solver = make_pressure_solver(v.settings, MPI_COMM_WORLD);

    Scene scene = build_scene(spec);
    ParticleSet& p = scene.particles;
    // The physics runs on this rank alone (same trajectory for every rank count); only the variants'
    // solves are distributed.
    Distribution self(MPI_COMM_SELF, {});
    FluidSolver fluid(fluid_setup(spec), p, self);
    std::vector<Real> p_prev, x0, x;
    LocalRows mine;
    Real t = 0;
    std::size_t rows = 0;
    for (int s = 0; s < n_steps; ++s) {
      // Previous pressure by global particle id (the fluid reorders and may remove particles).
      const auto& pressure = p.scalar_field("pressure");
      GlobalId id_max = 0;
      for (const GlobalId g : p.global_id) id_max = std::max(id_max, g);
      p_prev.assign(static_cast<std::size_t>(id_max) + 1, 0.0);
      for (std::size_t i = 0; i < p.size(); ++i) p_prev[static_cast<std::size_t>(p.global_id[i])] = pressure[i];

      const Real dt = fluid.stable_dt();
      fluid.advance(t, dt);
      t += dt;
      const LocalRows& sys = fluid.last_system();  // all rows (MPI_COMM_SELF)
      const auto& row_particle = fluid.row_particles();
      const auto& surface = p.scalar_field("free_surface");
      rows = sys.n_rows();
      x0.assign(rows, 0.0);
      for (std::size_t r = 0; r < rows; ++r) {
        const auto i = static_cast<std::size_t>(row_particle[r]);
        if (i < p.size() && surface[i] == 0) x0[r] = p_prev[static_cast<std::size_t>(p.global_id[i])];
      }
      for (auto& v : variants) {
        // This rank's block of the full system.
        mine = split_system(sys, rank, size);
        if (v.one_level) mine.group.clear();
        const std::size_t begin = rows / static_cast<std::size_t>(size) * static_cast<std::size_t>(rank) +
                                  std::min(rows % static_cast<std::size_t>(size), static_cast<std::size_t>(rank));
        x.assign(x0.begin() + static_cast<std::ptrdiff_t>(begin), x0.begin() + static_cast<std::ptrdiff_t>(begin + mine.n_rows()));
        const PressureSolveResult res = v.solver->solve(mine, x);
        v.matrix += res.t_matrix;
        v.setup += res.t_setup;
        v.solve += res.t_solve;
        v.iterations += res.iterations;
        v.max_iterations = std::max(v.max_iterations, res.iterations);
        v.max_residual = std::max(v.max_residual, res.residual);
        v.failures += res.converged ? 0 : 1;
      }
    }
    if (rank == 0) {
      fmt::print("dam break dp {} m, {} particles, {} PPE rows at the end, {} steps to t = {:.4f} s, {} rank(s)\n", dp,
                 p.size(), rows, n_steps, t, size);
      fmt::print("| variant | matrix ms | setup ms | solve ms | setup + solve ms | it (mean / max) | max true residual | converged |\n");
      fmt::print("|---|---|---|---|---|---|---|---|\n");
    }
    const double ms = 1e3 / n_steps;
    for (auto& v : variants) {
      double times[3] = {v.matrix, v.setup, v.solve};
      MPI_Allreduce(MPI_IN_PLACE, times, 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
      if (rank == 0)
        fmt::print("| {} | {:.2f} | {:.2f} | {:.2f} | {:.2f} | {:.1f} / {} | {:.1e} | {} |\n", v.label, times[0] * ms,
                   times[1] * ms, times[2] * ms, (times[1] + times[2]) * ms,
                   static_cast<double>(v.iterations) / n_steps, v.max_iterations, v.max_residual,
                   v.failures == 0 ? "yes" : fmt::format("NO ({} solves)", v.failures));
    }
    variants.clear();
  }
  MPI_Finalize();
  return 0;
}
