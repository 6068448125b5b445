// The default pressure scheme, the exact projection of the number density (fluid.scheme = projection;
// fluid/fluid_parameters.hpp FluidScheme; docs/validation.md, "The default scheme: projection"): the rows
// G p + p / (c^2 dt^2) = kappa rho / dt^2 (n* - n0) / n0 with G = (d/C) N N^T / n0 (N_ik = dn_i/dx_k), the wall
// groups, the active set of the complementarity p >= 0, the start from rest, and the correction by the
// transpose N^T p with its stiffness capped (fluid/fluid_solver.hpp, stiffness_number).
#include "fluid/pressure_scheme.hpp"

#include "core/buffers.hpp"
#include "core/kernel.hpp"
#include "core/operators.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace mpsfsi::fluid_detail {

namespace {

/// What the projection computes from one arrangement of the particles (projection_geometry): the operator's
/// derivatives, the wall groups and the free-surface pressures. Kept whole, so that a step's rows and its
/// correction see one arrangement.
struct Geometry {
  /// dn_self, dn_pair and c_of hold every particle's values; otherwise the fluid particles' only (the others'
  /// dn_self and c_of are 0, their dn_pair entries undefined).
  bool all_derivatives = true;
  std::vector<Vec> dn_self;            ///< dn_k/dx_k
  std::vector<Vec> dn_pair;            ///< dn_j/dx_k for entry q (row k, neighbour j) of the near list
  std::vector<Real> lap_weight;        ///< the weight w(r_jk) at re_gradient of entry q (stabilisation)
  /// Without lap_weight (a geometry for the rows alone, projection_geometry): the positions it was computed on,
  /// from which operator_row takes the weights as it needs them.
  const std::vector<Vec>* x = nullptr;
  std::vector<Real> n_kernel, c_of;    ///< each particle's kernel density, sum_j -w' r
  std::vector<Real> n_fluid;           ///< the fluid neighbours' part of n_kernel
  Real projection_scale = 0;           ///< d / C of the projection
  std::vector<LocalIndex> parent_of;   ///< the wall particle whose group a dummy joins, or -1
  std::vector<Real> group_error;       ///< a group dummy's density minus its reference
};

class ProjectionScheme final : public PressureScheme {
 public:
  ProjectionScheme(FluidCore& fluid_core, const FluidParameters& fluid)
      : core(fluid_core), p(core.p), dp(core.dp), re_g(core.re_g), lat_g(core.lat_g), lat_l(core.lat_l),
        gravity(core.gravity), rho(core.rho), c(core.c), kappa(core.kappa), n_steps(core.n_steps), comm(core.comm),
        roles(core.roles), near(core.near), dv(core.dv), row_of(core.row_of),
        particle_of_row(core.particle_of_row), sys(core.sys), x_own(core.x_own) {
    max_active_set_solves = fluid.max_active_set_solves;
    stabilisation = fluid.projection_stabilisation;
    kernel = fluid.projection_kernel;
    re_p = fluid.projection_radius * dp;
    const KernelSums sums = lattice_sums(kernel, dp, re_p);
    n0_kernel = sums.n0;
    c_lattice = sums.c;
    p.add_scalar_field(reference_density_field, 0.0);
    p.add_scalar_field(rest_offset_field, 0.0);
    p.add_scalar_field(rest_rate_field, 0.0);
    p.add_scalar_field(surface_pressure_field, 0.0);
    p.add_vector_field(trial_dv_field);
  }

  Real near_radius() const override { return std::max(re_g, re_p); }  // the kernel may reach further than re_g
  /// Every ghost's row in the first step and with G in the rows (stabilisation < 1): G couples a row with its
  /// neighbours' neighbours. Otherwise the dummies' alone: a dummy's row names its wall group (the column its
  /// pressure takes in the rows and corrections that reach it) and holds its density (a member's part of its
  /// group's row). A fluid ghost's trial correction and surface pressure come from its owner
  /// (update_active_set, prepare); a wall or solid ghost is a column, whose pairs no owned row reads.
  bool ghost_needs_row(const Role role) const override {
    return initial_step() || stabilisation < 1 || role == Role::dummy;
  }
  bool rows_need_wide_list() const override { return false; }
  /// The longest chain of pairs from a fluid particle to a particle whose row is read: a wet wall (near
  /// radius), its group's dummies (re_g), their neighbours (near radius: their densities, and the columns of the
  /// stabilisation's pairs), whose own group parents (re_g) name those columns.
  Real wall_reach() const override { return 2 * near_radius() + 2 * re_g; }

  void initial_state(FluidStepReport& report) override {
    reference_densities();
    core.refresh_ghosts({reference_density_field}, report);
    start_position = p.position;  // owned and ghosts: the first step's displacements (prepare_rows)
    start_compressibility = 1e-4 / std::pow(std::max(water_extent(), dp), 2);
  }

  bool keeps_surface() const override { return true; }

