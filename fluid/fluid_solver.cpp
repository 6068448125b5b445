// Semi-implicit MPS fluid step (seed 004 §4.1, §4.3, §4.6): weight and number density (eq. 7-8),
// Laplacian (eq. 12-13) for the viscosity and the PPE, explicit prediction (eq. 16-17), collision model,
// number density n* (eq. 18), free surface by the double check (§4.3), the PPE with weak compressibility
// and relaxation (eq. 22-23; the alpha term enters the matrix as 1/(c^2 dt^2), see
// docs/architecture.md, ## Numerical choices), the correction (eq. 19, 24) with the minimum-pressure gradient
// (eq. 9 with p_min) or the corrected gradient (eq. 14-15), and the time-step control (eq. 52 plus the viscous
// limit).
// The default scheme replaces the PPE and the correction by the projection of the number density (section
// "the exact projection" below; fluid/fluid_parameters.hpp FluidScheme).
// Each rank advances the particles it owns (core/distribution.hpp): at the start of a step the owners
// are updated and the ghosts rebuilt; each phase refreshes at the ghosts the fields the next one reads.
// The PPE rows are the owned particles with a pressure unknown, named by their global ids.
#include "fluid/fluid_solver.hpp"

#include "core/binary_io.hpp"
#include "core/buffers.hpp"
#include "core/distribution.hpp"
#include "core/kernel.hpp"
#include "core/neighbours.hpp"
#include "core/operators.hpp"
#include "core/ramp.hpp"
#include "core/stopwatch.hpp"
#include "fluid/pressure_solver.hpp"

#include <Eigen/LU>
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

namespace {

/// What a particle does in the fluid computation.
enum class Role : std::uint8_t {
  fluid,     ///< moves with the fluid equations, PPE row
  boundary,  ///< prescribed position and velocity, PPE row (wall particles; solids when coupled)
  dummy,     ///< counts in the number density only
  none       ///< ignored (solids when not coupled)
};

inline bool has_row(const Role r) { return r == Role::fluid || r == Role::boundary; }

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

struct FluidSolver::Impl {
  Impl(const FluidSetup& setup, ParticleSet& particles, Distribution& distribution, const FluidOptions& options)
      : p(particles), dist(distribution), opt(options), motion(make_tank_motion(setup.tank_motion)) {
    const FluidParameters& fluid = setup.parameters;
    comm = dist.comm();
    rank = dist.rank();
    dp = setup.dp;
    re_g = fluid.re_gradient * dp;
    re_l = fluid.re_laplacian * dp;
    r_max = std::max(re_g, re_l);
    lat_g = lattice_constants(dp, re_g);
    lat_l = lattice_constants(dp, re_l);
    beta1 = fluid.beta1;
    beta2 = fluid.beta2;
    corrected = fluid.gradient == PressureGradient::corrected;
    projection = fluid.scheme == FluidScheme::projection;
    max_active_set_solves = fluid.max_active_set_solves;
    stabilisation = fluid.projection_stabilisation;
    kernel = fluid.projection_kernel;
    re_p = fluid.projection_radius * dp;
    if (projection) r_max = std::max(r_max, re_p);
    const KernelSums sums = lattice_sums(kernel, dp, re_p);
    n0_kernel = sums.n0;
    c_lattice = sums.c;
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
    if (projection) {
      p.add_scalar_field(reference_density_field, 0.0);
      p.add_scalar_field(rest_offset_field, 0.0);
      p.add_scalar_field(rest_rate_field, 0.0);
    }
    if (motion.moving() && !p.has_vector_field(wall_reference_field)) {
      auto& reference = p.add_vector_field(wall_reference_field);
      for (std::size_t i = 0; i < p.size(); ++i) reference[i] = p.position[i];
    }
  }

  /// The particle field that holds each wall particle's position in the tank's rest frame (moving tanks).
  static constexpr const char* wall_reference_field = "wall_reference";
  /// The projection: in the initial state, each dummy particle's number density (its wall group's reference),
  /// and each wall or solid particle's number density from its neighbours that are not fluid (the boundary
  /// part of its row's density, held at that value: the walls' and solids' own motion is no density change).
  static constexpr const char* reference_density_field = "reference_density";
  /// The projection: each row particle's number density offset o = o_0 + o_2 dt^2 that makes the initial
  /// state the scheme's equilibrium under the initial pressure at any dt (start_from_rest): o_0 here, o_2 in
  /// rest_rate_field [1/s^2].
  static constexpr const char* rest_offset_field = "rest_offset";
  static constexpr const char* rest_rate_field = "rest_rate";

  /// The projection, first step, at the initial positions: the reference densities (reference_density_field),
  /// and each row's density error before the step moves anything (initial_error, by the rows' definition of
  /// build_gram).
  void reference_densities() {
    auto& reference = p.scalar_field(reference_density_field);
    initial_error.assign(p.n_owned(), 0.0);
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (roles[i] == Role::none) continue;
      Real n_fluid_i = 0, n_other = 0;  // the kernel density from the fluid neighbours, from the others
      for_each_pair(p.position, nl, re_p, i, [&](const std::size_t j) { return roles[j] != Role::none; },
                    [&](const std::size_t j, const Vec&, const Real r2, Real) {
                      (roles[j] == Role::fluid ? n_fluid_i : n_other) += kernel_at(kernel, std::sqrt(r2), re_p).w;
                    });
      initial_error[i] = n_fluid_i + n_other - n0_kernel;
      if (p.kind[i] == ParticleKind::dummy) reference[i] = n_fluid_i + n_other;
      else if (roles[i] != Role::fluid) reference[i] = n_other;
    }
  }

