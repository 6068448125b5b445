// The phases of a fluid step that do not depend on the pressure scheme (fluid/fluid_core.hpp): the roles, the
// tank's walls, the explicit prediction (seed 004 eq. 12, 16-17), the collision model, the number density n*
// (eq. 8) and the free-surface double check (§4.3), the numbering of the pressure rows, the removal of the
// particles that left the domain.
#include "fluid/fluid_core.hpp"

#include "core/buffers.hpp"
#include "core/operators.hpp"
#include "core/ramp.hpp"
#include "core/stopwatch.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace mpsfsi::fluid_detail {

namespace {

/// The coarse group of a particle: the cell of side h that holds x, cut by the ranks' regions (a group that
/// straddles a cut is one group per owner: the deflation then also removes the error the block-Jacobi
/// sweeps leave across the cut). One key per group: the owner in the top 20 bits, then 43 / dim bits per
/// axis (cells counted from -2^(bits-1); cells further out share keys, which only merges groups).
std::int64_t group_key(const Vec& x, const Real h, const int owner) {
  constexpr int bits = 43 / dim;
  constexpr std::int64_t mask = (std::int64_t{1} << bits) - 1;
  std::int64_t key = static_cast<std::int64_t>(owner) & ((std::int64_t{1} << 20) - 1);
  for (int a = 0; a < dim; ++a)
    key = (key << bits) | ((static_cast<std::int64_t>(std::floor(x[a] / h)) + (std::int64_t{1} << (bits - 1))) & mask);
  return key;
}

}  // namespace

FluidCore::FluidCore(const FluidSetup& setup, ParticleSet& particles, Distribution& distribution,
                     const FluidOptions& options)
    : p(particles), dist(distribution), opt(options), motion(make_tank_motion(setup.tank_motion)) {
  const FluidParameters& fluid = setup.parameters;
  comm = dist.comm();
  rank = dist.rank();
  dp = setup.dp;
  re_g = fluid.re_gradient * dp;
  re_l = fluid.re_laplacian * dp;
  lat_g = lattice_constants(dp, re_g);
  lat_l = lattice_constants(dp, re_l);
  beta1 = fluid.beta1;
  beta2 = fluid.beta2;
  gravity_full = setup.gravity;
  gravity_ramp = setup.gravity_ramp;
  gravity = gravity_full * ramp_factor(0, gravity_ramp);
  time = setup.time;
  // One fluid material: the PPE is written for one density.
  int materials[2] = {-1, -1};  // the largest and (negated) the smallest fluid material over the ranks
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    if (p.kind[i] == ParticleKind::fluid) {
      materials[0] = std::max(materials[0], static_cast<int>(p.material[i]));
      materials[1] = std::max(materials[1], -static_cast<int>(p.material[i]));
    }
  MPI_Allreduce(MPI_IN_PLACE, materials, 2, MPI_INT, MPI_MAX, comm);
  const int material = materials[0];
  if (material >= 0 && -materials[1] != material)
    throw std::invalid_argument("the fluid solver supports one fluid material per case");
  if (material < 0 || material >= static_cast<int>(setup.materials.size()))
    throw std::invalid_argument("the fluid solver needs fluid particles with a fluid material");
  const FluidMaterial& m = setup.materials[static_cast<std::size_t>(material)];
  rho = m.rho;
  nu = m.nu;
  c = m.c;
  kappa = m.kappa;
  lateral_friction = lateral_wall_friction_rate(fluid.lateral_walls, nu);

  PressureSolverSettings ps;
  ps.solver = fluid.solver;
  ps.preconditioner = fluid.preconditioner;
  ps.tolerance = fluid.tolerance;
  ps.max_iterations = fluid.max_iterations;
  ps.rebuild_every = fluid.preconditioner_rebuild_every;
  solver = make_pressure_solver(ps, comm);
  tolerance = ps.tolerance;
  if (fluid.coarse_size != 0 && !(fluid.coarse_size >= fluid.re_laplacian))
    throw std::invalid_argument("fluid.coarse_size: " + std::to_string(fluid.coarse_size) +
                                " (expected 0 or at least re_laplacian = " + std::to_string(fluid.re_laplacian) + ")");
  const bool two_level = ps.preconditioner == Preconditioner::ssor || ps.preconditioner == Preconditioner::sgs;
  coarse_cell = two_level ? fluid.coarse_size * dp : 0;
  density_tolerance = fluid.density_tolerance;
  preconditioner = std::string(to_string(ps.preconditioner));

  p.add_scalar_field(fluid_fields::pressure, 0.0);
  p.add_scalar_field(fluid_fields::free_surface, 0.0);
  p.add_scalar_field(near_fluid_field, 1.0);
  p.add_scalar_field(work_field, 0.0);
  if (opt.coupled_solid) {
    for (const char* name : {solid_surface_field, solid_reference_field, solid_offset_field}) p.add_scalar_field(name, 0.0);
    for (const char* name : {solid_x_field, solid_v_field}) p.add_vector_field(name);
  }
  for (const auto& [name, spec] : setup.wall_motions) {
    const auto it = std::find_if(p.bodies.begin(), p.bodies.end(), [&](const auto& b) { return b.name == name; });
    if (it == p.bodies.end() || it->kind != ParticleKind::wall)
      throw std::invalid_argument("wall_motions: no wall body '" + name + "' among the particles");
    body_motion.resize(p.bodies.size());
    body_motion[static_cast<std::size_t>(it - p.bodies.begin())] = WallMotion(spec);
  }
  body_state.assign(p.bodies.size(), WallMotionState{});
  if (walls_move() && !p.has_vector_field(wall_reference_field)) {
    auto& reference = p.add_vector_field(wall_reference_field);
    for (std::size_t i = 0; i < p.size(); ++i) reference[i] = p.position[i];
  }
}
Role FluidCore::role(const ParticleKind k) const {
  switch (k) {
    case ParticleKind::fluid: return Role::fluid;
    case ParticleKind::wall: return Role::boundary;
    case ParticleKind::dummy: return Role::dummy;
    case ParticleKind::solid: return opt.solid_as_boundary ? Role::boundary : Role::none;
  }
  return Role::none;
}