  void after_surface() override {
    const std::size_t n = p.n_owned();
    auto& surface = p.scalar_field(fluid_fields::free_surface);
    // A wall or solid row that no fluid particle reads constrains nothing that moves: it is a free-surface row
    // (p = 0) and stays one until the water reaches it. A fluid particle reads the rows of its neighbours and
    // of its dummy neighbours' wall groups (wall_groups: a dummy joins a wall particle among its neighbours), so
    // a row is wet when a fluid particle is its neighbour or a neighbour of one of its dummy neighbours. Dry
    // with the first alone, a wall particle a few rows under a thin wall's face (the floor under a beach's toe)
    // would hold p = 0 in the dummies next to the water, which would flow toward them.
    // A dry wall row whose support is full (inside the walls: the floor under a block standing on it) faces no
    // air, and its p = 0 is no pressure of the water's: it is flagged inside_flag, and the stabilisation leaves
    // its pairs out (operator_row), as it would pull the wet rows next to it toward 0. A dry row short of
    // neighbours faces air, whose pressure is 0: it stays an ordinary free-surface row in its neighbours' pairs.
    // So do a solid's dry rows and the dry wall rows next to a solid (a clamp, a channel beside a block), whose
    // pairs with the solid's rows the coupled cases were validated with (docs/validation.md, "Water at rest on
    // walls that rest on walls").
    const std::size_t n_listed = near.n_particles();
    const auto has_fluid_neighbour = [&](const std::size_t j) {
      for (std::size_t q = near.begin(j); q < near.end(j); ++q)
        if (roles[static_cast<std::size_t>(near.index[q])] == Role::fluid) return true;
      return false;
    };
    const auto inside_walls = [&](const std::size_t i) {
      if (p.kind[i] != ParticleKind::wall || core.n_star[i] < core.beta1 * lat_g.n0) return false;
      for (std::size_t q = near.begin(i); q < near.end(i); ++q)
        if (p.kind[static_cast<std::size_t>(near.index[q])] == ParticleKind::solid) return false;
      return true;
    };
    dry.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
      if (roles[i] != Role::boundary) continue;
      bool wet = has_fluid_neighbour(i);
      if (p.kind[i] == ParticleKind::wall)
        for (std::size_t q = near.begin(i); q < near.end(i) && !wet; ++q) {
          const auto m = static_cast<std::size_t>(near.index[q]);
          if (m < n_listed && p.kind[m] == ParticleKind::dummy && roles[m] == Role::dummy) wet = has_fluid_neighbour(m);
        }
      dry[i] = !wet;
      if (!wet) surface[i] = inside_walls(i) ? inside_flag : 1;
      else if (surface[i] == inside_flag) surface[i] = 1;
    }
  }

  void prepare(Real, FluidStepReport& report) override {
    step_alpha = initial_step() ? start_alpha : stabilisation;
    linear_source = initial_step();
    // The first solve on the positions before the step moved them.
    projection_geometry(linear_source ? start_position : p.position);
    // Of the fluid ghosts only: the others' values are 0 at their owners, and so at the ghosts copied from them.
    core.refresh_ghosts({surface_pressure_field}, report, ParticleKind::fluid);
    surface_pressure = &p.scalar_field(surface_pressure_field);
    rows_ready = false;
  }

  void assemble(const Real dt) override { assemble_projection(dt); }

  /// The pressure a free-surface row holds: 0, or with the projection the hydrostatic pressure at a fluid
  /// particle's centre, half a spacing below the surface, rho dp / 2 max(0, -g . n) with n the outward normal
  /// -dn_k/dx_k / |dn_k/dx_k| (rho g dp / 2 on a level surface, 0 on a vertical one).
  Real surface_value(const std::size_t i) const override { return (*surface_pressure)[i]; }

  int max_solves() const override { return max_active_set_solves; }

  // Rows come back in the first two updates only.
  bool update_rows(const int solves, const Real dt, FluidStepReport& report) override {
    return update_active_set(solves <= 2, dt, report);
  }

  void after_solve(const Real dt) override {
    if (initial_step()) start_from_rest(dt);
  }

  void correct(const Real dt) override { correct_projection(dt); }

 private:
  /// The projection: in the initial state, each dummy particle's number density (its wall group's reference),
  /// and each wall or solid particle's number density from its neighbours that are not fluid (the boundary
  /// part of its row's density, held at that value: the walls' and solids' own motion is no density change).
  static constexpr const char* reference_density_field = "reference_density";
  /// The projection: each row particle's number density offset o = o_0 + o_2 dt^2 that makes the initial
  /// state the scheme's equilibrium under the initial pressure at any dt (start_from_rest): o_0 here, o_2 in
  /// rest_rate_field [1/s^2].
  static constexpr const char* rest_offset_field = "rest_offset";
  static constexpr const char* rest_rate_field = "rest_rate";
  /// The projection: each fluid particle's pressure as a free-surface row (surface_pressures), and the
  /// correction's velocity change at the current pressures (update_active_set), from their owners at the ghosts.
  static constexpr const char* surface_pressure_field = "_projection_surface_pressure";
  static constexpr const char* trial_dv_field = "_projection_trial_dv";