  Role role(const ParticleKind k) const {
    switch (k) {
      case ParticleKind::fluid: return Role::fluid;
      case ParticleKind::wall: return Role::boundary;
      case ParticleKind::dummy: return Role::dummy;
      case ParticleKind::solid: return opt.solid_as_boundary ? Role::boundary : Role::none;
    }
    return Role::none;
  }

  // ---- phases of a step, one loop over a neighbour list each ----

  void classify() {
    const std::size_t n = p.size();
    roles.resize(n);
    for (std::size_t i = 0; i < n; ++i) roles[i] = role(p.kind[i]);
    // Coupled solids: flagged (surface) particles are boundary particles, the others dummies.
    if (opt.boundary_flag_field.empty() || !p.has_scalar_field(opt.boundary_flag_field)) return;
    const auto& flag = p.scalar_field(opt.boundary_flag_field);
    for (std::size_t i = 0; i < n; ++i)
      if (p.kind[i] == ParticleKind::solid) roles[i] = flag[i] != 0 ? Role::boundary : Role::dummy;
  }

  /// Walls and their dummy layers follow the tank motion: rotation about the pivot, v = omega x r.
  void move_walls(const Real t) {
    if (!motion.moving()) return;
    const auto [theta, omega] = motion.at(t);
    wall_omega = omega;
    const auto& reference = p.vector_field(wall_reference_field);
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (p.kind[i] != ParticleKind::wall && p.kind[i] != ParticleKind::dummy) continue;
      p.position[i] = motion.place(reference[i], theta);
      p.velocity[i] = motion.velocity_at(p.position[i], omega);
    }
  }

  /// Eq. 12, 16, 17: v* = v + dt (nu lap v + g), r* = r + dt v* for fluid particles. With lateral-wall
  /// friction k (fluid.lateral_walls), the velocity relative to the tank then decays exactly over the step:
  /// v* = v_wall + (v* - v_wall) exp(-k dt), v_wall the rigid velocity of the tank at the particle.
  void predict(const Real dt) {
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

  /// Pairs within re_g at the predicted positions (a filtered copy of the big list).
  void build_near_list() {
    // The projection also needs the rows of the ghosts (their dn/dx in the pressure rows of their neighbours).
    const std::size_t n = projection ? p.size() : p.n_owned();
    // The projection's kernel may reach further than re_g (fluid.projection_radius).
    near.radius = projection ? std::max(re_g, re_p) : re_g;
    near.support_only = true;
    near.offset.resize(n + 1);
    // An upper bound; not trimmed (n_pairs() = offset.back()), so that the next step need not zero-fill it.
    if (near.index.size() < nl.n_pairs()) resize_with_headroom(near.index, nl.n_pairs());
    near.offset[0] = 0;
    std::size_t m = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec xi = p.position[i];
      if (roles[i] != Role::none)
        for (std::size_t k = nl.begin(i); k < nl.end(i); ++k) {
          const LocalIndex j = nl.index[k];
          const bool keep = roles[static_cast<std::size_t>(j)] != Role::none &&
                            in_support((p.position[static_cast<std::size_t>(j)] - xi).squaredNorm(), near.radius);
          near.index[m] = j;  // branch-free append
          m += keep;
        }
      near.offset[i + 1] = m;
    }
  }

  /// Collision model (MPS-Basic collision()): approaching pairs closer than the collision distance
  /// exchange momentum along their line with restitution e; boundaries have infinite mass.
  void collide(const Real dt) {
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
  void density_and_surface() {
    const std::size_t n = p.n_owned();
    const bool warm_start = projection && n_steps > 0;
    n_star.resize(n);
    auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::vector<Real>* offset = nullptr;
    if (!opt.density_offset_field.empty() && p.has_scalar_field(opt.density_offset_field))
      offset = &p.scalar_field(opt.density_offset_field);
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
    if (!projection) return;
    // A wall or solid row with no fluid particle within the kernel's reach constrains nothing that moves: it is
    // a free-surface row (p = 0) and stays one until the water reaches it.
    dry.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (roles[i] != Role::boundary) continue;
      bool wet = false;
      for (std::size_t q = near.begin(i); q < near.end(i) && !wet; ++q)
        wet = roles[static_cast<std::size_t>(near.index[q])] == Role::fluid;
      dry[i] = !wet;
      if (!wet) surface[i] = 1;
    }
  }

  /// Eq. 23 assembled for this rank's rows (its owned particles with a pressure unknown): -lap P + P / (c^2
  /// dt^2) = kappa rho / dt^2 (n* - n0) / n0, with p = 0 rows (free surface) as identity rows dropped from
  /// the other rows' columns (keeps symmetry). Ghosts with a pressure unknown are the remote columns.
  void assemble(const Real dt) {
    const std::size_t n = p.size(), n_own = p.n_owned();
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
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
    if (projection) {
      assemble_projection(dt);
      return;
    }
    // Upper bound of the entries: each row's neighbours plus its diagonal; trimmed at the end.
    std::size_t max_entries = 0;
    for (std::size_t r = 0; r < n_rows; ++r) max_entries += nl.count(static_cast<std::size_t>(particle_of_row[r])) + 1;
    resize_with_headroom(sys.col, max_entries);
    resize_with_headroom(sys.value, max_entries);
    std::size_t m = 0;  // entries written
    sys.row_ptr[0] = 0;
    const Real a = 2.0 * dim / (lat_l.lambda * lat_l.n0);
    const Real compress = 1.0 / (c * c * dt * dt);
    const Real source = kappa * rho / (dt * dt) / lat_g.n0;
    const Real dirichlet_diag = a * lat_l.n0 + compress;
    const auto is_row = [&](const std::size_t j) { return has_row(roles[j]); };
    for (std::size_t r = 0; r < n_rows; ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      const auto me = static_cast<LocalIndex>(r);
      if (surface[i] != 0) {
        sys.col[m] = me;
        sys.value[m++] = dirichlet_diag;
        sys.rhs[r] = 0;
        sys.row_ptr[r + 1] = m;
        continue;
      }
      Real diag = compress;
      std::size_t diag_pos = std::numeric_limits<std::size_t>::max();
      // Row i of eq. 12's Laplacian (pair weights a w_ij) over the neighbours with pressure rows; the list is
      // sorted by local index and row_of increases with it, so the columns come out sorted.
      for_each_pair(p.position, nl, re_l, i, is_row, [&](const std::size_t j, const Vec&, Real, const Real w) {
        const Real coef = a * w;
        diag += coef;
        if (surface[j] != 0) return;
        if (diag_pos == std::numeric_limits<std::size_t>::max() && j > i) {
          diag_pos = m;
          sys.col[m] = me;
          sys.value[m++] = 0;
        }
        sys.col[m] = row_of[j];
        sys.value[m++] = -coef;
      });
      if (diag_pos == std::numeric_limits<std::size_t>::max()) {
        diag_pos = m;
        sys.col[m] = me;
        sys.value[m++] = 0;
      }
      sys.value[diag_pos] = diag;
      sys.rhs[r] = source * (n_star[i] - lat_g.n0);
      sys.row_ptr[r + 1] = m;
    }
    sys.col.resize(m);
    sys.value.resize(m);
  }

  // ---- the exact projection (fluid.scheme = projection; fluid/fluid_parameters.hpp) ----

  /// dn_k/dx_k at every particle with a row in the near list (owned and ghosts), with the projection's kernel,
  /// and the scale d / C of the force, C the mean over the interior fluid particles of sum_j -w'(r_ij) r_ij
  /// (sum_j re / r_ij = n0 + N0 on the lattice for the MPS weight), so that -(d/C) N^T p is -grad p for a
  /// linear pressure on the current arrangement.
  void projection_geometry() {
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::size_t n = near.n_particles();
    // The near list holds the pairs within re_g of particles that take part (build_near_list): entry q of
    // row k, neighbour j, gets dn_j/dx_k; by the symmetry of w, dn_k/dx_k is their sum.
    // Also the kernel's number density n_k and sum_j -w'(r_jk) r_jk (C of the particle).
    dn_pair.resize(near.n_pairs());
    dn_self.resize(n);
    n_kernel.resize(n);
    n_fluid.resize(n);
    c_of.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      Vec s = Vec::Zero();
      Real n_k = 0, n_f = 0, c_k = 0;
      for (std::size_t q = near.begin(k); q < near.end(k); ++q) {
        const auto j = static_cast<std::size_t>(near.index[q]);
        const Vec r_jk = p.position[k] - p.position[j];
        const Real r = r_jk.norm();
        const KernelValue kv = kernel_at(kernel, r, re_p);
        dn_pair[q] = (kv.dw / r) * r_jk;
        s += dn_pair[q];
        n_k += kv.w;
        if (roles[j] == Role::fluid) n_f += kv.w;
        c_k -= kv.dw * r;
      }
      dn_self[k] = s;
      n_kernel[k] = n_k;
      n_fluid[k] = n_f;
      c_of[k] = c_k;
    }
    Real sums[2] = {0, 0};  // sum over the interior fluid particles of sum_j -w'(r_ij) r_ij, their count
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (roles[i] != Role::fluid || surface[i] != 0) continue;
      sums[0] += c_of[i];
      sums[1] += 1;
    }
    MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_DOUBLE, MPI_SUM, comm);
    const Real c_sum = sums[1] > 0 ? sums[0] / sums[1] : c_lattice;
    projection_scale = dim / c_sum;
    wall_groups();
    surface_pressures();
  }

  /// The wall groups: each dummy particle within re_g of a wall particle joins the group of the nearest one
  /// (ties to the smaller global id, so that every rank that holds both decides alike). A group shares the
  /// wall particle's pressure unknown: the dummies carry its pressure in the force, and the group's row
  /// constrains the sum of its members' number densities (each against its initial value). Without it the
  /// dummies push with p = 0, and water at rest on the lattice feels a net force of up to 2.3 g toward the
  /// walls (docs/validation.md, ## Fluid).
  void wall_groups() {
    const std::size_t n = near.n_particles();
    parent_of.assign(n, -1);
    group_error.assign(n, 0.0);
    const auto& reference = p.scalar_field(reference_density_field);
    for (std::size_t m = 0; m < n; ++m) {
      if (p.kind[m] != ParticleKind::dummy || roles[m] != Role::dummy) continue;
      Real best = std::numeric_limits<Real>::max();
      GlobalId best_id = 0;
      for (std::size_t q = near.begin(m); q < near.end(m); ++q) {
        const auto j = static_cast<std::size_t>(near.index[q]);
        const Real r2 = (p.position[j] - p.position[m]).squaredNorm();
        if (p.kind[j] != ParticleKind::wall || roles[j] != Role::boundary) continue;
        if (r2 < best * (1 - 1e-12) || (r2 <= best * (1 + 1e-12) && p.global_id[j] < best_id)) {
          best = r2;
          best_id = p.global_id[j];
          parent_of[m] = static_cast<LocalIndex>(j);
        }
      }
      if (parent_of[m] >= 0) group_error[m] = n_kernel[m] - reference[m];
    }
  }

  /// The pressure unknown (local column) of particle j: its own row, its wall group's, or none (-1).
  LocalIndex column_of(const std::size_t j) const {
    if (row_of[j] >= 0) return row_of[j];
    if (j < parent_of.size() && parent_of[j] >= 0) return row_of[static_cast<std::size_t>(parent_of[j])];
    return -1;
  }

  /// The projection's operator over this rank's rows (every row particle, whatever its free-surface flag),
  /// (1 - alpha) G + alpha s L_g. G = (d/C) N N^T / n0, N_ik = dn_i/dx_k over the fluid particles k (the ones
  /// the force moves). L_g is minus the Laplacian of eq. 12 at re_gradient over the row neighbours (pair
  /// weights 2d w_ij / (lambda n0)), s = C / (d n0) its factor to G's long-wave limit, so that alpha changes
  /// neither a smooth pressure nor the hydrostatic one in the bulk, and damps the oscillating pressures that G
  /// alone leaves free (N^T p of a checkerboard p is nearly zero). Built once per step, after the rows are
  /// numbered (assemble), and filtered by the active set at each solve.
  void build_gram(const Real dt) {
    const std::size_t n_rows = particle_of_row.size();
    const auto& rest_offset = p.scalar_field(rest_offset_field);
    const auto& rest_rate = p.scalar_field(rest_rate_field);
    const auto& reference = p.scalar_field(reference_density_field);
    const std::size_t n_columns = n_rows + sys.remote_id.size();
    acc.assign(n_columns, 0.0);
    lap_acc.assign(n_columns, 0.0);
    touched_flag.assign(n_columns, 0);
    touched.clear();
    gram_ptr.assign(n_rows + 1, 0);
    gram_col.clear();
    gram_val.clear();
    column_particle.assign(n_columns, 0);
    for (std::size_t j = 0; j < p.size(); ++j)
      if (row_of[j] >= 0) column_particle[static_cast<std::size_t>(row_of[j])] = static_cast<LocalIndex>(j);
    const Real scale = (1.0 - step_alpha) * projection_scale / n0_kernel;
    const Real lap_scale = step_alpha / (projection_scale * n0_kernel) * (2.0 * dim / (lat_g.lambda * lat_g.n0));
    const auto add_column = [&](const std::size_t col, const Real v) {
      if (!touched_flag[col]) {
        touched_flag[col] = 1;
        touched.push_back(static_cast<LocalIndex>(col));
      }
      acc[col] += v;
    };
    const auto add = [&](const std::size_t j, const Real v) { add_column(static_cast<std::size_t>(row_of[j]), v); };
    const auto add_laplacian_column = [&](const std::size_t col, const Real v) {
      add_column(col, 0.0);
      lap_acc[col] += v;
    };
    // Moving k (N_ik given) adds N_ik . N_jk to the entries (i, j): j = k and the row neighbours j of k
    // (dn_pair of row k's entries).
    const auto visit_k = [&](const std::size_t k, const Vec& n_ik) {
      if (has_row(roles[k])) add(k, n_ik.dot(dn_self[k]));
      for (std::size_t q = near.begin(k); q < near.end(k); ++q) {
        const LocalIndex col = column_of(static_cast<std::size_t>(near.index[q]));
        if (col >= 0) add_column(static_cast<std::size_t>(col), n_ik.dot(dn_pair[q]));
      }
    };
    // The members of each row's wall group (dummies whose parent is the row's particle).
    member_ptr.assign(n_rows + 1, 0);
    for (std::size_t m = 0; m < parent_of.size(); ++m)
      if (parent_of[m] >= 0 && static_cast<std::size_t>(parent_of[m]) < p.n_owned())
        ++member_ptr[static_cast<std::size_t>(row_of[static_cast<std::size_t>(parent_of[m])]) + 1];
    for (std::size_t r = 0; r < n_rows; ++r) member_ptr[r + 1] += member_ptr[r];
    members.resize(member_ptr[n_rows]);
    {
      std::vector<std::size_t> fill(member_ptr.begin(), member_ptr.end() - 1);
      for (std::size_t m = 0; m < parent_of.size(); ++m)
        if (parent_of[m] >= 0 && static_cast<std::size_t>(parent_of[m]) < p.n_owned())
          members[fill[static_cast<std::size_t>(row_of[static_cast<std::size_t>(parent_of[m])])]++] = static_cast<LocalIndex>(m);
    }
    // Each row's density error: its particle's against n0, plus its group's dummies' against their references.
    row_error.resize(n_rows);
    for (std::size_t r = 0; r < n_rows; ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      // A wall or solid row: its fluid neighbours' part of the density, and the rest at its reference.
      const Real n_i = roles[i] == Role::fluid ? n_kernel[i] : n_fluid[i] + reference[i];
      row_error[r] = n_i - n0_kernel + rest_offset[i] + rest_rate[i] * dt * dt;
      for (std::size_t e = member_ptr[r]; e < member_ptr[r + 1]; ++e) row_error[r] += group_error[static_cast<std::size_t>(members[e])];
    }
    for (std::size_t r = 0; r < n_rows; ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      if (step_alpha < 1) {  // G (at alpha = 1 the matrix is the scaled Laplacian alone)
        if (roles[i] == Role::fluid) visit_k(i, dn_self[i]);
        // Entry q of row i, neighbour k, holds dn_k/dx_i = -dn_i/dx_k; likewise for the group's dummies.
        for (std::size_t q = near.begin(i); q < near.end(i); ++q) {
          const auto k = static_cast<std::size_t>(near.index[q]);
          if (roles[k] == Role::fluid) visit_k(k, -dn_pair[q]);
        }
        for (std::size_t e = member_ptr[r]; e < member_ptr[r + 1]; ++e) {
          const auto m = static_cast<std::size_t>(members[e]);
          for (std::size_t q = near.begin(m); q < near.end(m); ++q) {
            const auto k = static_cast<std::size_t>(near.index[q]);
            if (roles[k] == Role::fluid) visit_k(k, -dn_pair[q]);
          }
        }
      }
      if (step_alpha > 0)
        // The pairs of the row's group (its particle and its dummies) with the other groups' particles.
        for (std::size_t e = member_ptr[r]; e <= member_ptr[r + 1]; ++e) {
          const std::size_t a = e < member_ptr[r + 1] ? static_cast<std::size_t>(members[e]) : i;
          for (std::size_t q = near.begin(a); q < near.end(a); ++q) {
            const auto j = static_cast<std::size_t>(near.index[q]);
            const LocalIndex col = column_of(j);
            if (col < 0 || static_cast<std::size_t>(col) == r) continue;
            const Real v = lap_scale * weight((p.position[j] - p.position[a]).norm(), re_g);
            add_laplacian_column(static_cast<std::size_t>(col), -v);
            add_laplacian_column(r, v);
          }
        }
      if (!touched_flag[r]) {
        touched_flag[r] = 1;
        touched.push_back(static_cast<LocalIndex>(r));
      }
      std::sort(touched.begin(), touched.end());
      for (const LocalIndex col : touched) {
        const auto q = static_cast<std::size_t>(col);
        gram_col.push_back(col);
        gram_val.push_back(scale * acc[q] + lap_acc[q]);
        acc[q] = 0;
        lap_acc[q] = 0;
        touched_flag[q] = 0;
      }
      touched.clear();
      gram_ptr[r + 1] = gram_col.size();
    }
  }

  /// The rows of the projection: G p + p / (c^2 dt^2) = kappa rho / dt^2 (n*_i - n0) / n0 (build_gram) over the
  /// rows and columns that are not free surface; free-surface rows p = 0.
  void assemble_projection(const Real dt) {
    if (!gram_ready) {
      build_gram(dt);
      gram_ready = true;
    }
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::size_t n_rows = particle_of_row.size();
    sys.col.clear();
    sys.value.clear();
    // The first step solves for the incompressible pressure (kappa 1, start_compressibility of the case's).
    const Real compress = (initial_step() ? start_compressibility : 1.0) / (c * c * dt * dt);
    const Real source = (initial_step() ? 1.0 : kappa) * rho / (dt * dt) / n0_kernel;
    projection_source = source;
    const Real dirichlet_diag = 2.0 * dim / lat_l.lambda + compress;
    sys.row_ptr[0] = 0;
    for (std::size_t r = 0; r < n_rows; ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      if (surface[i] != 0) {
        sys.col.push_back(static_cast<LocalIndex>(r));
        sys.value.push_back(dirichlet_diag);
        sys.rhs[r] = dirichlet_diag * surface_pressure[i];
      } else {
        sys.rhs[r] = source * row_error[r];
        for (std::size_t e = gram_ptr[r]; e < gram_ptr[r + 1]; ++e) {
          const auto q = static_cast<std::size_t>(gram_col[e]);
          const auto j = static_cast<std::size_t>(column_particle[q]);
          if (surface[j] != 0) {
            sys.rhs[r] -= gram_val[e] * surface_pressure[j];
            continue;
          }
          sys.col.push_back(gram_col[e]);
          sys.value.push_back(gram_val[e] + (q == r ? compress : 0.0));
        }
      }
      sys.row_ptr[r + 1] = sys.col.size();
    }
  }

  /// The complementarity of the density constraint, p >= 0, w = A p - b >= 0, p w = 0 (a primal-dual active
  /// set step): rows whose pressure came out negative become free-surface (p = 0) rows; free-surface rows whose
  /// density the other rows' pressures do not bring down to n0 (w_i < 0, the particle would stay compressed)
  /// become rows again, with `additions` only (the later updates of one time step only remove rows: the set
  /// then shrinks and the iteration ends; a primal-dual active set can cycle when the matrix is not an
  /// M-matrix, as this one is not). The pressures of the ghosts must be current. Whether any row changed on any rank.
  bool update_active_set(const bool additions) {
    auto& surface = p.scalar_field(fluid_fields::free_surface);
    const auto& pressure = p.scalar_field(fluid_fields::pressure);
    const Real w_tolerance = 1e-9 * projection_source * n0_kernel;  // a relative density change of 1e-9
    int changed = 0;
    for (std::size_t r = 0; r < particle_of_row.size(); ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      if (surface[i] == 0) {
        if (x_own[r] < 0) {
          surface[i] = 1;
          changed = 1;
        }
        continue;
      }
      if (!additions || dry[i]) continue;
      Real w = -projection_source * row_error[r];
      for (std::size_t e = gram_ptr[r]; e < gram_ptr[r + 1]; ++e)
        w += gram_val[e] * pressure[static_cast<std::size_t>(column_particle[static_cast<std::size_t>(gram_col[e])])];
      if (w < -w_tolerance) {
        surface[i] = 0;
        changed = 1;
      }
    }
    MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_MAX, comm);
    return changed != 0;
  }

  /// The projection's first step (the start from rest), whose system is the incompressible one: kappa 1, the
  /// compressibility start_compressibility of the case's, stabilisation start_alpha.
  bool initial_step() const { return projection && n_steps == 0; }

  /// The start from rest, after the first step's solve: its pressure p0 holds the fluid. Each row then gets
  /// the offset o that makes p0 the solution of the later steps' system in the state this step leaves,
  /// (G' + eps) p0 = kappa S (b + o), b the row's density error, S = rho / (dt^2 n0), eps = 1 / (c^2 dt^2),
  /// G' the matrix of projection_stabilisation. b = b_0 + (b - b_0), b_0 the error at the initial positions
  /// and b - b_0 the prediction's, which grows as dt^2 (the fluid falls g dt^2); so does G' p0 / (kappa S).
  /// Hence o = o_0 + o_2 dt^2 holds p0 at every later dt: o_0 = eps p0 / (kappa S) - b_0 = p0 n0 / (kappa rho
  /// c^2) - b_0, o_2 = (G' p0 / (kappa S) - (b - b_0)) / dt^2. So the fluid starts in its discrete equilibrium,
  /// compressed as the weak compressibility wants it, instead of having to compress and ring first
  /// (docs/validation.md, ## Fluid).
  void start_from_rest(const Real dt) {
    step_alpha = stabilisation;
    build_gram(dt);  // G' of the later steps (the offsets are still 0: row_error is b)
    auto& rest_offset = p.scalar_field(rest_offset_field);
    auto& rest_rate = p.scalar_field(rest_rate_field);
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const auto& pressure = p.scalar_field(fluid_fields::pressure);  // p0, current at the ghosts
    const Real s = kappa * rho / (dt * dt) / n0_kernel;
    for (std::size_t r = 0; r < particle_of_row.size(); ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      if (surface[i] != 0) continue;
      Real g_p = 0;  // (G' p0)_r, free-surface columns at their pressure
      for (std::size_t e = gram_ptr[r]; e < gram_ptr[r + 1]; ++e)
        g_p += gram_val[e] * pressure[static_cast<std::size_t>(column_particle[static_cast<std::size_t>(gram_col[e])])];
      rest_offset[i] = pressure[i] * n0_kernel / (kappa * rho * c * c) - initial_error[i];
      rest_rate[i] = (g_p / s - (row_error[r] - initial_error[i])) / (dt * dt);
    }
  }

  /// The projection's correction: v_k += -(dt/rho)(d/C) sum_j (p_k + p_j - 2 b_k) dn_j/dx_k, r_k += dt dv_k, for
  /// the fluid particles k; the sum runs over the neighbours j that carry a pressure (rows and wall groups; the
  /// others add p_k dn_j/dx_k). With b_k = 0 it is the transpose of the rows' operator, (d/C)(p_k dn_k/dx_k +
  /// sum_j p_j dn_j/dx_k); b_k = max(0, p_k - p_cap) caps the pressure the force's stiffness carries
  /// (stiffness_number in fluid/fluid_solver.hpp).
  void correct_projection(const Real dt) {
    const auto& pressure = p.scalar_field(fluid_fields::pressure);
    const Real p_cap = stiffness_number * rho * dp * dp / (dt * dt);
    const std::size_t n = p.n_owned();
    dv.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      dv[k].setZero();
      if (roles[k] != Role::fluid) continue;
      Vec f = pressure[k] * dn_self[k];
      const Real two_b = 2.0 * std::max(0.0, pressure[k] - p_cap);
      for (std::size_t q = near.begin(k); q < near.end(k); ++q) {
        const auto j = static_cast<std::size_t>(near.index[q]);
        if (has_row(roles[j])) f += (pressure[j] - two_b) * dn_pair[q];
        else if (parent_of[j] >= 0) f += (pressure[static_cast<std::size_t>(parent_of[j])] - two_b) * dn_pair[q];
      }
      dv[k] = -dt / rho * projection_scale * f;
    }
    for (std::size_t k = 0; k < n; ++k) {
      if (roles[k] != Role::fluid) continue;
      p.velocity[k] += dv[k];
      p.position[k] += dt * dv[k];
    }
  }

  /// The pressure a free-surface row holds: 0, or with the projection the hydrostatic pressure at a fluid
  /// particle's centre, half a spacing below the surface, rho dp / 2 max(0, -g . n) with n the outward normal
  /// -dn_k/dx_k / |dn_k/dx_k| (rho g dp / 2 on a level surface, 0 on a vertical one).
  Real surface_value(const std::size_t i) const { return projection ? surface_pressure[i] : 0.0; }

  /// The projection: surface_value of every particle in the near list (owned and ghosts).
  void surface_pressures() {
    const std::size_t n = near.n_particles();
    surface_pressure.assign(n, 0.0);
    for (std::size_t k = 0; k < n; ++k) {
      const Real norm = dn_self[k].norm();
      if (roles[k] != Role::fluid || !(norm > 0)) continue;
      surface_pressure[k] = 0.5 * rho * dp * std::max(0.0, gravity.dot(dn_self[k]) / norm);
    }
  }

  /// Solve, then p = 0 on the free surface; negative pressures clipped for the min-pressure gradient.
  PressureSolveResult solve_pressure() {
    auto& pressure = p.scalar_field(fluid_fields::pressure);
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::size_t n_rows = particle_of_row.size();
    x_own.resize(n_rows);
    for (std::size_t r = 0; r < n_rows; ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      x_own[r] = surface[i] != 0 ? surface_value(i) : pressure[i];  // warm start
    }
    const PressureSolveResult res = solver->solve(sys, x_own);
    std::fill(pressure.begin(), pressure.end(), 0.0);
    for (std::size_t r = 0; r < n_rows; ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      pressure[i] = surface[i] != 0 ? surface_value(i) : std::max(x_own[r], 0.0);
    }
    return res;
  }

  /// Eq. 19 and 24: v += -dt/rho grad P, r += dt (-dt/rho grad P). grad P by eq. 9 with p_min (every pair
  /// repels), or by the corrected gradient eq. 14-15 (falls back to p_min where the matrix is singular).
  void correct(const Real dt) {
    if (projection) {
      correct_projection(dt);
      return;
    }
    const auto& pressure = p.scalar_field(fluid_fields::pressure);
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::size_t n = p.n_owned();
    const Real c_grad = dim / lat_g.n0;
    dv.resize(n);  // n: the owned particles
    const auto is_row = [&](const std::size_t j) { return has_row(roles[j]); };
    for (std::size_t i = 0; i < n; ++i) {
      dv[i].setZero();
      if (roles[i] != Role::fluid) continue;
      if (corrected && surface[i] == 0) {
        // Eq. 14-15 where A_i is well conditioned (det A > 1e-2 tr(A)^d), else the p_min gradient below.
        const CorrectedGradient c = corrected_gradient_at(p.position, near, re_g, i, pressure, 1e-2, is_row);
        if (c.ok) {
          dv[i] = -dt / rho * c.gradient;
          continue;
        }
      }
      const Real p_min = min_value_at(p.position, near, re_g, i, pressure, is_row);
      dv[i] = -dt / rho * c_grad * gradient_sum_at(p.position, near, re_g, i, pressure, p_min, is_row);
    }
    for (std::size_t i = 0; i < n; ++i) {
      if (roles[i] != Role::fluid) continue;
      p.velocity[i] += dv[i];
      p.position[i] += dt * dv[i];
    }
  }

  /// Refreshes these fields at the ghosts from their owners.
  void refresh_ghosts(const std::vector<std::string>& fields, FluidStepReport& report) {
    const auto t0 = Clock::now();
    dist.exchange_ghosts(p, fields);
    report.t_halo += seconds_since(t0);
  }

  /// Fluid particles outside the case's domain are removed (with the ghosts, which are then renewed at the
  /// next step).
  std::size_t remove_escaped() {
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

  ParticleSet& p;
  Distribution& dist;
  FluidOptions opt;
  TankMotion motion;
  int rank = 0;
  Real dp = 0, re_g = 0, re_l = 0, r_max = 0;
  Real re_p = 0;  ///< radius of the projection's density kernel (fluid.projection_radius)
  LatticeConstants lat_g, lat_l;
  Real beta1 = 0, beta2 = 0;
  bool corrected = false;
  bool projection = false;        ///< fluid.scheme = projection
  Real step_alpha = 0;            ///< the stabilisation of this step's matrix: start_alpha in the first step, else alpha
  /// The first step's stabilisation: nearly the exact projection, whose pressure balances gravity in the
  /// force's own terms, with enough of the Laplacian to keep G's near-null pressure modes out of p0 (at 0 they
  /// put errors of up to 90 % next to the walls at dp 1 cm; docs/validation.md, ## Fluid).
  static constexpr Real start_alpha = 0.1;
  /// The first step's compressibility, as a share of the case's 1 / c^2: nearly incompressible.
  static constexpr Real start_compressibility = 1e-4;
  int max_active_set_solves = 6;  ///< fluid.max_active_set_solves
  Real stabilisation = 0;         ///< alpha of fluid.projection_stabilisation
  DensityKernel kernel = DensityKernel::wendland;  ///< fluid.projection_kernel
  Real n0_kernel = 0;             ///< n0 of that kernel at re_gradient
  Real c_lattice = 0;             ///< its sum_j -w'(r_j) r_j on the lattice (C when no particle is interior)
  Real projection_scale = 0;      ///< d / C of the projection (projection_geometry)
  Real projection_source = 0;     ///< kappa rho / (dt^2 n0) of the step's rows (assemble_projection)
  Vec gravity = Vec::Zero();       ///< of the current step: gravity_full times the ramp at its middle
  Vec gravity_full = Vec::Zero();  ///< the case's gravity
  Real gravity_ramp = 0;           ///< [s] (core/ramp.hpp)
  TimeSpec time;
  Rect domain;
  Real rho = 1000, nu = 0, c = 20, kappa = 1;
  Real lateral_friction = 0;  ///< k [1/s] of fluid.lateral_walls (0: off)
  Real wall_omega = 0;        ///< the tank's angular velocity at the end of the current step
  Real tolerance = 1e-8;
  Real coarse_cell = 0;  ///< side of the pressure solve's coarse groups (0: none)
  Real density_tolerance = 0;  ///< fluid.density_tolerance: absolute stop, RMS of r dt^2 / rho
  Real density_tolerance_cap = std::numeric_limits<Real>::infinity();  ///< set_density_tolerance_cap
  std::string preconditioner;
  std::unique_ptr<PressureSolver> solver;
  std::size_t n_steps = 0;

  // Work arrays, reused between steps.
  std::vector<Role> roles;
  NeighbourList nl, near;
  CellGrid grid;
  std::vector<Real> n_star;
  std::vector<Vec> v_new, dv;
  std::vector<LocalIndex> row_of;  ///< local column id of each particle's pressure unknown, -1 if none
  std::vector<LocalIndex> particle_of_row;
  LocalRows sys;
  MPI_Comm comm = MPI_COMM_NULL;
  std::vector<Real> x_own;
  std::vector<std::uint8_t> remove;
  std::vector<Vec> dn_self;              ///< projection: dn_k/dx_k
  std::vector<Vec> dn_pair;              ///< projection: dn_j/dx_k for entry q (row k, neighbour j) of the near list
  std::vector<Real> surface_pressure;    ///< projection: the pressure of each particle as a free-surface row
  std::vector<Real> n_kernel, c_of;      ///< projection: each particle's kernel density, sum_j -w' r
  std::vector<Real> n_fluid;             ///< projection: the fluid neighbours' part of n_kernel
  std::vector<Real> initial_error;       ///< projection, first step: each row's density error at the start
  std::vector<std::uint8_t> dry;         ///< projection: a wall or solid row without a fluid neighbour
  std::vector<LocalIndex> parent_of;     ///< projection: the wall particle whose group a dummy joins, or -1
  std::vector<Real> group_error;         ///< projection: a group dummy's density minus its reference
  std::vector<std::size_t> member_ptr;   ///< projection: each row's group dummies (CSR)
  std::vector<LocalIndex> members;
  std::vector<Real> row_error;           ///< projection: each row's density error (with its group's)
  std::vector<Real> acc;                 ///< projection: a row's entries by column while it is assembled (G ...
  std::vector<Real> lap_acc;             ///< ... and the stabilisation)
  std::vector<std::uint8_t> touched_flag;
  std::vector<LocalIndex> touched;
  std::vector<std::size_t> gram_ptr;     ///< projection: the operator G of build_gram (CRS, sorted columns)
  std::vector<LocalIndex> gram_col;
  std::vector<Real> gram_val;
  std::vector<LocalIndex> column_particle;  ///< projection: the particle of each column
  bool gram_ready = false;                  ///< G built for this step
};

