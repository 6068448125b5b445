// The explicit elastic solid of seed 004 §4.2/§4.4 and seed 000 §2 (rotation-aware MPS with brittle
// fracture and contact), as a participant of the run loop: the driver asks for a stable dt and
// advances it one sub-step at a time. External loads (e.g. from the fluid) arrive in the vector
// field "solid_load" (force per particle [N per unit thickness]); the case's pressure pulses
// (solid_loads) and seismic sources (sources, solid/sources.hpp) are applied by the solver itself.
//
// Equations: relative displacement with the pair's mean rotation removed (seed 004 eq. 25-29, seed 000
// eq. 7-12), volumetric strain eq. 30 (optionally with weights that are exact at free surfaces,
// solid.volumetric_strain), stresses eq. 31-33, accelerations eq. 36-38, shear torque
// eq. 41-44, symplectic Euler eq. 39-40 and 45-46, brittle fracture eq. 47, surface particles eq. 48,
// contact of unbonded surface particles §4.4. Lame constants from E and nu by eq. 4 (plane strain) or
// the plane-stress reduction, or from the wave speeds vp, vs (seed 000 §4).
// Optional Kelvin-Voigt bond damping (set_damping; off unless called, the coupled run loop calls it with
// coupling.solid_damping): each bond adds k eta (e . (v_j - v_i)) e to its elastic force, with k the
// bond's stiffness and e its direction, so the damping ratio of a mode is eta omega / 2.
// Its parameters live in solid/solid_parameters.hpp (SolidSetup); it sees no case file.
#pragma once

#include "core/participant.hpp"
#include "core/particles.hpp"
#include "core/setup_error.hpp"
#include "solid/solid_parameters.hpp"

#include <memory>
#include <string>

namespace mpsfsi {

class BinaryWriter;
class BinaryReader;
class Distribution;

struct SolidStepReport {
  std::size_t n_broken = 0;    ///< bonds broken so far
  Real max_speed = 0;          ///< largest solid particle speed [m/s]
  std::size_t n_contacts = 0;  ///< unbonded surface pairs in contact in this step
};

/// Conserved quantities of the solid particles (per unit thickness), for tests and logs.
struct SolidDiagnostics {
  Vec momentum = Vec::Zero();   ///< sum m v [kg m/s]
  Angular angular_momentum = angular_zero();  ///< sum m (x cross v) + I omega, about the origin [kg m2/s] (a vector in 3D)
  Real kinetic = 0;             ///< sum m v^2 / 2 [J]
  Real rotational = 0;          ///< sum I omega^2 / 2 [J]
  Real strain = 0;              ///< bond energy + volumetric energy (the potential of eq. 36-38, 43) [J]
  Real contact = 0;             ///< energy stored in the contact springs [J]
  Real total() const { return kinetic + rotational + strain + contact; }
};

/// Lame constants of the 2D model of a solid material.
struct LameConstants {
  Real lambda = 0;
  Real mu = 0;
};

/// The material law of the 2D model, the one place it is computed: from vp, vs when given (seed 000 §4),
/// else eq. 4 (plane strain), reduced to plane stress with solid.plane_stress
/// (lambda* = 2 lambda mu / (lambda + 2 mu)), with E / (1 - nu^2) in place of E for solid.wide_plate.
LameConstants lame_constants(const SolidMaterial& m, const SolidParameters& numerics);
/// P-wave speed sqrt((lambda + 2 mu) / rho) of that law [m/s].
Real p_wave_speed(const SolidMaterial& m, const SolidParameters& numerics);
/// The distance within which a distributed solid needs the other ranks' particles: its bonds' range re with
/// room for their stretch (contact, within dp, is shorter) [m]; the halo is this plus the skin.
Real solid_interaction_radius(const SolidSetup& setup);

/// Interface forces of a coupling: typed interface data, by global id, of each of this rank's owned solid
/// particles (in the manner of a preCICE participant's read data): the external force on the particle [N per unit
/// thickness in 2D, N in 3D].
struct SolidLoadData {
  std::vector<GlobalId> ids;  ///< this rank's owned solid particles, in local order
  std::vector<Vec> force;     ///< one per id
};

class SolidSolver : public Participant {
 public:
  /// Builds the bonds (reference configuration) and registers the solid's fields on `particles`:
  /// rotation, angular_velocity, displacement, von_mises, solid_pressure, fragment, surface, solid_load.
  /// io/ builds `setup` from a case (solid_setup). Throws SetupError (a std::invalid_argument) when the
  /// setup does not fit the particles (e.g. a load on an unknown body, a load region without particles).
  /// This process holds the whole solid (no ghosts).
  SolidSolver(const SolidSetup& setup, ParticleSet& particles);
  /// Distributed: `particles` holds this rank's owned particles of `distribution` (the initial scene); the
  /// solver renews owners and ghosts itself at each step (migrate, build_ghosts, exchange_ghosts), and every
  /// query below is a collective over the distribution's ranks with the result for the whole solid. The halo
  /// must cover solid_interaction_radius(setup).
  SolidSolver(const SolidSetup& setup, ParticleSet& particles, Distribution& distribution);
  ~SolidSolver() override;
  SolidSolver(const SolidSolver&) = delete;
  SolidSolver& operator=(const SolidSolver&) = delete;

