// The incompressible free-surface fluid of seed 004 §4.1 and §4.3 (semi-implicit MPS, eq. 7-24), as a
// participant of the run loop: the driver asks for a stable dt (eq. 52 plus the viscous limit) and
// advances it one step at a time. Trilinos stays behind fluid/pressure_solver.hpp; this header
// includes none of it. Its parameters live in fluid/fluid_parameters.hpp (FluidSetup); it sees no case file.
#pragma once

#include "core/participant.hpp"
#include "core/particles.hpp"
#include "fluid/pressure_solver.hpp"
#include "core/kernel.hpp"
#include "core/time_spec.hpp"
#include "fluid/fluid_parameters.hpp"

#include <mpi.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace mpsfsi {

class Distribution;

/// What one fluid step did, for the log and the benchmarks.
struct FluidStepReport {
  Real dt = 0;
  int iterations = 0;          ///< pressure-solver iterations (of all solves)
  int solves = 1;              ///< pressure solves (scheme projection: one per active set)
  Real residual = 0;           ///< achieved relative residual of the pressure solve
  std::size_t n_surface = 0;   ///< free-surface particles
  Real max_speed = 0;          ///< largest fluid particle speed after the step [m/s]
  std::size_t n_rows = 0;      ///< rows of the pressure system (fluid + wall particles)
  std::size_t n_removed = 0;   ///< fluid particles removed this step because they left the domain
  std::size_t n_put_back = 0;  ///< fluid particles put back out of a wall this step (FluidCore::keep_out_of_walls)
  // Wall time of the phases [s].
  double t_neighbours = 0, t_assembly = 0, t_setup = 0, t_solve = 0, t_rest = 0;
  double t_halo = 0;  ///< owners, ghosts and their refreshes (core/distribution.hpp)
};

/// The decay rate k [1/s] of the velocity relative to the tank that fluid.lateral_walls gives a fluid of
/// kinematic viscosity nu [m^2/s]: stokes sqrt(2 nu omega) / gap, poiseuille 12 nu / gap^2; 0 when off.
/// Throws std::invalid_argument for an unknown model.
Real lateral_wall_friction_rate(const LateralWallFriction& walls, Real nu);

/// Numerical choices that are not (yet) in the case file.
struct FluidOptions {
  Real collision_distance = 0.5;   ///< collision model: pairs closer than this x dp (docs/architecture.md)
  Real restitution = 0.2;          ///< collision model: restitution coefficient
  int reorder_every = 20;          ///< cell-order the particles every N steps (0: never; skipped with solids)
  Real viscous_number = 0.2;       ///< viscous limit dt <= viscous_number dp^2 / nu
  /// Solid particles take part as boundary particles with prescribed position and velocity (PPE rows,
  /// number density, collisions), like wall particles. Off: solids are ignored by the fluid.
  bool solid_as_boundary = false;
  /// Coupled runs: a coupling gives the fluid its view of the solid before each step
  /// (FluidSolver::set_solid_boundary); the fluid registers the particle fields that keep it.
  bool coupled_solid = false;
};

/// What a coupled solid shows the fluid for its next step: typed interface data, by global id, of each of this
/// rank's owned solid particles (in the manner of a preCICE participant's read data). A particle on the solid's
/// surface (eq. 48) is a boundary particle of the fluid (prescribed position and velocity, PPE row), one inside it a
/// dummy (number density only). The fluid sees each particle at `position` with `velocity` for its next step and
/// leaves the solid's own state as it found it. With density_offsets, the fluid adds (n^0)_solid - (n)_solid
/// to n* of a surface particle in the PPE source and the free-surface check, (n)_solid the number density of the
/// solid's particles alone where the fluid sees them, so that the solid's own deformation does not act as a fluid
/// density error.
struct SolidBoundaryData {
  std::vector<GlobalId> ids;            ///< this rank's owned solid particles, in local order
  std::vector<std::uint8_t> surface;    ///< 1: on the surface (boundary), 0: inside (dummy); one per id
  std::vector<Vec> position;            ///< where the fluid sees each particle in its next step
  std::vector<Vec> velocity;            ///< and with which velocity
  std::vector<Real> reference_density;  ///< (n^0)_solid of each when density_offsets
  bool density_offsets = false;         ///< the fluid takes density offsets (the same on every rank)
};

/// The largest interaction radius of the fluid [m] (the neighbour search's): the distribution's halo
/// must reach at least this far, plus the distance particles move in a step.
Real fluid_interaction_radius(const FluidSetup& setup);

/// Work of one particle of `kind` in a fluid step relative to a fluid particle, for the partition of the
/// particles over the ranks: every particle is in the neighbour search, walls also have pressure rows, fluid
/// particles also the explicit phases (docs/performance.md, ## Parallel runs); the weights differ by dimension.
/// Other kinds: 1. A wall or dummy particle that took no part in the last fluid step (far from the fluid,
/// `takes_part` false) costs little.
Real fluid_work_weight(ParticleKind kind, bool takes_part = true);
/// Whether particle i of p took part in the last fluid step: every particle but a wall or dummy particle that
/// the last step left out, far from the fluid (every particle of a set the fluid has not stepped yet).
bool fluid_takes_part(const ParticleSet& p, std::size_t i);
/// fluid_work_weight of the first n particles of p, with the marks of the last fluid step where p has them (a
/// set the fluid has not stepped yet: every particle takes part); where the last step counted each particle's
/// pairs, a fluid, wall or dummy particle's weight scales with its pairs against its kind's mean over the ranks
/// of comm (a collective; with p replicated on every rank, the means are the same).
std::vector<Real> fluid_work_weights(const ParticleSet& p, std::size_t n, MPI_Comm comm);