Real fluid_work_weight(const ParticleKind kind) {
  if (kind == ParticleKind::wall) return 0.8;
  if (kind == ParticleKind::dummy) return 0.2;
  return 1.0;
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
    if (m.p.kind[i] == ParticleKind::fluid || (m.motion.moving() && m.p.kind[i] == ParticleKind::wall))
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
  // Owners and ghosts are renewed (with the cell order now and then) when a particle has moved half the
  // skin since they were built; in between, the ghosts' positions and velocities are refreshed.
  const bool has_solid = m.p.n_of_kind(ParticleKind::solid) > 0;
  const bool reorder = m.opt.reorder_every > 0 && !has_solid && m.n_steps % static_cast<std::size_t>(m.opt.reorder_every) == 0;
  m.dist.renew(m.p, {"position", "velocity"}, std::nullopt, reorder, [&] {
    if (reorder) m.p.reorder(cell_order(m.p.position, 0.5 * m.r_max));
  });
  report.t_halo += seconds_since(t0);
  t0 = Clock::now();
  m.classify();
  m.gravity = m.gravity_full * ramp_factor(t + 0.5 * dt, m.gravity_ramp);
  m.move_walls(t + dt);
  report.t_rest += seconds_since(t0);

  t0 = Clock::now();
  // The ghosts need no rows, but for the projection (projection_geometry).
  build_neighbour_list(m.p.position, m.r_max, m.nl, m.grid, true, m.projection ? m.p.size() : m.p.n_owned());
  report.t_neighbours += seconds_since(t0);

  t0 = Clock::now();
  if (m.projection && m.n_steps == 0) {
    m.reference_densities();
    m.refresh_ghosts({Impl::reference_density_field}, report);
  }
  m.predict(dt);
  report.t_rest += seconds_since(t0);
  m.refresh_ghosts({"position", "velocity"}, report);
  t0 = Clock::now();
  m.build_near_list();
  report.t_neighbours += seconds_since(t0);
  t0 = Clock::now();
  m.collide(dt);
  report.t_rest += seconds_since(t0);
  m.refresh_ghosts({"position", "velocity"}, report);
  t0 = Clock::now();
  m.density_and_surface();
  report.t_rest += seconds_since(t0);
  m.refresh_ghosts({fluid_fields::free_surface}, report);

  t0 = Clock::now();
  if (m.projection) {
    m.step_alpha = m.initial_step() ? Impl::start_alpha : m.stabilisation;
    m.projection_geometry();
    m.gram_ready = false;
  }
  m.assemble(dt);
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
  PressureSolveResult res = m.solve_pressure();
  report.t_assembly += res.t_matrix;
  report.t_setup = res.t_setup;
  report.t_solve = res.t_solve;
  report.iterations = res.iterations;
  // The projection's active set: re-solved while rows change (at most max_active_set_solves solves); rows
  // come back in the first two updates only.
  for (int solves = 1; m.projection && solves < m.max_active_set_solves; ++solves) {
    m.refresh_ghosts({fluid_fields::pressure}, report);
    if (!m.update_active_set(solves <= 2)) break;
    m.refresh_ghosts({fluid_fields::free_surface}, report);
    t0 = Clock::now();
    m.assemble(dt);
    report.t_assembly += seconds_since(t0);
    res = m.solve_pressure();
    report.t_assembly += res.t_matrix;
    report.t_setup += res.t_setup;
    report.t_solve += res.t_solve;
    report.iterations += res.iterations;
    ++report.solves;
  }
  m.refresh_ghosts({fluid_fields::pressure}, report);
  if (m.initial_step()) m.start_from_rest(dt);
  report.residual = res.residual;
  if (!res.converged)
    throw std::runtime_error(fmt::format(
        "the pressure solve did not converge: {} iterations, true relative residual {:.3e} > tolerance {:.1e} "
        "({} rows, preconditioner '{}'); raise fluid.max_iterations, use another fluid.preconditioner or reduce dt",
        res.iterations, res.residual, res.tolerance, report.n_rows, m.preconditioner));

  t0 = Clock::now();
  m.correct(dt);
  const auto& surface = m.p.scalar_field(fluid_fields::free_surface);
  // Sums over the ranks: surface particles, rows, removed particles; the largest fluid speed.
  unsigned long long counts[3] = {0, m.particle_of_row.size(), 0};
  for (std::size_t i = 0; i < m.p.n_owned(); ++i) counts[0] += surface[i] != 0;
  counts[2] = m.remove_escaped();
  for (std::size_t i = 0; i < m.p.n_owned(); ++i)
    if (m.p.kind[i] == ParticleKind::fluid) report.max_speed = std::max(report.max_speed, m.p.velocity[i].norm());
  MPI_Allreduce(MPI_IN_PLACE, counts, 3, MPI_UNSIGNED_LONG_LONG, MPI_SUM, m.comm);
  MPI_Allreduce(MPI_IN_PLACE, &report.max_speed, 1, MPI_DOUBLE, MPI_MAX, m.comm);
  report.n_surface = counts[0];
  report.n_rows = counts[1];
  report.n_removed = counts[2];
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
  return exact;
}

FluidSolver::IterationState FluidSolver::iteration_state() const { return {impl_->n_steps}; }

void FluidSolver::restore(const IterationState& state) { impl_->n_steps = state.n_steps; }

void FluidSolver::set_density_tolerance_cap(const Real cap) {
  if (!(cap > 0)) throw std::invalid_argument("FluidSolver::set_density_tolerance_cap: a cap > 0 expected");
  impl_->density_tolerance_cap = cap;
}

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
}  // namespace mpsfsi
