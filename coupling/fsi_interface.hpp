// Partitioned fluid-solid coupling of seed 004 §4.5-4.6 (eq. 49-51), shaped as a participant loop in the
// manner of preCICE. Fluid and solid share one ParticleSet; per fluid step the driver calls
//   prepare_fluid_boundary()   (a) solid surface particles (field "surface", eq. 48) enter the fluid step as
//                                  boundary particles (PPE rows) where the coupling scheme says the fluid
//                                  sees them (the solid's position, a mid-step prediction or an iterate);
//                                  interior solid particles are dummies. It returns that view as typed data
//                                  by global id (SolidBoundaryData), which the driver gives the fluid
//                                  (FluidSolver::set_solid_boundary); the particle set is not written.
//   <fluid advance>
//   compute_load()             (b) reads the pressures and computes the interface force of eq. 50 on each
//                                  wetted solid surface particle (interface_load(): typed data by global id)
//   advance_solid(...)         (c) advances the solid N sub-steps of dt / N with that load held, and
//                                  integrates the work the load does; (d) the solid's new position and
//                                  velocity are in the shared set, which is what the fluid sees next step.
// fluid/ and solid/ know nothing of each other; only this folder sees both.
//
// Interface force (eq. 50), per wetted solid surface particle i, per unit thickness:
//   F_i = -V * 2d / n_norm * sum_{j*} (P_i + P_j)/2 * (r_j - r_i) / |r_j - r_i|^2 * w(|r_ij|),   V = dp^d
// over fluid and solid-surface neighbours j* within re (the fluid's re_gradient); dummies, walls and
// interior solid particles are left out. The minus sign makes it -grad P: the fluid's pressure pushes the
// solid away from the fluid. A particle counts as wetted when it has a fluid neighbour and
// n~_i = (n_i)_total - (n_i^0)_solid > 0 (eq. 51; (n_i^0)_solid from the initial configuration, solid
// particles only). n_norm is n~_i with Normalisation::seed (eq. 50-51 as written) or the lattice n0 with
// Normalisation::lattice (default): with n~_i a flat wetted face under a uniform pressure P gets
// 3.0 P dp per particle instead of P dp (n0 / n~ = 6.54 / 2.12 at re = 2.1 dp); see docs/validation.md.
//
// Stability of the explicit (weak) coupling: the fluid's pressure answers the solid's displacement like a
// stiff spring one step late, which pumps energy into the solid. Two generic measures reduce it: the fluid
// sees the solid at mid-step (midstep_predictor) and the solid's own deformation does not enter the fluid's
// density source (freeze_solid_density). What is left goes into the solid's particle-scale modes: the run
// loop gives the solid's bonds a Kelvin-Voigt damping (CouplingParameters::solid_damping,
// SolidSolver::set_damping) that damps those modes and leaves the first bending mode alone. The measured
// interface work with and without each measure is in docs/validation.md (## Coupling). Clamped particles get no
// load and are no j* in eq. 50 (exclude_clamped). load_relaxation (default 1, off) under-relaxes the load.
#pragma once

#include "core/neighbours.hpp"
#include "core/particles.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "solid/solid_solver.hpp"

#include <Eigen/Core>

#include <fstream>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace mpsfsi {

class Distribution;
class BinaryWriter;
class BinaryReader;

struct FsiOptions {
  enum class Normalisation { lattice, seed };
  Normalisation normalisation = Normalisation::lattice;
  std::string flag_field = solid_fields::surface;  ///< solid surface flag (eq. 48), kept current by the solid
  std::string pressure_field = fluid_fields::pressure;  ///< the fluid's pressure (fluid and boundary particles) [Pa]
  /// The fluid's PPE sees the solid at its initial number density: (a) gives the fluid (n_i^0)_solid of each solid
  /// particle (SolidBoundaryData::reference_density); the fluid adds (n_i^0)_solid - (n_i)_solid, taken where it
  /// sees the solid, to n* of its boundary particles.
  bool freeze_solid_density = true;
  /// The fluid sees the solid at the middle of the coming step: x^n + u dt/2 with velocity u, u the
  /// solid's mean velocity over the previous step (its displacement / dt, free of the sub-steps'
  /// oscillations). The solid's own state is not touched: the view is typed data the fluid reads.
  bool midstep_predictor = true;
  /// Clamped solid particles (e.g. the foot of a plate embedded in the floor) are wall-like: they get no
  /// load and are left out of the j* of eq. 50 (their PPE pressure is spurious where their lattice and the
  /// floor's overlap). They stay PPE rows of the fluid like walls: as dummies the fluid leaks through the
  /// floor at the plate's foot (docs/validation.md, ## Coupling).
  bool exclude_clamped = true;
  /// Under-relaxation of the load in time: F_applied = a F_eq.50 + (1 - a) F_applied(previous step).
  Real load_relaxation = 1.0;
};

/// Interface quantities of one solid body.
struct InterfaceBody {
  std::string name;
  std::uint16_t body = 0;       ///< index into ParticleSet::bodies
  Vec force = Vec::Zero();      ///< total fluid force at the last compute_load [N per unit thickness]
  Real work_step = 0;           ///< work of the interface load over the last advance_solid [J per unit thickness]
  Real work_total = 0;          ///< cumulative work of the interface load [J per unit thickness]
  std::size_t n_wetted = 0;     ///< wetted surface particles at the last compute_load
};

