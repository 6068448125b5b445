// The fluid step of seed 004 §4.1, §4.3, §4.6 as a participant of the run loop: advance() runs the phases every
// scheme shares (fluid/fluid_core.cpp: roles, prediction, collisions, n* and the free surface, the rows'
// numbering) and the hooks of the case's pressure scheme (fluid/pressure_scheme.hpp: standard or projection) in
// the order of docs/architecture.md, "One coupled time step"; also the time-step control (eq. 52 plus the
// viscous limit) and the fluid's part of a checkpoint.
// Each rank advances the particles it owns (core/distribution.hpp): at the start of a step the owners
// are updated and the ghosts rebuilt; each phase refreshes at the ghosts the fields the next one reads.
// The PPE rows are the owned particles with a pressure unknown, named by their global ids.
#include "fluid/fluid_solver.hpp"

#include "core/binary_io.hpp"
#include "core/distribution.hpp"
#include "core/ramp.hpp"
#include "core/stopwatch.hpp"
#include "fluid/fluid_core.hpp"
#include "fluid/pressure_scheme.hpp"
#include "fluid/pressure_solver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace mpsfsi {

/// The fluid solver: the phases every scheme shares (FluidCore) and the pressure scheme of the case.
struct FluidSolver::Impl : fluid_detail::FluidCore {
  Impl(const FluidSetup& setup, ParticleSet& particles, Distribution& distribution, const FluidOptions& options)
      : FluidCore(setup, particles, distribution, options),
        scheme(setup.parameters.scheme == FluidScheme::projection
                   ? fluid_detail::make_projection_scheme(*this, setup.parameters)
                   : fluid_detail::make_standard_scheme(*this, setup.parameters)) {
    // Half the near radius: every particle has a near row, and the wide rows (fluid only) scan little more with
    // these cells than with cells of half their own radius (docs/performance.md, "Neighbour search").
    cell_size = 0.5 * scheme->near_radius();
    partitions_seen = distribution.stats().n_partitions;
  }

  std::unique_ptr<fluid_detail::PressureScheme> scheme;
  int partitions_seen = 0;  ///< the distribution's partitions when the last step began (or the solver was made)
};

Real fluid_work_weight(const ParticleKind kind, const bool takes_part) {
  // A fluid particle's work is chiefly its rows at re_laplacian (the neighbour list, the viscous term), which
  // in 3D hold several times the neighbours they hold in 2D; a wall's and a dummy's are their near rows, which
  // grow less: in 3D they weigh less against the fluid.
  constexpr Real wall = dim == 2 ? 0.8 : 0.3, dummy = dim == 2 ? 0.2 : 0.1, left_out = dim == 2 ? 0.05 : 0.01;
  if (kind == ParticleKind::wall) return takes_part ? wall : left_out;
  if (kind == ParticleKind::dummy) return takes_part ? dummy : left_out;
  return 1.0;
}

bool fluid_takes_part(const ParticleSet& p, const std::size_t i) {
  using fluid_detail::FluidCore;
  if (p.kind[i] != ParticleKind::wall && p.kind[i] != ParticleKind::dummy) return true;
  return !p.has_scalar_field(FluidCore::near_fluid_field) || p.scalar_field(FluidCore::near_fluid_field)[i] != 0;
}

