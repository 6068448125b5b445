// The state one fluid step shares between its phases (fluid/fluid_core.cpp) and its pressure scheme
// (fluid/pressure_scheme.hpp): the particles and their roles, the neighbour lists, the numbering of the pressure
// rows and the pressure system, the fluid's material and the step's gravity. Internal to fluid/: FluidSolver
// (fluid/fluid_solver.cpp) runs a step as a sequence of these phases and of its scheme's.
#pragma once

#include "core/distribution.hpp"
#include "core/geometry.hpp"
#include "core/kernel.hpp"
#include "core/neighbours.hpp"
#include "core/particles.hpp"
#include "core/tank_motion.hpp"
#include "core/wall_motion.hpp"
#include "core/time_spec.hpp"
#include "fluid/fluid_solver.hpp"
#include "fluid/pressure_solver.hpp"

#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mpsfsi::fluid_detail {

/// What a particle does in the fluid computation.
enum class Role : std::uint8_t {
  fluid,     ///< moves with the fluid equations, PPE row
  boundary,  ///< prescribed position and velocity, PPE row (wall particles; solids when coupled)
  dummy,     ///< counts in the number density only
  none       ///< ignored (solids when not coupled)
};

inline bool has_row(const Role r) { return r == Role::fluid || r == Role::boundary; }

/// The phases of a step that do not depend on the pressure scheme, and what they leave for it.
struct FluidCore {
  /// The fluid's material, the kernels' radii and lattice constants, the pressure solver; throws
  /// std::invalid_argument when the particles hold more than one fluid material or none.
  FluidCore(const FluidSetup& setup, ParticleSet& particles, Distribution& distribution, const FluidOptions& options);

  /// The particle field that holds each wall particle's position in the tank's rest frame (moving tanks), or at
  /// rest (walls that move on their own).
  static constexpr const char* wall_reference_field = "wall_reference";

  /// The particle fields that keep a coupled solid's view (FluidSolver::set_solid_boundary) with its particles:
  /// 1 for a surface (boundary) particle, 0 for a dummy; the reference density (n^0)_solid and the density
  /// offset; the position and velocity of the view, which hold the solid's own while the step runs.
  static constexpr const char* solid_surface_field = "_fluid_solid_surface";
  static constexpr const char* solid_reference_field = "_fluid_solid_n0";
  static constexpr const char* solid_offset_field = "_fluid_solid_offset";
  static constexpr const char* solid_x_field = "_fluid_solid_x";
  static constexpr const char* solid_v_field = "_fluid_solid_v";

  Role role(ParticleKind k) const;
  /// Takes a coupled solid's view into the fields above (this rank's owned solid particles; see
  /// FluidSolver::set_solid_boundary).
  void set_solid_boundary(const SolidBoundaryData& data);
  /// At the start of a step with a new view: the owned solid particles take the view's position and velocity
  /// (theirs are kept in its fields); with reference densities the solid ghosts are renewed and the density
  /// offsets taken where the fluid sees the solid. Returns the halo time [s].
  double place_solid_view();
  /// At the end of the step (or when it throws): the owned solid particles get their own position and velocity
  /// back. Does nothing when no view is placed.
  void release_solid_view();
  /// Exchanges the owned solid particles' position and velocity with the view's fields.
  void swap_solid_view();
  /// roles of every particle (owned and ghosts) for this step.
  void classify();
  /// The particle field that marks, for leave_out_far_walls, the wall and dummy particles that take part.
  static constexpr const char* near_fluid_field = "_fluid_near_fluid";
  /// After classify (and the first step's initial state): the wall and dummy particles farther than `reach`,
  /// plus the step's moves, from every fluid particle that a rank holding them holds (owned or ghost) take no
  /// part in the step (role none): no row of the step reads them when `reach` covers the scheme's chain of pairs
  /// from a fluid particle (PressureScheme::wall_reach). A particle takes part on every rank that holds it as
  /// soon as one of them needs it, so that the ranks' rows agree; a rank without fluid keeps its walls. Returns
  /// the halo time [s].
  double leave_out_far_walls(Real reach, Real dt);
  /// The particle field that holds each owned particle's neighbours in the step's near and wide lists (0 for a
  /// particle that took no part, and before the first step): the partition's measure of its work
  /// (fluid_work_weights).
  static constexpr const char* work_field = "_fluid_work";
  /// After build_near_list: work_field of the owned particles from their rows in both lists.
  void note_work();
  /// Walls and their dummy layers follow the tank motion (rotation about the pivot, v = omega x r) or their own
  /// (core/wall_motion.hpp), to their place and velocity at t.
  void move_walls(Real t);
  /// Whether any wall moves (with the tank or on its own).
  bool walls_move() const { return motion.moving() || !body_motion.empty(); }
  /// The rotation of wall particle j's body at the last move_walls (the identity for walls at rest).
  const Mat& wall_rotation(std::size_t j) const;
  /// Eq. 12, 16, 17: v* = v + dt (nu lap v + g), r* = r + dt v* for fluid particles (fluid/fluid_core.cpp).
  void predict(Real dt);
  /// The wide list nl (pairs within re_laplacian) at the current positions, rows of the owned particles that
  /// need it only: the fluid particles for the viscous term (nu > 0), and with `row_particles` every particle
  /// with a pressure row (a Laplacian of re_laplacian in the rows); the other rows are empty.
  void build_wide_list(bool row_particles);
  /// The near list: the pairs within `radius` (in_support) at the current positions of the particles that take
  /// part, rows of the owned particles and of the ghosts whose role `ghost_needs_row` names (the others' rows
  /// empty), each row in increasing index order. With predicted_dt (the step's predict moved the fluid since
  /// build_wide_list), the wide list's rows are filtered where they cover the near ones.
  void build_near_list(Real radius, const std::function<bool(Role)>& ghost_needs_row, std::optional<Real> predicted_dt);
  /// Collision model (MPS-Basic collision()).
  void collide(Real dt);
  /// Eq. 8 at the predicted positions: n*, and the free-surface double check; `keep_surface`: a particle
  /// flagged in the last step stays flagged (the active set's warm start).
  void density_and_surface(bool keep_surface);
  /// The rows of this rank (owned particles with a pressure unknown), the remote columns, the coarse groups
  /// and the solve's absolute tolerance; sizes sys.row_ptr and sys.rhs.
  void number_rows(Real dt);
  /// Solves sys; free-surface rows hold surface_value(i) (a function of the scheme), negative pressures are
  /// clipped to 0.
  template <class SurfaceValue>
  PressureSolveResult solve_pressure(const SurfaceValue& surface_value);
  /// Refreshes these fields at the ghosts from their owners.
  void refresh_ghosts(const std::vector<std::string>& fields, FluidStepReport& report,
                      std::optional<ParticleKind> only = std::nullopt);
  /// Walls hold water: a fluid particle that ends the step inside the lattice cell of a wall or dummy particle,
  /// or in a gap between those cells and a face off the lattice, goes back onto that wall's wetted surface (the
  /// particle's wall_surface_field offset), and its velocity
  /// towards the wall, relative to the wall, is reflected with the collision model's restitution. Returns
  /// the particles put back. Off when the particles have no wall_surface_field (docs/architecture.md).
  std::size_t keep_out_of_walls();
  /// Fluid particles outside the case's domain are removed (with the ghosts, renewed at the next step).
  std::size_t remove_escaped();