  /// Stable explicit time step of the solid: dt_factor * dp / c_p (c_p the largest P-wave speed,
  /// sqrt((lambda + 2 mu) / rho)); see docs/validation.md for the measured stability limit.
  Real stable_dt() const override;
  /// Kelvin-Voigt damping of the bonds: sigma = E (eps + eta d eps/dt) on the bonds' normal stretch, with
  /// the retardation time eta = beta dp / c_p. A mode of angular frequency omega gets the damping ratio
  /// eta omega / 2: beta = 0.5 gives ~0.5 at the particle scale (omega ~ 2 c_p / dp)
  /// and eta omega_1 / 2 ~ 1e-3 to a plate's first bending mode (docs/validation.md, ## Coupling).
  void set_damping(Real beta);
  Real damping_time() const;  ///< eta [s]
  /// One explicit step from t to t + dt (seed 004 eq. 25-48).
  SolidStepReport advance(Real t, Real dt);
  /// A coupling's interface forces, held (in the field solid_load, which travels with the particles) until the
  /// next call. Throws std::logic_error when the ids are not this rank's owned solid particles in local order.
  void set_interface_load(const SolidLoadData& data);
  /// Called by the driver just before an output frame: refresh derived fields (stress, displacement,
  /// fragments) and append to fragments.csv when an output directory is set.
  void prepare_output(Real t);
  /// Directory for fragments.csv (written at every prepare_output); empty: no file. append: continue an
  /// existing file (a restarted run) instead of starting it with its header.
  void set_output_directory(const std::string& dir, bool append = false);

  /// Checkpoints: the solid's state besides the particle arrays (the count of broken bonds). Everything the
  /// solid knows of a particle is in its particle arrays and fields (rotation, angular velocity, surface flag,
  /// and the internal fields "_solid_*": reference position, 1/n0, reference bond count, broken bonds), which
  /// the checkpoint holds by global id; after load_state the solver renews its bonds from them. load_state
  /// always returns true (the solid's steps continue bit for bit).
  void save_state(BinaryWriter& out) const override;
  bool load_state(BinaryReader& in) override;

  /// An iteration checkpoint holds the count of broken bonds; reloading it renews the bonds from the particle
  /// arrays (which the caller puts back) at the next use.
  void store_iteration_checkpoint() override;
  void reload_iteration_checkpoint() override;

  SolidDiagnostics diagnostics() const;
  /// Number of fragments (connected components of intact bonds) at the last prepare_output or
  /// min_distance_between_fragments (0 before).
  std::size_t n_fragments() const;
  /// Smallest distance between two solid particles of different fragments (fragments recomputed
  /// now), or +inf when none are closer than dp. O(N); for tests.
  Real min_distance_between_fragments() const;
  /// Intact bonds (each pair once).
  std::size_t n_bonds() const;
  /// Bytes held by the solver (bonds, per-particle arrays, scratch).
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mpsfsi