std::vector<Real> fluid_work_weights(const ParticleSet& p, const std::size_t n, MPI_Comm comm) {
  using fluid_detail::FluidCore;
  const std::vector<Real>* marks = p.has_scalar_field(FluidCore::near_fluid_field) ? &p.scalar_field(FluidCore::near_fluid_field) : nullptr;
  const std::vector<Real>* work = p.has_scalar_field(FluidCore::work_field) ? &p.scalar_field(FluidCore::work_field) : nullptr;
  std::vector<Real> w(n);
  for (std::size_t i = 0; i < n; ++i) w[i] = fluid_work_weight(p.kind[i], !marks || (*marks)[i] != 0);
  if (!work) return w;
  // Within each of the kinds fluid, wall and dummy a particle's weight scales with its pairs against the mean
  // of its kind over all ranks (integer sums: the same on any number of ranks), so that each kind's total is
  // what the kind weights give and the rows' lengths (an interior against a free surface, a wall corner) move
  // the cut; a particle without pairs (no step yet, or left out) keeps its kind's weight.
  constexpr int n_kinds = 3;
  const auto scaled = [&](const std::size_t i) {
    const int k = static_cast<int>(p.kind[i]);
    return k < n_kinds && (*work)[i] > 0 ? k : -1;
  };
  static_assert(static_cast<int>(ParticleKind::fluid) < n_kinds && static_cast<int>(ParticleKind::wall) < n_kinds &&
                static_cast<int>(ParticleKind::dummy) < n_kinds);
  unsigned long long sums[2 * n_kinds] = {};  // pairs, then particles, by kind
  for (std::size_t i = 0; i < n; ++i)
    if (const int k = scaled(i); k >= 0) {
      sums[k] += static_cast<unsigned long long>((*work)[i]);
      ++sums[n_kinds + k];
    }
  MPI_Allreduce(MPI_IN_PLACE, sums, 2 * n_kinds, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm);
  for (std::size_t i = 0; i < n; ++i)
    if (const int k = scaled(i); k >= 0 && sums[k] > 0)
      w[i] *= (*work)[i] * static_cast<Real>(sums[n_kinds + k]) / static_cast<Real>(sums[k]);
  return w;
}

Real fluid_interaction_radius(const FluidSetup& setup) {
  const FluidParameters& f = setup.parameters;
  // The projection's rows couple particles that share a neighbour: two kernel radii apart.
  const Real reach = f.scheme == FluidScheme::projection ? 2 * std::max(f.re_gradient, f.projection_radius) : f.re_gradient;
  return std::max(reach, f.re_laplacian) * setup.dp;
}

Real lateral_wall_friction_rate(const LateralWallFriction& walls, const Real nu) {
  if (walls.gap <= 0) return 0;
  if (walls.model == LateralWallModel::poiseuille) return 12.0 * nu / (walls.gap * walls.gap);
  if (walls.model == LateralWallModel::stokes) return std::sqrt(2.0 * nu * 2.0 * pi * walls.frequency) / walls.gap;
  throw std::invalid_argument("fluid.lateral_walls.model: unknown model " + std::to_string(static_cast<int>(walls.model)) +
                              " (expected one of: " + join_names(lateral_wall_model_names()) + ")");
}

FluidSolver::FluidSolver(const FluidSetup& setup, ParticleSet& particles, Distribution& distribution,
                         const FluidOptions& options)
    : impl_(std::make_unique<Impl>(setup, particles, distribution, options)) {
  impl_->domain = setup.domain;
}

FluidSolver::~FluidSolver() = default;

Real FluidSolver::stable_dt(std::string* limit) const {
  const Impl& m = *impl_;
  if (m.time.dt) return fluid_stable_dt(m.time, m.dp, m.nu, 0, 0, m.opt.viscous_number, limit);
  Real v2_max = 0;
  for (std::size_t i = 0; i < m.p.n_owned(); ++i)
    if (m.p.kind[i] == ParticleKind::fluid || (m.walls_move() && m.p.kind[i] == ParticleKind::wall))
      v2_max = std::max(v2_max, m.p.velocity[i].squaredNorm());
  MPI_Allreduce(MPI_IN_PLACE, &v2_max, 1, MPI_DOUBLE, MPI_MAX, m.comm);
  return fluid_stable_dt(m.time, m.dp, m.nu, m.gravity.norm(), std::sqrt(v2_max), m.opt.viscous_number, limit);
}