/// The projection's force on fluid particle k, -(1/rho)(d/C) sum_i p_i dn_i/dx_k = -(1/rho)(d/C) sum_j (p_k + p_j)
/// dn_j/dx_k, holds the whole pressure, not a difference of pressures: a particle displaced by xi from its
/// neighbours feels a restoring acceleration of order p xi / (rho dp^2), a stiffness that the step integrates
/// explicitly and that is stable only while p dt^2 / (rho dp^2) stays below a bound (0.12-0.24, measured in
/// docs/validation.md, "Fluid at every resolution"). The correction therefore takes p_k + p_j - 2 b_k in place of
/// p_k + p_j, b_k = max(0, p_k - p_cap), p_cap = stiffness_number rho dp^2 / dt^2: the stiffness carries at most
/// p_cap. The term taken away, -2 b_k dn_k/dx_k, is zero wherever the neighbours of k lie on a regular
/// arrangement (a full support, or the walls' lattice), so the force there is unchanged; as dt -> 0 the cap
/// rises above every pressure and the force is the transpose of the rows' operator. Not in the first step (the
/// start from rest), whose force must hold its pressure exactly.
inline constexpr Real stiffness_number = 0.09;

/// Largest admissible fluid dt: time.dt when fixed, else the smallest of time.dt_max, the CFL limit of
/// eq. 52 for the largest speed v_max, the same limit for a particle that starts at rest under the
/// acceleration |g| (sqrt(C dp / |g|)) and the viscous limit viscous_number dp^2 / nu. `limit`, if given,
/// receives the name of the active limit ("fixed", "dt_max", "cfl", "acceleration", "viscous").
Real fluid_stable_dt(const TimeSpec& time, Real dp, Real nu, Real acceleration, Real v_max, Real viscous_number,
                     std::string* limit = nullptr);

class FluidSolver : public Participant {
 public:
  /// Registers the fluid's fields (pressure, free_surface, ...) on `particles`, which hold this rank's
  /// particles as `distribution` places them. All ranks construct it and call every member together. io/ builds `setup` from a case (fluid_setup). Throws
  /// std::invalid_argument when the setup does not fit the particles (e.g. two fluid materials).
  FluidSolver(const FluidSetup& setup, ParticleSet& particles, Distribution& distribution,
              const FluidOptions& options = {});
  ~FluidSolver() override;
  FluidSolver(const FluidSolver&) = delete;
  FluidSolver& operator=(const FluidSolver&) = delete;

  /// Largest admissible dt now (fluid_stable_dt for the fluid's largest speed and the gravity); `limit` receives
  /// the name of the limit that sets it.
  Real stable_dt(std::string* limit) const;
  Real stable_dt() const override { return stable_dt(nullptr); }
  /// One semi-implicit step (seed 004 eq. 16-24) from time t to t + dt.
  FluidStepReport advance(Real t, Real dt);

  /// Bytes held by the fluid's work arrays, neighbour list, matrix and preconditioner on this rank.
  std::size_t memory_bytes() const;

  /// Run checkpoints: what the fluid carries from step to step besides the particle arrays (the step count
  /// that times the cell reordering, the pressure solver's state). Everything else is rebuilt at every
  /// step or derived from the initial scene (the walls' reference positions), which a restarted run
  /// rebuilds before it loads the state. load_state returns false when the pressure solver's kept state
  /// cannot be restored (PressureSolver::load_state).
  void save_state(BinaryWriter& out) const override;
  bool load_state(BinaryReader& in) override;

  /// An iteration checkpoint holds the step count (the first step is the start from rest). The pressure
  /// solver's state is left as it is: it changes the iterations of a solve, not its answer beyond the tolerance.
  void store_iteration_checkpoint() override;
  void reload_iteration_checkpoint() override;

  /// The largest density error (RMS over the rows of r dt^2 / rho, as a fraction of n0) that the coming
  /// pressure solves may leave, below fluid.density_tolerance when that is tighter; +infinity: none. A
  /// coupling that iterates a step sets it, so that the fluid's answer is exact to well below the coupling's
  /// tolerance. With fluid.density_tolerance 0 (relative tolerance only) it changes nothing.
  void set_density_tolerance_cap(Real cap);

  /// A coupled solid's view: where the solid is for the next step (positions and velocities), and until the next
  /// call which solid particles are boundary particles and which dummies, and their density offsets. Without a
  /// call the solid takes part as FluidOptions::solid_as_boundary says. Needs FluidOptions::coupled_solid. The
  /// fluid keeps the values with its particles and refreshes their ghosts itself. Throws std::logic_error when the
  /// ids are not this rank's owned solid particles in local order, or without FluidOptions::coupled_solid.
  void set_solid_boundary(const SolidBoundaryData& data);

  /// Diagnostics and tests: this rank's rows of the last pressure system, the particle (local index at
  /// the time of the solve) of each row, and the lattice constants used (density/gradient, Laplacian).
  const LocalRows& last_system() const;
  const std::vector<LocalIndex>& row_particles() const;
  const LatticeConstants& lattice_gradient() const;
  const LatticeConstants& lattice_laplacian() const;
  /// The cell side [m] that the neighbour lists are searched with and the particles are kept in cell order by.
  Real cell_size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mpsfsi