// ---- phases of a step, one loop over a neighbour list each ----

void FluidCore::set_solid_boundary(const SolidBoundaryData& data) {
  if (!opt.coupled_solid)
    throw std::logic_error("FluidSolver::set_solid_boundary: the fluid was built without FluidOptions::coupled_solid");
  const std::size_t n_ids = data.ids.size();
  if (data.surface.size() != n_ids || data.position.size() != n_ids || data.velocity.size() != n_ids ||
      data.reference_density.size() != (data.density_offsets ? n_ids : 0))
    throw std::logic_error(fmt::format("FluidSolver::set_solid_boundary: {} ids, {} surface flags, {} positions, {} "
                                       "velocities and {} reference densities (expected one each; no densities "
                                       "without density_offsets)",
                                       n_ids, data.surface.size(), data.position.size(), data.velocity.size(),
                                       data.reference_density.size()));
  if (solid_view_placed) throw std::logic_error("FluidSolver::set_solid_boundary: called within a step");
  const std::vector<LocalIndex> at =
      owned_in_order(p, ParticleKind::solid, data.ids, "FluidSolver::set_solid_boundary");
  auto& surface = p.scalar_field(solid_surface_field);
  auto& reference = p.scalar_field(solid_reference_field);
  auto& view_x = p.vector_field(solid_x_field);
  auto& view_v = p.vector_field(solid_v_field);
  for (std::size_t k = 0; k < at.size(); ++k) {
    const auto i = static_cast<std::size_t>(at[k]);
    surface[i] = data.surface[k] != 0 ? 1.0 : 0.0;
    reference[i] = data.density_offsets ? data.reference_density[k] : 0.0;
    view_x[i] = data.position[k];
    view_v[i] = data.velocity[k];
  }
  solid_boundary = true;
  solid_offsets = data.density_offsets;
  solid_view_new = true;
}