  /// The projection, first step, at the initial positions: the reference densities (reference_density_field),
  /// and each row's density error before the step moves anything (initial_error, by the rows' definition of
  /// prepare_rows).
  void reference_densities() {
    auto& reference = p.scalar_field(reference_density_field);
    initial_error.assign(p.n_owned(), 0.0);
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (roles[i] == Role::none) continue;
      Real n_fluid_i = 0, n_other = 0;  // the kernel density from the fluid neighbours, from the others
      for_each_pair(p.position, near, re_p, i, [&](const std::size_t j) { return roles[j] != Role::none; },
                    [&](const std::size_t j, const Vec&, const Real r2, Real) {
                      (roles[j] == Role::fluid ? n_fluid_i : n_other) += kernel_at(kernel, std::sqrt(r2), re_p).w;
                    });
      initial_error[i] = n_fluid_i + n_other - n0_kernel;
      if (p.kind[i] == ParticleKind::dummy) reference[i] = n_fluid_i + n_other;
      else if (roles[i] != Role::fluid) reference[i] = n_other;
    }
  }

  /// The diagonal of the box that holds the fluid particles of every rank (0 without any).
  Real water_extent() const {
    Real box[2 * dim];  // -min and max per axis
    std::fill(box, box + 2 * dim, -std::numeric_limits<Real>::infinity());
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (roles[i] != Role::fluid) continue;
      for (int a = 0; a < dim; ++a) {
        box[a] = std::max(box[a], -p.position[i][a]);
        box[dim + a] = std::max(box[dim + a], p.position[i][a]);
      }
    }
    MPI_Allreduce(MPI_IN_PLACE, box, 2 * dim, MPI_DOUBLE, MPI_MAX, comm);
    Real d2 = 0;
    for (int a = 0; a < dim; ++a)
      if (box[dim + a] >= -box[a]) d2 += (box[dim + a] + box[a]) * (box[dim + a] + box[a]);
    return std::sqrt(d2);
  }

  // ---- the exact projection (fluid.scheme = projection; fluid/fluid_parameters.hpp) ----

  /// dn_k/dx_k at every particle with a row in the near list (owned and ghosts), with the projection's kernel,
  /// and the scale d / C of the force, C the mean over the interior fluid particles of sum_j -w'(r_ij) r_ij
  /// (sum_j re / r_ij = n0 + N0 on the lattice for the MPS weight), so that -(d/C) N^T p is -grad p for a
  /// linear pressure on the current arrangement.
  ///
  /// `for_correction` false: the geometry serves the rows alone (start_from_rest's offsets, while `x` lives):
  /// without G the pairs' derivatives, which only the correction and G read, are not kept (dn_pair is then
  /// empty), nor the stabilisation's weights.
  void projection_geometry(const std::vector<Vec>& x, const bool for_correction = true) {
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::size_t n = near.n_particles();
    // The near list holds the pairs within re_g of particles that take part (build_near_list): entry q of
    // row k, neighbour j, gets dn_j/dx_k; by the symmetry of w, dn_k/dx_k is their sum.
    // Also the kernel's number density n_k and sum_j -w'(r_jk) r_jk (C of the particle).
    // Without G (stabilisation 1) only the fluid particles' derivatives are used (the correction, the surface
    // pressures, C); the others' rows need their densities and the stabilisation's weights alone.
    geo.all_derivatives = step_alpha < 1;
    const bool keep_pairs = for_correction || geo.all_derivatives;
    // Likewise the stabilisation's weights, which such a geometry's rows take from the positions.
    const bool keep_weights = for_correction && step_alpha > 0;
    if (keep_pairs) {
      geo.dn_pair.resize(near.n_pairs());
    } else {
      std::vector<Vec>().swap(geo.dn_pair);
    }
    if (keep_weights) {
      geo.lap_weight.resize(near.n_pairs());
    } else {
      std::vector<Real>().swap(geo.lap_weight);
    }
    geo.x = !for_correction && step_alpha > 0 ? &x : nullptr;
    geo.dn_self.resize(n);
    geo.n_kernel.resize(n);
    geo.n_fluid.resize(n);
    geo.c_of.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      Vec s = Vec::Zero();
      Real n_k = 0, n_f = 0, c_k = 0;
      if (geo.all_derivatives || roles[k] == Role::fluid) {
        for (std::size_t q = near.begin(k); q < near.end(k); ++q) {
          const auto j = static_cast<std::size_t>(near.index[q]);
          const Vec r_jk = x[k] - x[j];
          const Real r = r_jk.norm();
          const KernelValue kv = kernel_at(kernel, r, re_p);
          const Vec dn = (kv.dw / r) * r_jk;
          if (keep_pairs) geo.dn_pair[q] = dn;
          if (keep_weights) geo.lap_weight[q] = weight(r, re_g);
          s += dn;
          n_k += kv.w;
          if (roles[j] == Role::fluid) n_f += kv.w;
          c_k -= kv.dw * r;
        }
      } else {
        for (std::size_t q = near.begin(k); q < near.end(k); ++q) {
          const auto j = static_cast<std::size_t>(near.index[q]);
          const Real r = (x[k] - x[j]).norm();
          const Real w = kernel_at(kernel, r, re_p).w;
          if (keep_weights) geo.lap_weight[q] = weight(r, re_g);
          n_k += w;
          if (roles[j] == Role::fluid) n_f += w;
        }
      }
      geo.dn_self[k] = s;
      geo.n_kernel[k] = n_k;
      geo.n_fluid[k] = n_f;
      geo.c_of[k] = c_k;
    }
    Real sums[2] = {0, 0};  // sum over the interior fluid particles of sum_j -w'(r_ij) r_ij, their count
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (roles[i] != Role::fluid || surface[i] != 0) continue;
      sums[0] += geo.c_of[i];
      sums[1] += 1;
    }
    MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_DOUBLE, MPI_SUM, comm);
    const Real c_sum = sums[1] > 0 ? sums[0] / sums[1] : c_lattice;
    geo.projection_scale = dim / c_sum;
    wall_groups(x);
    if (for_correction) surface_pressures();
  }

  /// The wall groups: each dummy particle within re_g of a wall particle joins the group of the nearest one
  /// (ties to the smaller global id, so that every rank that holds both decides alike). A group shares the
  /// wall particle's pressure unknown: the dummies carry its pressure in the force, and the group's row
  /// constrains the sum of its members' number densities (each against its initial value). Without it the
  /// dummies push with p = 0, and water at rest on the lattice feels a net force of up to 2.3 g toward the
  /// walls (docs/validation.md, ## Fluid).
  void wall_groups(const std::vector<Vec>& x) {
    const std::size_t n = near.n_particles();
    geo.parent_of.assign(n, -1);
    geo.group_error.assign(n, 0.0);
    const auto& reference = p.scalar_field(reference_density_field);
    for (std::size_t m = 0; m < n; ++m) {
      if (p.kind[m] != ParticleKind::dummy || roles[m] != Role::dummy) continue;
      Real best = std::numeric_limits<Real>::max();
      GlobalId best_id = 0;
      for (std::size_t q = near.begin(m); q < near.end(m); ++q) {
        const auto j = static_cast<std::size_t>(near.index[q]);
        const Real r2 = (x[j] - x[m]).squaredNorm();
        if (p.kind[j] != ParticleKind::wall || roles[j] != Role::boundary) continue;
        if (r2 < best * (1 - 1e-12) || (r2 <= best * (1 + 1e-12) && p.global_id[j] < best_id)) {
          best = r2;
          best_id = p.global_id[j];
          geo.parent_of[m] = static_cast<LocalIndex>(j);
        }
      }
      if (geo.parent_of[m] >= 0) geo.group_error[m] = geo.n_kernel[m] - reference[m];
    }
  }

  /// The pressure unknown (local column) of particle j: its own row, its wall group's, or none (-1).
  LocalIndex column_of(const std::size_t j) const {
    if (row_of[j] >= 0) return row_of[j];
    if (j < geo.parent_of.size() && geo.parent_of[j] >= 0) return row_of[static_cast<std::size_t>(geo.parent_of[j])];
    return -1;
  }

  /// The change of particle i's number density to first order in the displacements d(j) of the particles:
  /// sum_j dw(r_ij)/dx_i . (d_i - d_j) over its neighbours (the fluid ones only for `fluid_only`, a wall or
  /// solid row, whose other neighbours count at their reference). Needs row i's derivatives (a fluid
  /// particle's, or all_derivatives).
  template <class Displacement>
  Real density_change(const std::size_t i, const bool fluid_only, const Displacement& d) const {
    assert(geo.all_derivatives || roles[i] == Role::fluid);
    const Vec d_i = d(i);
    Real change = 0;
    for (std::size_t q = near.begin(i); q < near.end(i); ++q) {
      const auto j = static_cast<std::size_t>(near.index[q]);
      if (!fluid_only || roles[j] == Role::fluid) change += geo.dn_pair[q].dot(d_i - d(j));
    }
    return change;
  }

  /// The first step's density_change of particle i for the fluid's displacements since the start
  /// (start_position). The walls and solids count at their start: p0 is the pressure of the water at rest
  /// against its boundaries, and a boundary that moves in the first step (a tank that starts rolling, a wall
  /// table whose first value is not the start) would put that motion's impulse into p0, which the rest offsets
  /// then hold for the whole run; the later steps' rows see the boundary's motion as they see it at any step.
  Real linear_change(const std::size_t i, const bool fluid_only) const {
    assert(geo.all_derivatives);
    return density_change(i, fluid_only, [&](const std::size_t j) {
      return roles[j] == Role::fluid ? Vec(p.position[j] - start_position[j]) : Vec(Vec::Zero());
    });
  }

  /// The projection's operator over this rank's rows (every row particle, whatever its free-surface flag),
  /// (1 - alpha) G + alpha s L_g. G = (d/C) N N^T / n0, N_ik = dn_i/dx_k over the fluid particles k (the ones
  /// the force moves). L_g is minus the Laplacian of eq. 12 at re_gradient over the row neighbours (pair
  /// weights 2d w_ij / (lambda n0)), s = C / (d n0) its factor to G's long-wave limit, so that alpha changes
  /// neither a smooth pressure nor the hydrostatic one in the bulk, and damps the oscillating pressures that G
  /// alone leaves free (N^T p of a checkerboard p is nearly zero). The operator is not stored: prepare_rows
  /// sets up what its rows need once per step, after the rows are numbered (assemble), and operator_row
  /// computes a row where it is read (the system's layout, a row the active set rewrites, a wall row's
  /// complementarity test). The first step's G couples particles two kernel radii apart, and a stored copy
  /// beside the system's would double the largest arrays of the run.
  void prepare_rows(const Real dt) {
    const std::size_t n_rows = particle_of_row.size();
    const auto& rest_offset = p.scalar_field(rest_offset_field);
    const auto& rest_rate = p.scalar_field(rest_rate_field);
    const auto& reference = p.scalar_field(reference_density_field);
    const std::size_t n_columns = n_rows + sys.remote_id.size();
    acc.assign(n_columns, 0.0);
    lap_acc.assign(n_columns, 0.0);
    touched_flag.assign(n_columns, 0);
    touched.resize(n_columns);  // the columns of the row being built
    // Each particle's pressure unknown (column_of), once.
    column_of_particle.resize(p.size());
    for (std::size_t j = 0; j < column_of_particle.size(); ++j) column_of_particle[j] = column_of(j);
    column_particle.assign(n_columns, 0);
    for (std::size_t j = 0; j < p.size(); ++j)
      if (row_of[j] >= 0) column_particle[static_cast<std::size_t>(row_of[j])] = static_cast<LocalIndex>(j);
    // The dry rows inside the walls (after_surface; the flag holds through the step), which the stabilisation's
    // pairs leave out.
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    column_inside.resize(n_columns);
    for (std::size_t q = 0; q < n_columns; ++q) column_inside[q] = surface[static_cast<std::size_t>(column_particle[q])] == inside_flag;
    row_scale = (1.0 - step_alpha) * geo.projection_scale / n0_kernel;
    row_lap_scale = step_alpha / (geo.projection_scale * n0_kernel) * (2.0 * dim / (lat_g.lambda * lat_g.n0));
    // The members of each row's wall group (dummies whose parent is the row's particle).
    member_ptr.assign(n_rows + 1, 0);
    for (std::size_t m = 0; m < geo.parent_of.size(); ++m)
      if (geo.parent_of[m] >= 0 && static_cast<std::size_t>(geo.parent_of[m]) < p.n_owned())
        ++member_ptr[static_cast<std::size_t>(row_of[static_cast<std::size_t>(geo.parent_of[m])]) + 1];
    for (std::size_t r = 0; r < n_rows; ++r) member_ptr[r + 1] += member_ptr[r];
    members.resize(member_ptr[n_rows]);
    {
      std::vector<std::size_t> fill(member_ptr.begin(), member_ptr.end() - 1);
      for (std::size_t m = 0; m < geo.parent_of.size(); ++m)
        if (geo.parent_of[m] >= 0 && static_cast<std::size_t>(geo.parent_of[m]) < p.n_owned())
          members[fill[static_cast<std::size_t>(row_of[static_cast<std::size_t>(geo.parent_of[m])])]++] = static_cast<LocalIndex>(m);
    }
    // Each row's density error: its particle's against n0, plus its group's dummies' against their references.
    row_error.resize(n_rows);
    for (std::size_t r = 0; r < n_rows; ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      if (linear_source) {
        // The first solve: the step's displacements' change to first order, the change that the correction's G
        // undoes. The arrangement at the start is the state of rest: its own density errors (the truncated
        // supports below the free surface, the walls' lattice) are not removed in one step, which would weigh
        // them by 1 / dt^2 against gravity's dt-independent part and make p0 depend on dt; the rest offsets
        // take them in (start_from_rest).
        row_error[r] = linear_change(i, roles[i] != Role::fluid);
        for (std::size_t e = member_ptr[r]; e < member_ptr[r + 1]; ++e)
          row_error[r] += linear_change(static_cast<std::size_t>(members[e]), false);
        continue;
      }
      // A wall or solid row: its fluid neighbours' part of the density, and the rest at its reference.
      const Real n_i = roles[i] == Role::fluid ? geo.n_kernel[i] : geo.n_fluid[i] + reference[i];
      row_error[r] = n_i - n0_kernel + rest_offset[i] + rest_rate[i] * dt * dt;
      for (std::size_t e = member_ptr[r]; e < member_ptr[r + 1]; ++e) row_error[r] += geo.group_error[static_cast<std::size_t>(members[e])];
    }
  }

  /// Row r of the operator (prepare_rows) into row_col / row_val, its columns sorted.
  void operator_row(const std::size_t r) {
    std::size_t n_touched = 0;
    const auto touch = [&](const std::size_t col) {
      if (!touched_flag[col]) {
        touched_flag[col] = 1;
        touched[n_touched++] = static_cast<LocalIndex>(col);
      }
    };
    const auto add_column = [&](const std::size_t col, const Real v) {
      touch(col);
      acc[col] += v;
    };
    const auto add = [&](const std::size_t j, const Real v) { add_column(static_cast<std::size_t>(row_of[j]), v); };
    const auto add_laplacian_column = [&](const std::size_t col, const Real v) {
      touch(col);
      lap_acc[col] += v;
    };
    // Moving k (N_ik given) adds N_ik . N_jk to the entries (i, j): j = k and the row neighbours j of k
    // (geo.dn_pair of row k's entries).
    const auto visit_k = [&](const std::size_t k, const Vec& n_ik) {
      if (has_row(roles[k])) add(k, n_ik.dot(geo.dn_self[k]));
      for (std::size_t q = near.begin(k); q < near.end(k); ++q) {
        const LocalIndex col = column_of_particle[static_cast<std::size_t>(near.index[q])];
        if (col >= 0) add_column(static_cast<std::size_t>(col), n_ik.dot(geo.dn_pair[q]));
      }
    };
    const auto i = static_cast<std::size_t>(particle_of_row[r]);
    if (step_alpha < 1) {  // G (at alpha = 1 the matrix is the scaled Laplacian alone)
      assert(geo.all_derivatives);
      if (roles[i] == Role::fluid) visit_k(i, geo.dn_self[i]);
      // Entry q of row i, neighbour k, holds dn_k/dx_i = -dn_i/dx_k; likewise for the group's dummies.
      for (std::size_t q = near.begin(i); q < near.end(i); ++q) {
        const auto k = static_cast<std::size_t>(near.index[q]);
        if (roles[k] == Role::fluid) visit_k(k, -geo.dn_pair[q]);
      }
      for (std::size_t e = member_ptr[r]; e < member_ptr[r + 1]; ++e) {
        const auto m = static_cast<std::size_t>(members[e]);
        for (std::size_t q = near.begin(m); q < near.end(m); ++q) {
          const auto k = static_cast<std::size_t>(near.index[q]);
          if (roles[k] == Role::fluid) visit_k(k, -geo.dn_pair[q]);
        }
      }
    }
    if (step_alpha > 0)
      // The pairs of the row's group (its particle and its dummies) with the other groups' particles.
      for (std::size_t e = member_ptr[r]; e <= member_ptr[r + 1]; ++e) {
        const std::size_t a = e < member_ptr[r + 1] ? static_cast<std::size_t>(members[e]) : i;
        for (std::size_t q = near.begin(a); q < near.end(a); ++q) {
          const auto j = static_cast<std::size_t>(near.index[q]);
          const LocalIndex col = column_of_particle[j];
          if (col < 0 || static_cast<std::size_t>(col) == r) continue;
          if (column_inside[static_cast<std::size_t>(col)]) continue;
          const Real v = row_lap_scale * (geo.x ? weight(((*geo.x)[a] - (*geo.x)[j]).norm(), re_g) : geo.lap_weight[q]);
          add_laplacian_column(static_cast<std::size_t>(col), -v);
          add_laplacian_column(r, v);
        }
      }
    touch(r);
    std::sort(touched.begin(), touched.begin() + static_cast<std::ptrdiff_t>(n_touched));
    row_col.resize(n_touched);
    row_val.resize(n_touched);
    for (std::size_t t = 0; t < n_touched; ++t) {
      const LocalIndex col = touched[t];
      const auto q = static_cast<std::size_t>(col);
      row_col[t] = col;
      row_val[t] = row_scale * acc[q] + lap_acc[q];
      acc[q] = 0;
      lap_acc[q] = 0;
      touched_flag[q] = 0;
    }
  }

  /// sum + (operator x)_r, every column at its particle's value of x (computes row r: operator_row).
  Real add_row_times(const std::size_t r, const std::vector<Real>& x, Real sum) {
    operator_row(r);
    for (std::size_t e = 0; e < row_col.size(); ++e)
      sum += row_val[e] * x[static_cast<std::size_t>(column_particle[static_cast<std::size_t>(row_col[e])])];
    return sum;
  }

  /// The rows of the projection: G p + p / (c^2 dt^2) = kappa rho / dt^2 (n*_i - n0) / n0 (prepare_rows) over
  /// the rows and columns that are not free surface; free-surface rows p = 0. The first assembly of a step lays
  /// out every row's entries whatever its flag (a free-surface row or column holds zeros off the diagonal),
  /// except the dry rows', which stay free surface through the step; the active set's re-solves then write
  /// only the rows whose flag or a column's flag changed (LocalRows::values_only).
  void assemble_projection(const Real dt) {
    const bool layout = !rows_ready;
    if (!rows_ready) {
      prepare_rows(dt);
      rows_ready = true;
    }
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const std::size_t n_rows = particle_of_row.size();
    const std::size_t n_columns = column_particle.size();
    // The first step solves for the incompressible pressure (kappa 1), with a compressibility that does not
    // depend on dt (start_compressibility).
    row_compress = initial_step() ? start_compressibility : 1.0 / (c * c * dt * dt);
    projection_source = (initial_step() ? 1.0 : kappa) * rho / (dt * dt) / n0_kernel;
    sys.values_only = !layout;
    sys.changed_rows.clear();
    column_surface.resize(n_columns);
    for (std::size_t q = 0; q < n_columns; ++q) column_surface[q] = surface[static_cast<std::size_t>(column_particle[q])] != 0;
    if (layout) {
      // A dry row of this rank's: free surface through the step, no entry in its column.
      column_dry.assign(n_columns, 0);
      for (std::size_t q = 0; q < n_rows; ++q) column_dry[q] = dry[static_cast<std::size_t>(column_particle[q])];
      // The entries: a dry row its diagonal alone, the others the operator's entries in the columns that are
      // not dry. The arrays keep their capacity between steps unless it is far above the size (trim_oversized).
      sys.col.clear();
      sys.value.clear();
      sys.row_ptr[0] = 0;
      remote_rows.clear();  // the rows with an entry in a column of another rank's row
      for (std::size_t r = 0; r < n_rows; ++r) {
        if (column_dry[r]) {
          sys.col.push_back(static_cast<LocalIndex>(r));
          row_col.clear();  // a dry row is a free-surface row: its diagonal alone
          row_val.clear();
        } else {
          operator_row(r);
          for (const LocalIndex q : row_col)
            if (!column_dry[static_cast<std::size_t>(q)]) sys.col.push_back(q);
          if (!row_col.empty() && static_cast<std::size_t>(row_col.back()) >= n_rows) remote_rows.push_back(static_cast<LocalIndex>(r));
        }
        sys.row_ptr[r + 1] = sys.col.size();
        sys.value.resize(sys.col.size());
        write_row(r);
      }
      trim_oversized(sys.col);  // the first step's system is the widest of the run
      trim_oversized(sys.value);
      assert(pattern_is_symmetric());
      assembled_column_surface = column_surface;
      return;
    }
    // The columns whose free-surface flag changed since the last assembly; a row is rewritten when its own
    // column (r) or one of its entries' did. The pattern is symmetric (pattern_is_symmetric), so the rows with an
    // entry in a changed column of this rank's are that column's own entries; a changed column of another rank's
    // row is looked for in the rows that have such columns (remote_rows). A dry column never changes.
    const auto changed_column = [&](const std::size_t q) { return column_surface[q] != assembled_column_surface[q]; };
    rewrite.assign(n_rows, 0);
    for (std::size_t q = 0; q < n_rows; ++q) {
      if (!changed_column(q)) continue;
      rewrite[q] = 1;
      for (std::size_t e = sys.row_ptr[q]; e < sys.row_ptr[q + 1]; ++e)
        if (static_cast<std::size_t>(sys.col[e]) < n_rows) rewrite[static_cast<std::size_t>(sys.col[e])] = 1;
    }
    bool remote_changed = false;
    for (std::size_t q = n_rows; q < n_columns && !remote_changed; ++q) remote_changed = changed_column(q);
    if (remote_changed)
      for (const LocalIndex r : remote_rows)
        for (std::size_t e = sys.row_ptr[static_cast<std::size_t>(r)]; e < sys.row_ptr[static_cast<std::size_t>(r) + 1]; ++e)
          if (changed_column(static_cast<std::size_t>(sys.col[e]))) rewrite[static_cast<std::size_t>(r)] = 1;
    for (std::size_t r = 0; r < n_rows; ++r) {
      if (!rewrite[r] || column_dry[r]) continue;
      operator_row(r);
      write_row(r);
      sys.changed_rows.push_back(static_cast<LocalIndex>(r));
    }
    assembled_column_surface = column_surface;
  }

  /// Whether every entry (r, c) of the system between two rows of this rank's has its transpose (c, r) (the
  /// operator's pattern: the pairs of the near list, which holds both directions, and G = N N^T; the dry rows
  /// and columns left out alike).
  bool pattern_is_symmetric() const {
    const std::size_t n_rows = particle_of_row.size();
    for (std::size_t r = 0; r < n_rows; ++r)
      for (std::size_t e = sys.row_ptr[r]; e < sys.row_ptr[r + 1]; ++e) {
        const auto c = static_cast<std::size_t>(sys.col[e]);
        if (c >= n_rows) continue;
        if (!std::binary_search(sys.col.begin() + static_cast<std::ptrdiff_t>(sys.row_ptr[c]),
                                sys.col.begin() + static_cast<std::ptrdiff_t>(sys.row_ptr[c + 1]), static_cast<LocalIndex>(r)))
          return false;
      }
    return true;
  }

  /// Row r's values and right-hand side on the entries assemble_projection laid out, from the operator's row r
  /// in row_col / row_val (operator_row; a dry row's diagonal alone needs none) and the free-surface flags by
  /// column, column_surface (row r's particle is column r's).
  void write_row(const std::size_t r) {
    Real* value = sys.value.data() + sys.row_ptr[r];
    if (column_surface[r]) {
      const Real dirichlet_diag = 2.0 * dim / lat_l.lambda + row_compress;
      const LocalIndex* col = sys.col.data() + sys.row_ptr[r];
      for (std::size_t k = 0; k < sys.row_ptr[r + 1] - sys.row_ptr[r]; ++k)
        value[k] = col[k] == static_cast<LocalIndex>(r) ? dirichlet_diag : 0.0;
      sys.rhs[r] = dirichlet_diag * surface_pressure_of_column(r);
      return;
    }
    sys.rhs[r] = projection_source * row_error[r];
    for (std::size_t e = 0; e < row_col.size(); ++e) {
      const auto q = static_cast<std::size_t>(row_col[e]);
      if (column_surface[q]) sys.rhs[r] -= row_val[e] * surface_pressure_of_column(q);
      if (column_dry[q]) continue;
      *value++ = column_surface[q] ? 0.0 : row_val[e] + (q == r ? row_compress : 0.0);
    }
  }

  /// The free-surface pressure of column q's particle.
  Real surface_pressure_of_column(const std::size_t q) const {
    return (*surface_pressure)[static_cast<std::size_t>(column_particle[q])];
  }

  /// The complementarity of the density constraint, p >= 0, w = A p - b >= 0, p w = 0 (a primal-dual active
  /// set step): rows whose pressure came out negative become free-surface (p = 0) rows; free-surface rows whose
  /// density the other rows' pressures do not bring down to n0 (w_i < 0, the particle would stay compressed)
  /// become rows again, with `additions` only (the later updates of one time step only remove rows: the set
  /// then shrinks and the iteration ends; a primal-dual active set can cycle when the matrix is not an
  /// M-matrix, as this one is not). A fluid particle's density after the step is the one the correction it
  /// will be given makes (correction_velocities, capped), b_i + dt sum_j dn_i/dx_j . dv_j (density_change):
  /// the rows' operator measures it only where it is G, and its stabilisation counts the neighbours' pressure
  /// as a flux into a free-surface particle that the force in fact pushes out (a flux that grows as
  /// p dt^2 / (rho dp^2) against the particle's density shortfall). A wall or solid row keeps the test w < 0.
  /// The pressures of the ghosts must be current. Whether any row changed on any rank.
  bool update_active_set(const bool additions, const Real dt, FluidStepReport& report) {
    auto& surface = p.scalar_field(fluid_fields::free_surface);
    const auto& pressure = p.scalar_field(fluid_fields::pressure);
    const Real w_tolerance = 1e-9 * projection_source * n0_kernel;  // a relative density change of 1e-9
    auto& trial_dv = p.vector_field(trial_dv_field);
    if (additions) {
      correction_velocities(dt, p.n_owned(), trial_dv);  // 0 for the others: the fluid ghosts' alone are sent
      core.refresh_ghosts({trial_dv_field}, report, ParticleKind::fluid);
    }
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
      if (roles[i] == Role::fluid) {
        // The particle's own density: in the first step its error at the start too, which that step's rows
        // leave out (prepare_rows), so that a free-surface particle of the start, short of neighbours, is not
        // taken for a compressed one.
        const Real start_error = linear_source ? initial_error[i] : 0.0;
        if (start_error + row_error[r] + dt * density_change(i, false, [&](const std::size_t j) { return trial_dv[j]; }) >
            1e-9 * n0_kernel) {
          surface[i] = 0;
          changed = 1;
        }
        continue;
      }
      const Real w = add_row_times(r, pressure, -projection_source * row_error[r]);
      if (w < -w_tolerance) {
        surface[i] = 0;
        changed = 1;
      }
    }
    MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_MAX, comm);
    return changed != 0;
  }

  /// The projection's first step (the start from rest), whose system is the incompressible one: kappa 1, the
  /// compressibility start_compressibility, stabilisation start_alpha.
  bool initial_step() const { return n_steps == 0; }

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
    linear_source = false;
    // The offsets on the geometry of the moved fluid positions, which the next step's rows see, with the walls
    // and solids at their start as in the first step's rows (linear_change); the correction of this step on the
    // geometry of its rows (the start's), kept aside meanwhile.
    Geometry start;
    std::swap(geo, start);
    std::vector<Vec> rest_position = p.position;
    for (std::size_t j = 0; j < rest_position.size(); ++j)
      if (roles[j] != Role::fluid) rest_position[j] = start_position[j];
    projection_geometry(rest_position, false);
    prepare_rows(dt);  // G' of the later steps (the offsets are still 0: row_error is b)
    auto& rest_offset = p.scalar_field(rest_offset_field);
    auto& rest_rate = p.scalar_field(rest_rate_field);
    const auto& surface = p.scalar_field(fluid_fields::free_surface);
    const auto& pressure = p.scalar_field(fluid_fields::pressure);  // p0, current at the ghosts
    const Real s = kappa * rho / (dt * dt) / n0_kernel;
    for (std::size_t r = 0; r < particle_of_row.size(); ++r) {
      const auto i = static_cast<std::size_t>(particle_of_row[r]);
      if (surface[i] != 0) continue;
      const Real g_p = add_row_times(r, pressure, 0.0);  // (G' p0)_r, free-surface columns at their pressure
      rest_offset[i] = pressure[i] * n0_kernel / (kappa * rho * c * c) - initial_error[i];
      rest_rate[i] = (g_p / s - (row_error[r] - initial_error[i])) / (dt * dt);
    }
    geo = std::move(start);
    std::vector<Vec>().swap(start_position);
  }

  /// The projection's correction: v_k += -(dt/rho)(d/C) sum_j (p_k + p_j - 2 b_k) dn_j/dx_k, r_k += dt dv_k, for
  /// the fluid particles k; the sum runs over the neighbours j that carry a pressure (rows and wall groups; the
  /// others add p_k dn_j/dx_k). With b_k = 0 it is the transpose of the rows' operator, (d/C)(p_k dn_k/dx_k +
  /// sum_j p_j dn_j/dx_k); b_k = max(0, p_k - p_cap) caps the pressure the force's stiffness carries
  /// (stiffness_number in fluid/fluid_solver.hpp).
  void correct_projection(const Real dt) {
    const std::size_t n = p.n_owned();
    dv.resize(n);
    correction_velocities(dt, n, dv);
    for (std::size_t k = 0; k < n; ++k) {
      if (roles[k] != Role::fluid) continue;
      p.velocity[k] += dv[k];
      p.position[k] += dt * dv[k];
    }
  }

  /// The correction's velocity change dv_k of correct_projection for the particles [0, n) (0 for the ones that
  /// are not fluid) into out[0, n), with the pressures as they are.
  void correction_velocities(const Real dt, const std::size_t n, std::vector<Vec>& out) const {
    assert(out.size() >= n);
    const auto& pressure = p.scalar_field(fluid_fields::pressure);
    // The start from rest (the first step) carries its whole pressure: its force is the transpose of its
    // rows, so that p0 holds the water (at fine spacings p0 is far above p_cap at the first step's dt).
    const Real p_cap = initial_step() ? std::numeric_limits<Real>::infinity()
                                      : stiffness_number * rho * dp * dp / (dt * dt);
    for (std::size_t k = 0; k < n; ++k) {
      out[k].setZero();
      if (roles[k] != Role::fluid) continue;
      Vec f = pressure[k] * geo.dn_self[k];
      const Real two_b = 2.0 * std::max(0.0, pressure[k] - p_cap);
      for (std::size_t q = near.begin(k); q < near.end(k); ++q) {
        const auto j = static_cast<std::size_t>(near.index[q]);
        if (has_row(roles[j])) f += (pressure[j] - two_b) * geo.dn_pair[q];
        else if (geo.parent_of[j] >= 0) f += (pressure[static_cast<std::size_t>(geo.parent_of[j])] - two_b) * geo.dn_pair[q];
      }
      out[k] = -dt / rho * geo.projection_scale * f;
    }
  }

  /// The projection: surface_value of every owned particle (surface_pressure_field). A particle whose
  /// neighbours balance (|dn_k/dx_k| at round-off, inside a regular arrangement) has no normal: 0.
  void surface_pressures() {
    const std::size_t n = p.n_owned();
    auto& value = p.scalar_field(surface_pressure_field);
    std::fill(value.begin(), value.begin() + static_cast<std::ptrdiff_t>(n), 0.0);
    const Real no_normal = 1e-9 * n0_kernel / dp;
    for (std::size_t k = 0; k < n; ++k) {
      const Real norm = geo.dn_self[k].norm();
      if (roles[k] != Role::fluid || !(norm > no_normal)) continue;
      value[k] = 0.5 * rho * dp * std::max(0.0, gravity.dot(geo.dn_self[k]) / norm);
    }
  }


  FluidCore& core;
  // The core's state under the names the scheme's formulas use.
  ParticleSet& p;
  const Real& dp;
  const Real& re_g;
  const LatticeConstants& lat_g;
  const LatticeConstants& lat_l;
  const Vec& gravity;
  const Real& rho;
  const Real& c;
  const Real& kappa;
  const std::size_t& n_steps;
  const MPI_Comm& comm;
  const std::vector<Role>& roles;
  NeighbourList& near;
  std::vector<Vec>& dv;
  std::vector<LocalIndex>& row_of;
  std::vector<LocalIndex>& particle_of_row;
  LocalRows& sys;
  std::vector<Real>& x_own;
  Real re_p = 0;  ///< radius of the projection's density kernel (fluid.projection_radius)
  Real step_alpha = 0;            ///< the stabilisation of this step's matrix: start_alpha in the first step, else alpha
  /// The first step's stabilisation: nearly the exact projection, whose pressure balances gravity in the
  /// force's own terms, with enough of the Laplacian to keep G's near-null pressure modes out of p0 (at 0 they
  /// put errors of up to 90 % next to the walls at dp 1 cm; docs/validation.md, ## Fluid).
  static constexpr Real start_alpha = 0.1;
  /// The first step's compressibility: a screening length of 100 times the water's extent D (initial_state),
  /// 1e-4 / D^2, which keeps the rows regular without bounding p0's reach (the case's 1 / (c^2 dt^2) would
  /// screen p0 over about 100 c dt, a length that shrinks with dt).
  Real start_compressibility = 0;
  int max_active_set_solves = 6;  ///< fluid.max_active_set_solves
  Real stabilisation = 0;         ///< alpha of fluid.projection_stabilisation
  DensityKernel kernel = DensityKernel::wendland;  ///< fluid.projection_kernel
  Real n0_kernel = 0;             ///< n0 of that kernel at re_gradient
  Real c_lattice = 0;             ///< its sum_j -w'(r_j) r_j on the lattice (C when no particle is interior)
  Real projection_source = 0;     ///< kappa rho / (dt^2 n0) of the step's rows (assemble_projection)
  Real row_compress = 0;          ///< the compressibility 1 / (c^2 dt^2) of the step's rows (assemble_projection)

  Geometry geo;                          ///< projection: the geometry of this step's rows and correction
  const std::vector<Real>* surface_pressure = nullptr;  ///< surface_pressure_field, current at the ghosts (prepare)
  std::vector<Real> initial_error;       ///< projection, first step: each row's density error at the start
  static constexpr Real inside_flag = 2;  ///< the free-surface flag of a dry row inside the walls (after_surface)
  std::vector<std::uint8_t> dry;         ///< projection: a wall or solid row that no fluid particle reads
  std::vector<std::size_t> member_ptr;   ///< projection: each row's group dummies (CSR)
  std::vector<LocalIndex> members;
  std::vector<Real> row_error;           ///< projection: each row's density error (with its group's)
  std::vector<Real> acc;                 ///< projection: a row's entries by column while it is assembled (G ...
  std::vector<Real> lap_acc;             ///< ... and the stabilisation)
  std::vector<std::uint8_t> touched_flag;
  std::vector<LocalIndex> touched;
  std::vector<LocalIndex> column_of_particle;  ///< projection: column_of of each particle in the near list (prepare_rows)
  std::vector<LocalIndex> row_col;       ///< projection: the operator's row of the last operator_row (sorted columns)
  std::vector<Real> row_val;
  Real row_scale = 0, row_lap_scale = 0;    ///< projection: the factors of G and of the stabilisation (prepare_rows)
  std::vector<LocalIndex> column_particle;  ///< projection: the particle of each column
  std::vector<std::uint8_t> column_inside;  ///< projection: each column's particle is a dry row inside the walls
  bool rows_ready = false;                  ///< prepare_rows done for this step
  /// The first solve's rows take the density change of the step's displacements to first order (prepare_rows):
  /// the error that G's correction removes, so that p0 does not depend on how far dt moves the fluid.
  bool linear_source = false;
  std::vector<Vec> start_position;          ///< the first step: every particle's position before it moves
  std::vector<std::uint8_t> column_surface;            ///< projection: each column's free-surface flag
  std::vector<std::uint8_t> assembled_column_surface;  ///< ... at the last assembly
  std::vector<std::uint8_t> column_dry;                ///< projection: each column's dry flag (this step)
  std::vector<std::uint8_t> rewrite;                   ///< projection: the rows a re-assembly rewrites
  std::vector<LocalIndex> remote_rows;                 ///< projection: the rows with columns of other ranks' rows
};

}  // namespace

std::unique_ptr<PressureScheme> make_projection_scheme(FluidCore& core, const FluidParameters& parameters) {
  return std::make_unique<ProjectionScheme>(core, parameters);
}

}  // namespace mpsfsi::fluid_detail