Real fluid_stable_dt(const TimeSpec& time, const Real dp, const Real nu, const Real acceleration, const Real v_max,
                     const Real viscous_number, std::string* limit) {
  const auto name = [&](const char* s) {
    if (limit) *limit = s;
  };
  if (time.dt) {
    name("fixed");
    return *time.dt;
  }
  Real dt = time.dt_max;
  name("dt_max");
  const Real courant = time.cfl ? *time.cfl : 0.2;
  if (v_max > 0 && courant * dp / v_max < dt) {  // eq. 52
    dt = courant * dp / v_max;
    name("cfl");
  }
  // Eq. 52 for the speed a particle at rest reaches within the step: a dt <= courant dp / v_max after it.
  if (acceleration > 0 && std::sqrt(courant * dp / acceleration) < dt) {
    dt = std::sqrt(courant * dp / acceleration);
    name("acceleration");
  }
  if (nu > 0 && viscous_number * dp * dp / nu < dt) {
    dt = viscous_number * dp * dp / nu;
    name("viscous");
  }
  return dt;
}

FluidStepReport FluidSolver::advance(const Real t, const Real dt) {
  Impl& m = *impl_;
  FluidStepReport report;
  report.dt = dt;
  auto t0 = Clock::now();
  const auto t_begin = t0;
  report.t_halo += m.place_solid_view();  // a coupled solid's view for this step
  // The solid's own state comes back at the end of the step, and also when the step throws.
  struct ReleaseView {
    fluid_detail::FluidCore& core;
    ~ReleaseView() { core.release_solid_view(); }
  } release_view{m};
  t0 = Clock::now();
  // Owners and ghosts are renewed (with the cell order now and then) when a particle has moved half the
  // skin since they were built; in between, the ghosts' positions and velocities are refreshed.
  // A partition since the last step appended the particles it brought to each rank: the cell order is renewed too.
  const bool has_solid = m.p.n_of_kind(ParticleKind::solid) > 0;
  const bool partitioned = m.dist.stats().n_partitions != m.partitions_seen;
  m.partitions_seen = m.dist.stats().n_partitions;
  const bool reorder = m.opt.reorder_every > 0 && !has_solid &&
                       (partitioned || m.n_steps % static_cast<std::size_t>(m.opt.reorder_every) == 0);
  const bool rebuilt = m.dist.renew(m.p, {"position", "velocity"}, std::nullopt, reorder, [&] {
    if (reorder) m.p.reorder(cell_order(m.p.position, m.cell_size));
  });
  // A coupled solid's view was set on the owners: their ghosts get it here (a rebuild copied it already).
  if (!rebuilt && m.solid_boundary) m.dist.exchange_ghosts(m.p, {fluid_detail::FluidCore::solid_surface_field}, ParticleKind::solid);
  report.t_halo += seconds_since(t0);
  t0 = Clock::now();
  m.classify();
  m.gravity = m.gravity_full * ramp_factor(t + 0.5 * dt, m.gravity_ramp);
  const auto ghost_needs_row = [&m](const fluid_detail::Role role) { return m.scheme->ghost_needs_row(role); };
  const bool initial = m.n_steps == 0;
  if (initial) {
    // The initial state with the walls where the run starts them (where the case placed them, around the water
    // it filled): a wall that moves in the first step (a tank that starts rolling, a motion table whose first
    // angle is not 0) is that step's motion, not part of the state the fluid starts at rest in.
    report.t_rest += seconds_since(t0);
    t0 = Clock::now();
    m.build_near_list(m.scheme->near_radius(), ghost_needs_row, std::nullopt);
    report.t_neighbours += seconds_since(t0);
    t0 = Clock::now();
    m.scheme->initial_state(report);
  }
  // The initial state (the projection's references) is every particle's; the step leaves the far walls out.
  if (m.scheme->wall_reach() > 0) report.t_halo += m.leave_out_far_walls(m.scheme->wall_reach(), dt);
  m.move_walls(t + dt);
  report.t_rest += seconds_since(t0);
  t0 = Clock::now();
  m.build_wide_list(m.scheme->rows_need_wide_list());
  report.t_neighbours += seconds_since(t0);

  t0 = Clock::now();
  m.predict(dt);
  report.t_rest += seconds_since(t0);
  m.refresh_ghosts({"position", "velocity"}, report);
  t0 = Clock::now();
  m.build_near_list(m.scheme->near_radius(), ghost_needs_row, dt);
  report.t_neighbours += seconds_since(t0);
  t0 = Clock::now();
  m.note_work();
  m.collide(dt);
  report.t_rest += seconds_since(t0);
  m.refresh_ghosts({"position", "velocity"}, report);
  t0 = Clock::now();
  m.density_and_surface(m.scheme->keeps_surface());
  m.scheme->after_surface();
  report.t_rest += seconds_since(t0);
  m.refresh_ghosts({fluid_fields::free_surface}, report);

  t0 = Clock::now();
  m.scheme->prepare(dt, report);
  m.number_rows(dt);
  m.scheme->assemble(dt);
  report.t_assembly += seconds_since(t0);
  // A system with an overflow (rho / dt^2 for a vanishing dt, huge velocities) cannot be solved: say why
  // instead of the Krylov solver's NaN message. All ranks agree before the solve, which is collective.
  // The matrix is finite when its dt factors are and the positions are (then the right-hand side is too).
  int finite = std::isfinite(m.rho / (dt * dt)) && std::isfinite(1.0 / (m.c * m.c * dt * dt)) &&
               std::all_of(m.sys.rhs.begin(), m.sys.rhs.end(), [](const Real v) { return std::isfinite(v); });
  MPI_Allreduce(MPI_IN_PLACE, &finite, 1, MPI_INT, MPI_MIN, m.comm);
  if (!finite)
    throw std::runtime_error(fmt::format(
        "the pressure system is not finite at dt = {:.3g} s (its terms scale as rho / dt^2 = {:.3g}): the time step "
        "is too small for double precision or the velocities overflowed; use a dt of at least ~1e-9 s (time.dt, "
        "time.dt_max) and check the run's earlier steps",
        dt, m.rho / (dt * dt)));
  const auto surface_value = [&m](const std::size_t i) { return m.scheme->surface_value(i); };
  PressureSolveResult res = m.solve_pressure(surface_value);
  report.t_assembly += res.t_matrix;
  report.t_setup = res.t_setup;
  report.t_solve = res.t_solve;
  report.iterations = res.iterations;
  // The projection's active set: re-solved while rows change (at most max_solves solves), on the same rows.
  for (int solves = 1; solves < m.scheme->max_solves(); ++solves) {
    m.refresh_ghosts({fluid_fields::pressure}, report);
    if (!m.scheme->update_rows(solves, dt, report)) break;
    m.refresh_ghosts({fluid_fields::free_surface}, report);
    t0 = Clock::now();
    m.scheme->assemble(dt);
    report.t_assembly += seconds_since(t0);
    res = m.solve_pressure(surface_value);
    report.t_assembly += res.t_matrix;
    report.t_setup += res.t_setup;
    report.t_solve += res.t_solve;
    report.iterations += res.iterations;
    ++report.solves;
  }
  m.refresh_ghosts({fluid_fields::pressure}, report);
  m.scheme->after_solve(dt);
  report.residual = res.residual;
  if (!res.converged)
    throw std::runtime_error(fmt::format(
        "the pressure solve did not converge: {} iterations, true relative residual {:.3e} > tolerance {:.1e} "
        "({} rows, preconditioner '{}'); raise fluid.max_iterations, use another fluid.preconditioner or reduce dt",
        res.iterations, res.residual, res.tolerance, report.n_rows, m.preconditioner));

  t0 = Clock::now();
  m.scheme->correct(dt);
  const auto& surface = m.p.scalar_field(fluid_fields::free_surface);
  // Sums over the ranks: surface particles, rows, removed particles, particles put back out of a wall; the
  // largest fluid speed.
  unsigned long long counts[4] = {0, m.particle_of_row.size(), 0, 0};
  for (std::size_t i = 0; i < m.p.n_owned(); ++i) counts[0] += surface[i] != 0;
  counts[3] = m.keep_out_of_walls();
  counts[2] = m.remove_escaped();
  for (std::size_t i = 0; i < m.p.n_owned(); ++i)
    if (m.p.kind[i] == ParticleKind::fluid) report.max_speed = std::max(report.max_speed, m.p.velocity[i].norm());
  MPI_Allreduce(MPI_IN_PLACE, counts, 4, MPI_UNSIGNED_LONG_LONG, MPI_SUM, m.comm);
  MPI_Allreduce(MPI_IN_PLACE, &report.max_speed, 1, MPI_DOUBLE, MPI_MAX, m.comm);
  report.n_surface = counts[0];
  report.n_rows = counts[1];
  report.n_removed = counts[2];
  report.n_put_back = counts[3];
  ++m.n_steps;
  const double total = seconds_since(t_begin);
  report.t_rest = total - report.t_neighbours - report.t_assembly - report.t_setup - report.t_solve - report.t_halo;
  return report;
}

