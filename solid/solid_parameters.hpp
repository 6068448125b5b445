// The parameters of the solid (docs/case-format.md `solid_materials`, `solid`, `solid_loads` and
// `sources`), owned by the solid: the case parser (io/case_file.cpp) fills and checks them, the solid
// solver reads them. Each option enum has its one name table here (the parser's choices and the log's names).
#pragma once

#include "core/enum_names.hpp"
#include "core/geometry.hpp"
#include "core/tank_motion.hpp"
#include "core/wall_motion.hpp"
#include "core/types.hpp"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mpsfsi {



/// The particle fields of the solid that the coupling reads or writes: declared here once.
namespace solid_fields {
inline constexpr const char* surface = "surface";    ///< 1 on surface particles (eq. 48), kept current by the solid
inline constexpr const char* load = "solid_load";    ///< external force per particle read by the solid [N/m]
}  // namespace solid_fields

struct SolidMaterial {
  std::string name;
  Real rho = 1000;    ///< density [kg/m3]
  Real E = 1e6;       ///< Young's modulus [Pa]
  Real nu = 0.3;      ///< Poisson's ratio
  std::optional<Real> fracture_strain;  ///< eps_max of seed 004 eq. 47; none: unbreakable
  /// Optional P- and S-wave speeds [m/s] (seed 000 §4): when given they define the Lame constants of
  /// the 2D model directly (mu = rho vs^2, lambda = rho (vp^2 - 2 vs^2)); E and nu then hold the
  /// equivalent (3D / plane-strain) values.
  std::optional<Real> vp, vs;
};

/// n0 of eq. 30 and 36-38: mean ((n_i^0 + n0)/2: surface rows get the stiffness of interior rows, see
/// docs/validation.md) | particle (each particle's initial n_i^0, seed 004) | lattice (one n0, seed 000).
/// Pair terms use the mean of 1/n_i and 1/n_j so forces stay equal and opposite.
enum class SolidNormalisation { mean, particle, lattice };
inline const NameTable<SolidNormalisation>& solid_normalisation_names() {
  static const NameTable<SolidNormalisation> t = {{"particle", SolidNormalisation::particle},
                                                  {"lattice", SolidNormalisation::lattice},
                                                  {"mean", SolidNormalisation::mean}};
  return t;
}
inline std::string_view to_string(const SolidNormalisation v) { return name_of(solid_normalisation_names(), v); }

/// Volumetric strain tr(eps)_i of eq. 30 (the pressure term, eq. 33, 38): n0 (eq. 30 with the n0 of
/// SolidParameters::normalisation) | corrected (bond weights w0/|r0| e^T B_i e with B_i from the particle's
/// own bonds, so that the trace of a linear displacement field is exact where the neighbourhood is truncated,
/// e.g. at a free surface; the same as eq. 30 in the interior). See docs/validation.md (Lamb's problem).
enum class VolumetricStrain { n0, corrected };
inline const NameTable<VolumetricStrain>& volumetric_strain_names() {
  static const NameTable<VolumetricStrain> t = {{"n0", VolumetricStrain::n0}, {"corrected", VolumetricStrain::corrected}};
  return t;
}
inline std::string_view to_string(const VolumetricStrain v) { return name_of(volumetric_strain_names(), v); }

/// The numerical parameters of the solid (case file key `solid`).
struct SolidParameters {
  Real re = 2.1;                ///< effective radius of the bonds, in units of dp
  std::optional<Real> dt;       ///< solid time step for solid-only runs [s]
  bool plane_stress = false;    ///< 2D Lame constants: false = plane strain (eq. 4 as written), true = plane stress
  /// Plane stress with the bending modulus of a plate much wider than thick, E / (1 - nu^2) in place of E
  /// (cylindrical bending, D = E t^3 / 12 (1 - nu^2)): plane strain's bending stiffness without its in-plane
  /// near-incompressibility, which locks the MPS solid at nu -> 0.5. Needs plane_stress and E, nu materials.
  bool wide_plate = false;