/// Sub-steps per fluid step. requested > 0: that N, raised to the automatic value (`raised`) when
/// dt_fluid / N would exceed dt_solid; requested <= 0 (auto): the smallest N with dt_fluid / N <= dt_solid.
struct SubcycleChoice {
  int n = 1;
  bool raised = false;
};
SubcycleChoice choose_subcycles(int requested, Real dt_fluid, Real dt_solid);

class FsiInterface {
 public:
  /// The interface of `particles` (fluid and solid particles, plus walls) for the case `spec`. With a
  /// distribution, `particles` holds this rank's owned particles and ghosts, every call below is a collective
  /// over its ranks, and bodies() holds the totals over all ranks.
  FsiInterface(const CaseSpec& spec, ParticleSet& particles, const FsiOptions& options = {},
               Distribution* distribution = nullptr);

  /// The fluid's options for a coupled run: the fluid takes its view of the solid from prepare_fluid_boundary
  /// (FluidSolver::set_solid_boundary) instead of seeing the solid as it is.
  static FluidOptions fluid_options(FluidOptions base = {});
  const FsiOptions& options() const { return opt_; }

  /// (n_i^0)_solid of every solid particle from the current (initial) configuration, and the bodies.
  void initialize();
  /// (a) The fluid's view of the solid for its next step, this rank's owned solid particles by global id: the
  /// solid's surface flag, where the fluid sees each particle and with which velocity, and with
  /// freeze_solid_density the reference densities (n_i^0)_solid. With midstep_predictor the fluid sees the solid
  /// at x + u dt / 2 with velocity u, u its mean velocity over the last step; else where it is.
  SolidBoundaryData prepare_fluid_boundary(Real dt = 0);
  /// (a) for an iteration of an implicit coupling: the fluid sees the solid where it is at the step's end,
  /// x + d, with velocity d / dt, d the solid's displacement over the coming step (this rank's owned solid
  /// particles, dim values each, in the order of solid_ids()): the pressure solve constrains the fluid's density
  /// at the step's end, so the boundary it sees must be there too.
  SolidBoundaryData prepare_fluid_boundary(Real dt, const Eigen::VectorXd& displacement);
  /// The global ids of this rank's owned solid particles, in local order: the entries of the interface data.
  std::vector<GlobalId> solid_ids() const;
  /// The displacement the solid would make over a step of dt at its mean velocity of the last step (zero
  /// before the first step), in the order of solid_ids(): the first iterate of an implicit coupling.
  Eigen::VectorXd predicted_displacement(Real dt) const;
  /// After advance_solid: each solid particle's displacement over it, in the order of `ids` (this rank's
  /// solid_ids() when the step began; particles that moved to another rank meanwhile are fetched from it).
  /// A collective.
  Eigen::VectorXd step_displacement(const std::vector<GlobalId>& ids) const;
  /// (b) Eq. 50 from the current pressures: the interface force of each solid particle (interface_load());
  /// totals per body.
  void compute_load();
  /// The interface forces of the last compute_load, by global id: this rank's owned solid particles in local order
  /// (zero where not wetted) [N per unit thickness in 2D].
  SolidLoadData interface_load() const;
  /// (c) + (d) gives the solid the load (SolidSolver::set_interface_load) and runs n_sub solid sub-steps of
  /// dt / n_sub from t with it held; the work F . v dt of every sub-step is summed per body.
  void advance_solid(SolidSolver& solid, Real t, Real dt, int n_sub);

  const std::vector<InterfaceBody>& bodies() const { return bodies_; }
  /// Lattice number density n0 used with Normalisation::lattice.
  Real n0() const { return n0_; }

  /// interface.csv: time, body, fx, fy, work_step, work_total, wetted (one row per solid body).
  /// append: continue an existing file (a restarted run) instead of starting it with its header.
  void open_csv(const std::string& path, bool append = false);
  void write_csv(Real t);

  /// Checkpoints: the per-body totals. What the interface knows of a particle is in particle fields that
  /// travel with it and that the checkpoint holds (internal, "_fsi_*": the initial solid number density, the
  /// previous step's load for load_relaxation, the solid's mean velocity for the mid-step predictor).
  void save_state(BinaryWriter& out) const;
  void load_state(BinaryReader& in);

 private:
  /// Owners and ghosts current (migration when due, else the solid ghosts' positions and velocities refreshed).
  void sync();
  /// The fluid's view of the k-th owned solid particle i: the offset of its position and its velocity.
  using SolidView = std::function<std::pair<Vec, Vec>(std::size_t k, std::size_t i)>;
  /// The fluid's view of the solid (nullptr: the solid as it is) with its flags and reference densities.
  SolidBoundaryData view_solid(const SolidView* view);
  /// Sums the per-body force and wetted count (after compute_load) or work (after advance_solid) over the ranks.
  void reduce_bodies(bool force);

  ParticleSet& p_;
  FsiOptions opt_;
  Distribution* dist_ = nullptr;
  Real dp_ = 0, re_ = 0, n0_ = 0;
  bool initialized_ = false;
  bool has_mean_v_ = false;              ///< the solid's mean velocity (field) is set: the predictor applies
  std::vector<InterfaceBody> bodies_;
  std::vector<int> body_slot_;           ///< ParticleSet body -> index into bodies_, or -1
  CellGrid grid_;
  std::vector<LocalIndex> rows_;  ///< compute_load: the loaded solid surface particles
  NeighbourList rows_nl_;         ///< compute_load: their neighbours among all particles
  std::ofstream csv_;
  std::string csv_path_;
};

}  // namespace mpsfsi