double FluidCore::place_solid_view() {
  if (!solid_view_new) return 0;
  solid_view_new = false;
  swap_solid_view();
  solid_view_placed = true;
  if (!solid_offsets) return 0;
  // The solid's ghosts where the fluid sees them (the view travels with particles that change their rank); a
  // collective: every rank's view has density_offsets alike.
  const auto t0 = Clock::now();
  dist.renew(p, {"position", "velocity"}, ParticleKind::solid);
  const double t_halo = seconds_since(t0);
  solid_x.clear();
  solid_at.clear();
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::solid) {
      solid_x.push_back(p.position[i]);
      solid_at.push_back(static_cast<LocalIndex>(i));
    }
  build_neighbour_list(solid_x, re_g, solid_nl, solid_grid);
  auto& offset = p.scalar_field(solid_offset_field);
  const auto& reference = p.scalar_field(solid_reference_field);
  for (std::size_t k = 0; k < solid_x.size(); ++k) {
    const auto i = static_cast<std::size_t>(solid_at[k]);
    if (i < p.n_owned()) offset[i] = reference[i] - number_density_at(solid_x, solid_nl, re_g, k).n;  // eq. 51
  }
  return t_halo;
}

void FluidCore::release_solid_view() {
  if (!solid_view_placed) return;
  swap_solid_view();
  solid_view_placed = false;
}

void FluidCore::swap_solid_view() {
  // The view's fields travel with their particles when a step moves them to another rank.
  auto& view_x = p.vector_field(solid_x_field);
  auto& view_v = p.vector_field(solid_v_field);
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    if (p.kind[i] == ParticleKind::solid) {
      std::swap(p.position[i], view_x[i]);
      std::swap(p.velocity[i], view_v[i]);
    }
}

void FluidCore::classify() {
  const std::size_t n = p.size();
  roles.resize(n);
  for (std::size_t i = 0; i < n; ++i) roles[i] = role(p.kind[i]);
  // A coupled solid's view: its surface particles are boundary particles, the others dummies.
  if (!solid_boundary) return;
  const auto& surface = p.scalar_field(solid_surface_field);
  for (std::size_t i = 0; i < n; ++i)
    if (p.kind[i] == ParticleKind::solid) roles[i] = surface[i] != 0 ? Role::boundary : Role::dummy;
}