void FluidSolver::save_state(BinaryWriter& out) const {
  out.section("fluid");
  out.u64(impl_->n_steps);
  out.i64(impl_->opt.reorder_every);
  impl_->solver->save_state(out);
}

bool FluidSolver::load_state(BinaryReader& in) {
  in.expect_section("fluid");
  const std::size_t n_steps = in.u64("the fluid step count");
  const auto reorder = in.i64("the reorder interval");
  if (reorder != impl_->opt.reorder_every)
    in.fail("the checkpoint's fluid reordered the particles every " + std::to_string(reorder) + " steps, this run every " +
            std::to_string(impl_->opt.reorder_every));
  const bool exact = impl_->solver->load_state(in);
  impl_->n_steps = n_steps;
  impl_->partitions_seen = impl_->dist.stats().n_partitions;  // the restart's own distribution is no migration of the run
  return exact;
}

void FluidSolver::store_iteration_checkpoint() { impl_->n_steps_stored = impl_->n_steps; }

void FluidSolver::reload_iteration_checkpoint() { impl_->n_steps = impl_->n_steps_stored; }

void FluidSolver::set_density_tolerance_cap(const Real cap) {
  if (!(cap > 0)) throw std::invalid_argument("FluidSolver::set_density_tolerance_cap: a cap > 0 expected");
  impl_->density_tolerance_cap = cap;
}

