// The run loop: fluid step, solid sub-steps, state checks, frames and probes.
#include "coupling/simulation.hpp"

#include "fluid/fluid_solver.hpp"
#include "io/probes.hpp"
#include "io/vtk_writer.hpp"
#include "solid/solid_solver.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <memory>

namespace mpsfsi {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(const Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Throws RunFailure naming the first particle with a non-finite position or velocity.
void check_finite(const ParticleSet& p, const std::size_t step, const Real t) {
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.position[i].allFinite() && p.velocity[i].allFinite()) continue;
    throw RunFailure(fmt::format(
        "step {} (t = {:.6g} s): particle {} ({} of body '{}') has a non-finite position or velocity; "
        "the run went unstable (reduce dt or the CFL number)",
        step, t, p.global_id[i], to_string(p.kind[i]), p.bodies[p.body[i]].name));
  }
}

}  // namespace

int resolve_subcycles(const int requested, const Real dt_fluid, const Real dt_solid) {
  if (requested > 0) return requested;
  return std::max(1, static_cast<int>(std::ceil(dt_fluid / dt_solid * (1 - 1e-12))));
}

RunSummary run_case(const CaseSpec& spec, Scene scene, const RunSettings& settings, MPI_Comm comm) {
  const auto t_start = Clock::now();
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  const bool log = rank == 0 && !settings.quiet;
  ParticleSet& p = scene.particles;
  const bool has_fluid = p.n_of_kind(ParticleKind::fluid) > 0;
  const bool has_solid = p.n_of_kind(ParticleKind::solid) > 0;

  std::unique_ptr<FluidSolver> fluid;
  std::unique_ptr<SolidSolver> solid;
  if (has_fluid) fluid = std::make_unique<FluidSolver>(spec, p, comm);
  if (has_solid) solid = std::make_unique<SolidSolver>(spec, p);
  if (solid && rank == 0) solid->set_output_directory(settings.output_dir);  // fragments.csv

  RunSummary summary;
  VtkSeriesWriter writer(settings.output_dir, "particles");
  writer.set_fields(spec.output.fields);
  ProbeWriter probes(spec, p, settings.output_dir + "/probes.csv");
  summary.pvd_path = writer.pvd_path();

  const auto write_output = [&](const Real t) {
    const auto t0 = Clock::now();
    if (solid) solid->prepare_output(t);
    if (rank == 0) {
      writer.write(p, t);
      probes.record(t, p);
    }
    summary.t_output += seconds_since(t0);
  };

  Real t = 0;
  std::size_t step = 0;
  write_output(t);
  Real next_output = spec.output.interval;
  const Real eps = 1e-12 * std::max<Real>(1, spec.time.end);
  while (t < spec.time.end - eps) {
    std::string limit = "fixed";
    Real dt = 0;
    if (fluid) {
      dt = fluid->stable_dt(&limit);
    } else {
      dt = spec.solid.dt ? *spec.solid.dt : solid->stable_dt();
      limit = spec.solid.dt ? "fixed" : "solid stability";
    }
    dt = std::min(dt, spec.time.end - t);
    int n_sub = 1;
    if (fluid && solid) n_sub = resolve_subcycles(spec.coupling.subcycles, dt, solid->stable_dt());

    FluidStepReport fr;
    try {
      if (fluid) {
        const auto t0 = Clock::now();
        fr = fluid->advance(t, dt);
        summary.t_fluid += seconds_since(t0);
      }
      if (solid) {
        const auto t0 = Clock::now();
        const Real dts = dt / n_sub;
        for (int k = 0; k < n_sub; ++k) solid->advance(t + k * dts, dts);
        summary.t_solid += seconds_since(t0);
      }
      check_finite(p, step + 1, t + dt);
    } catch (const RunFailure&) {
      throw;
    } catch (const std::exception& e) {
      throw RunFailure(fmt::format("step {} (t = {:.6g} s): {}", step + 1, t, e.what()));
    }
    t += dt;
    ++step;
    if (log && (step % static_cast<std::size_t>(settings.log_every) == 0 || step == 1)) {
      fmt::print("step {:>7}  t = {:.6f} s  dt = {:.3e} s ({})", step, t, dt, limit);
      if (fluid) fmt::print("  PPE {} it, res {:.2e}", fr.iterations, fr.residual);
      if (fluid && solid) fmt::print("  subcycles {} (solid dt {:.3e} s)", n_sub, dt / n_sub);
      fmt::print("\n");
    }
    if (t >= next_output - eps) {
      write_output(t);
      while (next_output <= t + eps) next_output += spec.output.interval;
    }
  }
  summary.n_steps = step;
  summary.end_time = t;
  summary.wall_seconds = seconds_since(t_start);
  return summary;
}

}  // namespace mpsfsi