double FluidCore::leave_out_far_walls(const Real reach, const Real dt) {
  const std::size_t n = p.size();
  const auto is_wall = [&](const std::size_t i) {
    return (p.kind[i] == ParticleKind::wall || p.kind[i] == ParticleKind::dummy) && roles[i] != Role::none;
  };
  // The reach grows by the step's moves: the fluid's (prediction and correction) and the walls'.
  Real v2_max = 0;
  bool any_fluid = false;
  Vec lo = Vec::Constant(std::numeric_limits<Real>::max()), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    if (roles[i] == Role::fluid) any_fluid = true;
    if (roles[i] == Role::fluid || is_wall(i)) {
      v2_max = std::max(v2_max, p.velocity[i].squaredNorm());
      lo = lo.cwiseMin(p.position[i]);
      hi = hi.cwiseMax(p.position[i]);
    }
  }
  const Real r = reach + dp + 4.0 * dt * std::sqrt(v2_max);
  // Cells of side r / 2 that hold a fluid particle, grown by two cells along every axis: a point closer than r
  // to a fluid particle lies in a grown cell (its cell differs by at most two along each axis).
  const Real h = 0.5 * r;
  IVec n_cells = IVec::Ones();
  double n_total = 1;
  for (int a = 0; a < dim && any_fluid; ++a) {
    n_cells[a] = static_cast<int>(std::min(1e9, std::floor((hi[a] - lo[a]) / h))) + 1;
    n_total *= n_cells[a];
  }
  auto& near_fluid = p.scalar_field(near_fluid_field);
  // A rank without fluid, or a grid larger than the particles (spread out, or a reach of a few spacings in a
  // huge domain), keeps every wall.
  const bool keep_all = !any_fluid || !(n_total <= 4.0 * static_cast<double>(n) + 1024);
  if (!keep_all) {
    const auto cell_of = [&](const Vec& x) {
      std::size_t k = 0;
      for (int a = dim - 1; a >= 0; --a)
        k = k * static_cast<std::size_t>(n_cells[a]) +
            static_cast<std::size_t>(std::clamp(static_cast<int>((x[a] - lo[a]) / h), 0, n_cells[a] - 1));
      return k;
    };
    std::vector<std::uint8_t> cells(static_cast<std::size_t>(n_total), 0), grown;
    for (std::size_t i = 0; i < n; ++i)
      if (roles[i] == Role::fluid) cells[cell_of(p.position[i])] = 1;
    std::size_t stride = 1;
    for (int a = 0; a < dim; ++a) {  // grown along axis a by two cells
      grown = cells;
      const auto m = static_cast<std::size_t>(n_cells[a]);
      for (std::size_t k = 0; k < cells.size(); ++k) {
        if (!cells[k]) continue;
        const std::size_t c = (k / stride) % m;
        for (std::size_t d = 1; d <= 2; ++d) {
          if (c >= d) grown[k - d * stride] = 1;
          if (c + d < m) grown[k + d * stride] = 1;
        }
      }
      cells.swap(grown);
      stride *= m;
    }
    for (std::size_t i = 0; i < n; ++i)
      near_fluid[i] = is_wall(i) && cells[cell_of(p.position[i])] ? 1.0 : 0.0;
  } else {
    for (std::size_t i = 0; i < n; ++i) near_fluid[i] = 1.0;
  }
  // A particle that some rank needs takes part on every rank that holds it.
  double t_halo = 0;
  if (dist.n_ranks() > 1) {
    const auto t0 = Clock::now();
    dist.reverse_sum(p, {near_fluid_field});
    dist.exchange_ghosts(p, {near_fluid_field});
    t_halo = seconds_since(t0);
  }
  for (std::size_t i = 0; i < n; ++i)
    if (is_wall(i) && near_fluid[i] == 0) roles[i] = Role::none;
  return t_halo;
}

void FluidCore::note_work() {
  auto& work = p.scalar_field(work_field);
  const std::size_t n = p.n_owned();
  const std::size_t n_near = std::min(n, near.n_particles()), n_wide = std::min(n, nl.n_particles());
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t pairs = (i < n_near ? near.count(i) : 0) + (i < n_wide ? nl.count(i) : 0);
    work[i] = roles[i] == Role::none ? 0.0 : static_cast<Real>(pairs);
  }
}

/// Walls and their dummy layers follow the tank motion (rotation about the pivot, v = omega x r) or their own.
void FluidCore::move_walls(const Real t) {
  if (!walls_move()) return;
  const auto& reference = p.vector_field(wall_reference_field);
  if (motion.moving()) {
    const auto [theta, omega] = motion.at(t);
    wall_omega = omega;
    wall_theta = theta;
    const Mat r = motion.matrix(theta);
    for (auto& m : body_state) m.rotation = r;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (p.kind[i] != ParticleKind::wall && p.kind[i] != ParticleKind::dummy) continue;
      p.position[i] = motion.place(reference[i], theta);
      p.velocity[i] = motion.velocity_at(p.position[i], omega);
    }
    return;
  }
  // Each body's motion once per step, then its points.
  for (std::size_t b = 0; b < body_motion.size(); ++b)
    if (body_motion[b].moving()) body_state[b] = body_motion[b].at(t);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.kind[i] != ParticleKind::wall && p.kind[i] != ParticleKind::dummy) continue;
    if (!body_motion[p.body[i]].moving()) continue;
    const WallMotionState& m = body_state[p.body[i]];
    p.position[i] = m.place(reference[i]);
    p.velocity[i] = m.velocity_of(reference[i]);
  }
}