  /// The Young's modulus the 2D model uses for material m: E, or E / (1 - nu^2) with wide_plate.
  Real modulus(const SolidMaterial& m) const { return wide_plate ? m.E / (1 - m.nu * m.nu) : m.E; }
  Real dt_factor = 0.2;         ///< stable dt = dt_factor * dp / c_p
  Real contact_stiffness = 1.0; ///< contact spring / nearest-neighbour bond stiffness (seed 004 §4.4)
  SolidNormalisation normalisation = SolidNormalisation::mean;
  VolumetricStrain volumetric_strain = VolumetricStrain::n0;
};

/// A time-dependent pressure on a region of a solid body's particles (seed 000 §4, Hopkinson bar):
/// p(t) = peak exp(-((t - time) / width)^2); each particle in the region gets the force
/// p(t) dp^(d-1) along `direction`.
struct SolidLoadSpec {
  std::string name;
  std::string body;             ///< a solid body
  Rect region;                  ///< particles of the body inside (initial positions) are loaded
  Vec direction = Vec::UnitX();  ///< unit direction of the force
  Real peak = 0;                ///< peak pressure [Pa]
  Real time = 0;                ///< time of the peak [s]
  Real width = 1;               ///< 1/e half-width of the Gaussian [s]
};

/// Time function s(t) of a source (same definitions as scripts/lamb/lamb2d.py; tau = t - delay,
/// sigma = 1 / (2 pi f0)): gaussian_derivative -sqrt(e) (tau/sigma) exp(-tau^2 / (2 sigma^2)) (unit peak,
/// positive lobe first, amplitude spectrum peaks at f0); ricker (1 - 2 pi^2 f0^2 tau^2) exp(-pi^2 f0^2 tau^2);
/// gaussian exp(-tau^2 / (2 sigma^2)); table: (time, value) linearly interpolated, zero outside.
enum class WaveletType { gaussian_derivative, ricker, gaussian, table };

struct WaveletSpec {
  WaveletType type = WaveletType::gaussian_derivative;
  Real frequency = 0;             ///< central frequency f0 [Hz] (not for table)
  Real delay = 0;                 ///< t0 [s] (not for table); the parser's default is 1.5 / f0
  std::vector<Real> time, value;  ///< table: samples, strictly increasing times [s]
  std::string file;               ///< table: the CSV it was read from (for messages)
};

/// A seismic source in a solid body (seed 000 §3): an explosive line source (isotropic line moment
/// M(t) delta_ij, M = amplitude s(t) [N m/m]; body force -M grad(delta), discretised by
/// core/point_stencil.hpp moment_stencil) or a line force F(t) = amplitude s(t) [N/m] along
/// `direction` (spread by interpolation_stencil), over the body's particles within `radius`.
enum class SourceType { explosion, force };

struct SourceSpec {
  std::string name;
  std::string body;               ///< a solid body
  SourceType type = SourceType::explosion;
  Vec position = Vec::Zero();     ///< source point [m] (in the reference configuration)
  Vec direction = Vec::UnitY();   ///< force only: unit direction
  Real amplitude = 1;             ///< M0 [N m/m] (explosion) or F0 [N/m] (force)
  Real radius = 0;                ///< stencil radius [m]; the parser's default is 2 dp
  WaveletSpec wavelet;
};

/// The initial angular velocity of a body (bodies[].angular_velocity of the case), by body name.
struct BodySpin {
  std::string body;
  Angular angular_velocity = angular_zero();  ///< [rad/s] (a vector in 3D)
};

/// Everything the solid solver (solid/solid_solver.hpp) is set up from; io/ builds it from a case
/// (solid_setup in io/case.hpp).
struct SolidSetup {
  std::string origin;                   ///< names the input in messages (the case file)
  Real dp = 0;                          ///< particle spacing l0 [m]
  Vec gravity = Vec::Zero();
  Real gravity_ramp = 0;                ///< [s]: gravity times ramp_factor(t, gravity_ramp) (core/ramp.hpp)
  std::vector<SolidMaterial> materials; ///< indexed by ParticleSet::material of the solid particles
  SolidParameters parameters;
  TankMotionSpec tank_motion;           ///< moves the clamped particles
  /// The bodies whose clamped particles move with a wall's own motion (a plate clamped into a paddle), by name.
  std::vector<std::pair<std::string, WallMotionSpec>> clamp_motions;
  std::vector<BodySpin> spins;          ///< every body of the case, in order
  std::vector<SolidLoadSpec> loads;
  std::vector<SourceSpec> sources;
};

}  // namespace mpsfsi