  ParticleSet& p;
  Distribution& dist;
  FluidOptions opt;
  TankMotion motion;
  /// The walls' own motions by ParticleSet body index (a motion that does not move for the other bodies); empty
  /// when no wall moves on its own.
  std::vector<WallMotion> body_motion;
  std::vector<WallMotionState> body_state;  ///< each body's motion at the last move_walls (at rest: the identity)
  int rank = 0;
  Real dp = 0, re_g = 0, re_l = 0;
  /// The side of the neighbour searches' cells, and of the cell order the particles are kept in, so that the
  /// lists' rows come out nearly sorted.
  Real cell_size = 0;
  LatticeConstants lat_g, lat_l;
  Real beta1 = 0, beta2 = 0;
  Vec gravity = Vec::Zero();       ///< of the current step: gravity_full times the ramp at its middle
  Vec gravity_full = Vec::Zero();  ///< the case's gravity
  Real gravity_ramp = 0;           ///< [s] (core/ramp.hpp)
  TimeSpec time;
  Rect domain;
  Real rho = 1000, nu = 0, c = 20, kappa = 1;
  Real lateral_friction = 0;  ///< k [1/s] of fluid.lateral_walls (0: off)
  Real wall_omega = 0;        ///< the tank's angular velocity at the end of the current step
  Real wall_theta = 0;        ///< the tank's angle at the end of the current step
  Real tolerance = 1e-8;
  Real coarse_cell = 0;        ///< side of the pressure solve's coarse groups (0: none)
  Real density_tolerance = 0;  ///< fluid.density_tolerance: absolute stop, RMS of r dt^2 / rho
  Real density_tolerance_cap = std::numeric_limits<Real>::infinity();  ///< set_density_tolerance_cap
  std::string preconditioner;
  std::unique_ptr<PressureSolver> solver;
  std::size_t n_steps = 0;
  std::size_t n_steps_stored = 0;  ///< n_steps at the last iteration checkpoint
  MPI_Comm comm = MPI_COMM_NULL;
  bool solid_boundary = false;  ///< a coupled solid has set its view (set_solid_boundary)
  bool solid_offsets = false;   ///< ... with density offsets
  bool solid_view_new = false;  ///< set_solid_boundary was called since the last step
  bool solid_view_placed = false;  ///< the owned solid particles hold the view (place_solid_view)
  std::vector<Vec> solid_x;  ///< scratch of place_solid_view: the solid particles' positions (owned and ghosts)
  std::vector<LocalIndex> solid_at;  ///< their local indices
  NeighbourList solid_nl;
  CellGrid solid_grid;

  // Work arrays, reused between steps.
  std::vector<Role> roles;
  NeighbourList nl, near;
  CellGrid grid, near_grid;
  std::vector<std::uint8_t> wide_row, near_row, takes_part;  ///< the masks of the lists' rows and candidates
  std::vector<Real> n_star;
  std::vector<Vec> v_new, dv;
  std::vector<LocalIndex> row_of;  ///< local column id of each particle's pressure unknown, -1 if none
  std::vector<LocalIndex> particle_of_row;
  LocalRows sys;
  std::vector<Real> x_own;
  std::vector<std::uint8_t> remove;
};

template <class SurfaceValue>
PressureSolveResult FluidCore::solve_pressure(const SurfaceValue& surface_value) {
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

}  // namespace mpsfsi::fluid_detail