const Mat& FluidCore::wall_rotation(const std::size_t j) const { return body_state[p.body[j]].rotation; }

/// Eq. 12, 16, 17: v* = v + dt (nu lap v + g), r* = r + dt v* for fluid particles. With lateral-wall
/// friction k (fluid.lateral_walls), the velocity relative to the tank then decays exactly over the step:
/// v* = v_wall + (v* - v_wall) exp(-k dt), v_wall the rigid velocity of the tank at the particle.
void FluidCore::predict(const Real dt) {
  const std::size_t n = p.n_owned();
  const Real a = 2.0 * dim / (lat_l.lambda * lat_l.n0);
  const Real decay = std::exp(-lateral_friction * dt);
  const bool friction = lateral_friction > 0;
  const auto takes_part = [&](const std::size_t j) { return roles[j] != Role::none; };
  // The Laplacian of the velocities at the start of the step, for every particle before any moves.
  dv.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    dv[i] = roles[i] == Role::fluid && nu > 0 ? laplacian_sum_at(p.position, nl, re_l, i, p.velocity, takes_part)
                                              : Vec::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    if (roles[i] != Role::fluid) continue;
    p.velocity[i] += dt * (nu * a * dv[i] + gravity);
    if (friction) {
      const Vec v_wall = motion.moving() ? motion.velocity_at(p.position[i], wall_omega) : Vec::Zero();
      p.velocity[i] = v_wall + decay * (p.velocity[i] - v_wall);
    }
    p.position[i] += dt * p.velocity[i];
  }
}

void FluidCore::build_wide_list(const bool row_particles) {
  const std::size_t n = p.n_owned();
  wide_row.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    wide_row[i] = (roles[i] == Role::fluid && nu > 0) || (row_particles && has_row(roles[i]));
  takes_part.resize(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) takes_part[i] = roles[i] != Role::none;
  // The ghosts come after the owned particles: a row sorts its ghost neighbours apart (the same rows).
  build_neighbour_list_masked(p.position, re_l, nl, grid, n, wide_row, takes_part, std::min(cell_size, re_l), false,
                              nullptr, p.n_owned());
}

void FluidCore::build_near_list(const Real radius, const std::function<bool(Role)>& ghost_needs_row,
                                const std::optional<Real> predicted_dt) {
  takes_part.resize(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) takes_part[i] = roles[i] != Role::none;
  // The scheme's answer once per role (indexed by Role; none takes no part).
  static_assert(static_cast<int>(Role::dummy) == 2 && static_cast<int>(Role::none) == 3);
  const bool ghost_row[] = {ghost_needs_row(Role::fluid), ghost_needs_row(Role::boundary), ghost_needs_row(Role::dummy),
                            false};
  const std::size_t n = ghost_row[0] || ghost_row[1] || ghost_row[2] ? p.size() : p.n_owned();
  near_row.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    near_row[i] = takes_part[i] && (i < p.n_owned() || ghost_row[static_cast<std::size_t>(roles[i])]);
  // The wide list's rows (fluid particles) hold their near rows when the wide radius covers the near one plus
  // both particles' moves since it was built: predict moved the fluid particles (owned and ghosts) by dt v.
  bool reuse = false;
  if (predicted_dt) {
    Real v2_max = 0;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (roles[i] == Role::fluid) v2_max = std::max(v2_max, p.velocity[i].squaredNorm());
    reuse = re_l > radius + 2.0 * 1.01 * *predicted_dt * std::sqrt(v2_max);
  }
  const WiderRows wider{nl, wide_row};
  build_neighbour_list_masked(p.position, radius, near, near_grid, n, near_row, takes_part, std::min(cell_size, radius),
                              true, reuse ? &wider : nullptr, p.n_owned());
}