void FluidSolver::set_solid_boundary(const SolidBoundaryData& data) { impl_->set_solid_boundary(data); }

std::size_t FluidSolver::memory_bytes() const {
  const Impl& m = *impl_;
  std::size_t bytes = m.nl.memory_bytes() + m.near.memory_bytes();
  bytes += m.sys.col.capacity() * sizeof(LocalIndex) + m.sys.value.capacity() * sizeof(Real) +
           m.sys.row_ptr.capacity() * sizeof(std::size_t) + m.sys.rhs.capacity() * sizeof(Real);
  bytes += m.n_star.capacity() * sizeof(Real) + (m.v_new.capacity() + m.dv.capacity()) * sizeof(Vec) +
           m.row_of.capacity() * sizeof(LocalIndex) + m.particle_of_row.capacity() * sizeof(LocalIndex) +
           m.x_own.capacity() * sizeof(Real) + m.roles.capacity();
  bytes += m.solver->memory_bytes();
  return bytes;
}

}  // namespace mpsfsi

namespace mpsfsi {
const LocalRows& FluidSolver::last_system() const { return impl_->sys; }
const std::vector<LocalIndex>& FluidSolver::row_particles() const { return impl_->particle_of_row; }
const LatticeConstants& FluidSolver::lattice_gradient() const { return impl_->lat_g; }
const LatticeConstants& FluidSolver::lattice_laplacian() const { return impl_->lat_l; }
Real FluidSolver::cell_size() const { return impl_->cell_size; }
}  // namespace mpsfsi