/// Collision model (MPS-Basic collision()): approaching pairs closer than the collision distance
/// exchange momentum along their line with restitution e; boundaries have infinite mass.
void FluidCore::collide(const Real dt) {
  const Real dc2 = std::pow(opt.collision_distance * dp, 2);
  const std::size_t n = p.n_owned();
  v_new.resize(n);
  for (std::size_t i = 0; i < n; ++i) v_new[i] = p.velocity[i];
  for (std::size_t i = 0; i < n; ++i) {
    if (roles[i] != Role::fluid) continue;
    const Vec xi = p.position[i], vi = p.velocity[i];
    for (std::size_t k = near.begin(i); k < near.end(i); ++k) {
      const auto j = static_cast<std::size_t>(near.index[k]);
      const Vec rij = p.position[j] - xi;
      const Real r2 = rij.squaredNorm();
      if (r2 >= dc2) continue;
      const Real r = std::sqrt(r2);
      const Vec e = rij / r;
      const Real approach = (vi - p.velocity[j]).dot(e);
      if (approach <= 0) continue;
      const Real share = roles[j] == Role::fluid ? 0.5 : 1.0;  // equal masses, or a wall
      v_new[i] -= (1 + opt.restitution) * share * approach * e;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (roles[i] != Role::fluid) continue;
    p.position[i] += dt * (v_new[i] - p.velocity[i]);
    p.velocity[i] = v_new[i];
  }
}

/// Eq. 8 at the predicted positions: n*, the neighbour count N, and the free-surface double check.
void FluidCore::density_and_surface(const bool keep_surface) {
  const std::size_t n = p.n_owned();
  const bool warm_start = keep_surface && n_steps > 0;
  n_star.resize(n);
  auto& surface = p.scalar_field(fluid_fields::free_surface);
  const std::vector<Real>* offset = solid_offsets ? &p.scalar_field(solid_offset_field) : nullptr;
  for (std::size_t i = 0; i < n; ++i) {
    // The near list holds exactly the pairs within re_g of particles that take part.
    const DensityAndCount d = roles[i] != Role::none ? number_density_at(p.position, near, re_g, i) : DensityAndCount{};
    Real ni = d.n;
    if (offset && roles[i] == Role::boundary) ni += (*offset)[i];
    n_star[i] = ni;
    const bool geometric = has_row(roles[i]) && ni < beta1 * lat_g.n0 && d.count < beta2 * lat_g.n_neighbours;
    // The projection starts from the last step's active set (update_active_set), and the geometric test adds
    // the particles that left the water.
    const bool kept = warm_start && surface[i] != 0;
    surface[i] = has_row(roles[i]) && (geometric || kept) ? 1.0 : 0.0;
  }
}


void FluidCore::number_rows(const Real dt) {
  const std::size_t n = p.size(), n_own = p.n_owned();
  row_of.resize(n);
  particle_of_row.clear();
  sys.row_id.clear();
  sys.remote_id.clear();
  sys.remote_rank.clear();
  for (std::size_t i = 0; i < n_own; ++i) {
    row_of[i] = has_row(roles[i]) ? static_cast<LocalIndex>(particle_of_row.size()) : -1;
    if (row_of[i] >= 0) {
      particle_of_row.push_back(static_cast<LocalIndex>(i));
      sys.row_id.push_back(p.global_id[i]);
    }
  }
  const std::size_t n_rows = particle_of_row.size();
  for (std::size_t j = n_own; j < n; ++j) {
    row_of[j] = has_row(roles[j]) ? static_cast<LocalIndex>(n_rows + sys.remote_id.size()) : -1;
    if (row_of[j] >= 0) {
      sys.remote_id.push_back(p.global_id[j]);
      sys.remote_rank.push_back(dist.ghost_owner(j - n_own));
    }
  }
  sys.group.clear();
  if (coarse_cell > 0) {  // the coarse groups: cells of side coarse_cell and owner, the same on every rank
    for (std::size_t r = 0; r < n_rows; ++r)
      sys.group.push_back(group_key(p.position[static_cast<std::size_t>(particle_of_row[r])], coarse_cell, dist.rank()));
    for (std::size_t j = n_own; j < n; ++j)
      if (row_of[j] >= 0) sys.group.push_back(group_key(p.position[j], coarse_cell, dist.ghost_owner(j - n_own)));
  }
  // ||r||_2 <= eta rho / dt^2 sqrt(n_rows): RMS over the rows of r dt^2 / rho below eta.
  unsigned long long n_rows_global = n_rows;
  MPI_Allreduce(MPI_IN_PLACE, &n_rows_global, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm);
  const Real eta = std::min(density_tolerance, density_tolerance_cap);
  sys.absolute_tolerance = eta * rho / (dt * dt) * std::sqrt(static_cast<Real>(n_rows_global));
  sys.row_ptr.resize(n_rows + 1);
  sys.rhs.resize(n_rows);
}

/// Refreshes these fields at the ghosts from their owners.
void FluidCore::refresh_ghosts(const std::vector<std::string>& fields, FluidStepReport& report,
                               const std::optional<ParticleKind> only) {
  const auto t0 = Clock::now();
  dist.exchange_ghosts(p, fields, only);
  report.t_halo += seconds_since(t0);
}

namespace {

/// The wall cell a point is deepest in: the wall or dummy particle, the depth behind its surface plane and the
/// plane's normal (towards the fluid); particle == none when the point is in no cell.
struct WallCell {
  std::size_t particle;
  Real depth = 0;
  Vec normal = Vec::Zero();
};

}  // namespace

/// A wall or dummy particle j stands for the lattice cell of side dp around it (the wall's solid region is the union
/// of these cells); a fluid particle i inside one or on its boundary (|x_i - x_j| <= dp/2 along each of the tank's
/// axes: a particle on a face that another wall body covers is still in that body's cells) is moved along
/// the cell's offset s_j to the wetted surface, past the plane through x_j + s_j normal to s_j by the restitution's
/// share of its depth behind it (a bounce: the position is reflected as the velocity is, so that particles put back
/// into a concave corner between two walls do not all land on the corner's point or edge). Of the cells that hold
/// it the one it is deepest in is taken (then the lowest global id), so that the result does not depend on the
/// order of the neighbours (on the number of ranks). A particle in a corner cell may land in a neighbouring cell:
/// up to `passes` cells are handled in turn.
///
/// A face that is not on the lattice (a slope, a curve) leaves the cells short of it: between the cells of the
/// lattice points inside the surface and the surface itself lie gaps that are no cell's. A particle in no cell
/// goes back to the surface plane of a wall or dummy particle j within 2 dp if it lies behind that plane by at
/// most dp and over j's patch of the surface (within 1.5 dp of x_j + s_j along the plane, 1.5 dp sqrt(2) in 3D),
/// unless a plane it is in front of closes the wall there: a particle k within 2 dp whose surface point and j's
/// lie each behind or on the other's plane (a convex edge or corner, where the wall is the intersection of the two
/// sides, not their union). Of such j the one whose surface point is nearest is taken (then the lowest global id).
/// On the lattice every point behind a face and over a patch is in a cell, so walls whose faces lie on the
/// lattice are kept by the cells alone.
std::size_t FluidCore::keep_out_of_walls() {
  if (!p.has_vector_field(wall_surface_field)) return 0;
  constexpr int passes = 3;
  const auto& to_surface = p.vector_field(wall_surface_field);
  const bool moving = walls_move();
  const Real half = 0.5 * dp, reach2 = dim * half * half;
  const Real face_reach2 = 4 * dp * dp, patch2 = 2.25 * (dim - 1) * dp * dp, on_plane = 1e-9 * dp;
  const std::size_t none = p.size();
  std::vector<std::size_t> near_walls;  // the wall and dummy particles within 2 dp of the particle
  std::vector<Vec> offsets;  // their offsets to the surface, as the walls stand now
  std::vector<std::pair<Vec, Vec>> surface_points;  // their surface points and normals
  const auto deepest_cell = [&](const std::size_t i) {
    WallCell cell{none};
    near_walls.clear();
    offsets.clear();
    for (std::size_t k = near.begin(i); k < near.end(i); ++k) {
      const auto j = static_cast<std::size_t>(near.index[k]);
      if (p.kind[j] != ParticleKind::wall && p.kind[j] != ParticleKind::dummy) continue;
      const Vec d = p.position[i] - p.position[j];
      const Real d2 = d.squaredNorm();
      if (d2 >= face_reach2) continue;
      assert(!to_surface[j].isZero() && "every wall and dummy particle has its offset to the surface");
      near_walls.push_back(j);
      offsets.push_back(moving ? Vec(wall_rotation(j) * to_surface[j]) : to_surface[j]);
      if (d2 >= reach2) continue;
      if ((moving ? Vec(wall_rotation(j).transpose() * d) : d).cwiseAbs().maxCoeff() > half) continue;
      const Vec& s = offsets.back();
      const Vec n = s.normalized();
      const Real depth = (s - d).dot(n);
      if (depth <= 0) continue;
      if (cell.particle == none || depth > cell.depth ||
          (depth == cell.depth && p.global_id[j] < p.global_id[cell.particle]))
        cell = {j, depth, n};
    }
    if (cell.particle != none || near_walls.empty()) return cell;
    // In no cell: the gaps between the cells and a face off the lattice.
    surface_points.clear();
    for (std::size_t q = 0; q < near_walls.size(); ++q)
      surface_points.push_back({p.position[near_walls[q]] + offsets[q], offsets[q].normalized()});
    const auto behind = [&](const Vec& x, const std::size_t q) {  // x's depth behind the plane of near_walls[q]
      return (surface_points[q].first - x).dot(surface_points[q].second);
    };
    WallCell gap{none};
    Real gap_distance2 = 0;
    for (std::size_t q = 0; q < near_walls.size(); ++q) {
      const Real depth = behind(p.position[i], q);
      if (depth <= 0 || depth > dp) continue;
      const Vec e = surface_points[q].first - p.position[i];
      if ((e - depth * surface_points[q].second).squaredNorm() > patch2) continue;
      const std::size_t j = near_walls[q];
      const Real distance2 = e.squaredNorm();
      if (gap.particle != none && (distance2 > gap_distance2 ||
                                   (distance2 == gap_distance2 && p.global_id[j] >= p.global_id[gap.particle])))
        continue;
      bool convex_edge = false;  // a plane in front of i that closes the wall with this one
      for (std::size_t k = 0; k < near_walls.size() && !convex_edge; ++k)
        convex_edge = behind(p.position[i], k) <= 0 && behind(surface_points[k].first, q) >= -on_plane &&
                      behind(surface_points[q].first, k) >= -on_plane;
      if (convex_edge) continue;
      gap = {j, depth, surface_points[q].second};
      gap_distance2 = distance2;
    }
    return gap;
  };
  std::size_t n_put_back = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    if (roles[i] != Role::fluid) continue;
    int pass = 0;
    for (WallCell cell = deepest_cell(i); cell.particle != none && pass < passes; cell = deepest_cell(i), ++pass) {
      p.position[i] += (1 + opt.restitution) * cell.depth * cell.normal;
      const Real approach = (p.velocity[i] - p.velocity[cell.particle]).dot(cell.normal);
      if (approach < 0) p.velocity[i] -= (1 + opt.restitution) * approach * cell.normal;
    }
    n_put_back += pass > 0;
  }
  return n_put_back;
}

/// Fluid particles outside the case's domain are removed (with the ghosts, which are then renewed at the
/// next step).
std::size_t FluidCore::remove_escaped() {
  const std::size_t n = p.n_owned();
  remove.assign(n, 0);
  std::size_t n_out = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (p.kind[i] == ParticleKind::fluid && !domain.contains(p.position[i])) {
      remove[i] = 1;
      ++n_out;
    }
  if (n_out > 0) {
    p.drop_ghosts();
    p.remove_if(remove);
  }
  return n_out;
}


}  // namespace mpsfsi::fluid_detail
