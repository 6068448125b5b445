// The in-memory form of a case file (cases/*.yaml), checked and in SI units. The parser
// (io/case_file.cpp) fills it; scene building, the fluid, the solid and the coupling read it.
// The schema is documented in docs/case-format.md.
#pragma once

#include "core/types.hpp"

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpsfsi {

// io/, fluid/, solid/, coupling/ and app/ are 2D only (e.g. Vec(1, 0) below would be a size request for
// a 3-vector); only core/ is dimension-generic. CMake builds them only for MPSFSI_DIM=2.
static_assert(dim == 2, "mpsfsi: io, fluid, solid, coupling and app are 2D only; MPSFSI_DIM=3 builds core/ alone");

/// An error in user input (case file or command line). Exit code 2.
class CaseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Axis-aligned rectangle [lo, hi].
struct Rect {
  Vec lo = Vec::Zero();
  Vec hi = Vec::Zero();
  Vec size() const { return hi - lo; }
  bool contains(const Vec& x) const { return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all(); }
};

/// True when the interiors of a and b intersect (touching edges do not overlap).
inline bool overlaps(const Rect& a, const Rect& b) {
  return (a.lo.array() < b.hi.array()).all() && (b.lo.array() < a.hi.array()).all();
}

struct FluidMaterial {
  std::string name;
  Real rho = 1000;    ///< density [kg/m3]
  Real nu = 1e-6;     ///< kinematic viscosity [m2/s]
  Real c = 20;        ///< sound speed of the weak-compressibility term alpha = 1/(rho c^2) [m/s]
  Real kappa = 0.2;   ///< relaxation of the PPE source term (seed 004 eq. 23)
};

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

enum class BodyKind { fluid, solid };

struct BodySpec {
  std::string name;
  BodyKind kind = BodyKind::fluid;
  std::string material;             ///< name of a fluid material (fluid) or solid material (solid)
  Rect rect;                        ///< region filled with particles
  std::optional<Rect> clamp;        ///< solid only: particles inside are clamped
  Vec velocity = Vec::Zero();       ///< initial velocity [m/s]
  Real angular_velocity = 0;        ///< initial angular velocity about the body's centroid [rad/s]
};

/// The part of a body that is not clamped: a clamp that spans the body's whole width (height) cuts its
/// height (width); otherwise the whole body counts. Only this part must stay clear of the walls, so a
/// clamped end may be embedded in a wall (the wall particles there give way, see io/scene.cpp).
Rect free_part(const BodySpec& b);

enum class WallType { box, block };

struct WallSpec {
  std::string name;
  WallType type = WallType::box;
  Rect rect;              ///< box: the inner (wetted) rectangle; block: the solid block itself
  bool open_top = true;   ///< box only: no lid
};

enum class TankMotionType { none, sine_roll, table };

struct TankMotionSpec {
  TankMotionType type = TankMotionType::none;
  Vec pivot = Vec::Zero();      ///< rotation centre [m]
  Real amplitude = 0;           ///< sine_roll: amplitude [rad] (case file in degrees)
  Real period = 1;              ///< sine_roll: period [s]
  std::string file;             ///< table: CSV of time [s], angle [deg], resolved relative to the case file
  std::vector<Real> time;       ///< table: the rows read from `file` when the case was parsed, times [s] ...
  std::vector<Real> angle;      ///< ... and angles [rad]
};

enum class ProbeType { pressure, surge_front, column_height, displacement };

/// Frame of a displacement probe: global, or the tank's rotating frame (R(-theta)(x - pivot) - (x0 - pivot)).
enum class ProbeFrame { global, tank };

struct ProbeSpec {
  std::string name;
  ProbeType type = ProbeType::pressure;
  Vec position = Vec::Zero();   ///< pressure: probe point; displacement: initial point on the body
  std::string body;             ///< displacement: which body (optional for others)
  ProbeFrame frame = ProbeFrame::global;  ///< displacement only
};

struct TimeSpec {
  Real end = 1;                 ///< end time [s]
  std::optional<Real> dt;       ///< fixed fluid time step [s], or
  std::optional<Real> cfl;      ///< Courant number C of seed 004 eq. 52 (adaptive dt)
  Real dt_max = 1e-3;           ///< upper bound of an adaptive dt [s]
};

struct CouplingSpec {
  int subcycles = 1;            ///< solid sub-steps per fluid step; 0 means "auto"
  Real solid_damping = 0.5;     ///< Kelvin-Voigt bond damping of the solid, eta = beta dp / c_p (SolidSolver::set_damping)
  Real load_relaxation = 1.0;   ///< FsiOptions::load_relaxation
};

/// Quasi-2D friction of the two lateral walls (front and back) of a narrow tank, which a 2D model does
/// not have: the fluid velocity relative to the tank decays at the rate k (dv/dt = -k (v - v_wall)).
/// stokes: oscillating laminar boundary layers (Stokes' second problem) on both walls, the part of the
/// wall shear in phase with the velocity, k = sqrt(2 nu omega) / gap, omega = 2 pi frequency.
/// poiseuille: steady laminar flow between the walls (Hele-Shaw), k = 12 nu / gap^2.
struct LateralWallFriction {
  Real gap = 0;                 ///< distance between the lateral walls [m]; 0: off
  std::string model = "stokes"; ///< stokes | poiseuille
  Real frequency = 0;           ///< stokes: oscillation frequency [Hz] (default: 1 / period of a sine_roll)
};

struct FluidNumerics {
  Real re_gradient = 2.1;       ///< effective radius for density/gradient, in units of dp
  Real re_laplacian = 4.0;      ///< effective radius for the Laplacian, in units of dp
  Real beta1 = 0.97;            ///< free surface: n_i < beta1 n0 ...
  Real beta2 = 0.85;            ///< ... and N_i < beta2 N0
  std::string gradient = "min_pressure";  ///< min_pressure | corrected
  std::string solver = "cg";              ///< cg | gmres
  /// ssor | sgs | jacobi | chebyshev | muelu | ilu | none. Default ssor (Eisenstat SSOR, omega 1.4): the fastest
  /// measured on the dam break, setup + solve 25.5 ms per step against 37.4 (jacobi) and 110 (muelu, rebuilt
  /// every step), docs/performance.md "Pressure solve".
  std::string preconditioner = "ssor";
  Real tolerance = 1e-8;                  ///< relative residual of the pressure solve
  /// Absolute stop of the pressure solve tied to the incompressibility error: the solve also stops when
  /// the RMS over the rows of r_i dt^2 / rho (the density error, as a fraction of n0, that the residual r
  /// leaves after the correction) is below this. 0: off (relative tolerance only). Its effect on the
  /// iterations and the results: docs/performance.md (## Fluid).
  Real density_tolerance = 1e-6;
  int max_iterations = 500;
  int preconditioner_rebuild_every = 1;   ///< full preconditioner setup every N steps, kept in between
  LateralWallFriction lateral_walls;      ///< quasi-2D lateral-wall friction (off by default)
  /// The largest share of a fluid body's particles that may leave the domain before the run stops (exit 3).
  Real max_loss = 0.05;
};

struct SolidNumerics {
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
  /// n0 of eq. 30 and 36-38: "mean" ((n_i^0 + n0)/2: surface rows get the stiffness of interior
  /// rows, see docs/validation.md) | "particle" (each particle's initial n_i^0, seed 004) | "lattice"
  /// (one n0, seed 000). Pair terms use the mean of 1/n_i and 1/n_j so forces stay equal and opposite.
  std::string normalisation = "mean";
  /// Volumetric strain tr(eps)_i of eq. 30 (the pressure term, eq. 33, 38): "n0" (eq. 30 with the n0 of
  /// `normalisation`) | "corrected" (bond weights w0/|r0| e^T B_i e with B_i from the particle's own bonds,
  /// so that the trace of a linear displacement field is exact where the neighbourhood is truncated, e.g.
  /// at a free surface; the same as eq. 30 in the interior). See docs/validation.md (Lamb's problem).
  std::string volumetric_strain = "n0";
};

/// A time-dependent pressure on a region of a solid body's particles (seed 000 §4, Hopkinson bar):
/// p(t) = peak exp(-((t - time) / width)^2); each particle in the region gets the force
/// p(t) dp^(d-1) along `direction`.
struct SolidLoadSpec {
  std::string name;
  std::string body;             ///< a solid body
  Rect region;                  ///< particles of the body inside (initial positions) are loaded
  Vec direction = Vec(1, 0);    ///< unit direction of the force
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
  Vec direction = Vec(0, 1);      ///< force only: unit direction
  Real amplitude = 1;             ///< M0 [N m/m] (explosion) or F0 [N/m] (force)
  Real radius = 0;                ///< stencil radius [m]; the parser's default is 2 dp
  WaveletSpec wavelet;
};

/// A receiver: the displacement of the material point of a solid body that starts at `position`,
/// interpolated from the body's particles within ReceiversSpec::radius (interpolation_stencil).
struct ReceiverSpec {
  std::string name;
  std::string body;
  Vec position = Vec::Zero();
};

struct ReceiversSpec {
  std::optional<Real> interval;   ///< simulated time between rows of receivers.csv [s]; none: every step
  Real radius = 0;                ///< stencil radius [m]; the parser's default is 2 dp
  std::vector<ReceiverSpec> points;
};

struct OutputSpec {
  Real interval = 0.01;         ///< simulated time between frames [s]
  std::vector<std::string> fields;  ///< empty: every field
};

struct CaseSpec {
  std::string file;             ///< path of the case file as given
  std::string name;
  std::string description;
  std::string source;           ///< where the geometry and data come from
  Rect domain;                  ///< particles leaving it are removed and counted
  Real dp = 0;                  ///< particle spacing l0 [m]
  TimeSpec time;
  Vec gravity = Vec::Zero();
  std::vector<FluidMaterial> fluid_materials;
  std::vector<SolidMaterial> solid_materials;
  std::vector<BodySpec> bodies;
  std::vector<WallSpec> walls;
  TankMotionSpec tank_motion;
  CouplingSpec coupling;
  FluidNumerics fluid;
  SolidNumerics solid;
  std::vector<SolidLoadSpec> solid_loads;
  std::vector<SourceSpec> sources;
  std::vector<ProbeSpec> probes;
  ReceiversSpec receivers;
  OutputSpec output;
  std::string resolved_yaml;    ///< the case after every override, as YAML (saved with the results)

  /// Index of a fluid/solid material by name, or -1.
  int fluid_material_index(const std::string& name) const;
  int solid_material_index(const std::string& name) const;
};

/// Parse and check a case file; `overrides` are "dotted.key=value" strings (--set), applied before
/// checking. Throws CaseError with file, line, key and the expected form on any bad input.
CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides = {});
/// Same, from YAML text (`name` stands for the file in messages; relative paths in the case, e.g. a
/// tank-motion table, are relative to base_dir).
CaseSpec parse_case(const std::string& yaml_text, const std::string& name,
                    const std::vector<std::string>& overrides = {}, const std::string& base_dir = ".");

/// Keys of a case that a restart may change freely (with --set or --end-time): time.end, output (interval,
/// fields), description and source.
const std::vector<std::string>& restart_free_keys();
/// Numerical controls a restart may change, e.g. to continue with a smaller time step after a run went
/// unstable: time.cfl, time.dt, time.dt_max, coupling.subcycles, fluid.solver, fluid.preconditioner,
/// fluid.tolerance, fluid.max_iterations, fluid.preconditioner_rebuild_every, fluid.max_loss, solid.dt,
/// solid.dt_factor. The continuation then is not the original run's. Every other key must equal the
/// checkpoint's case.
const std::vector<std::string>& restart_tunable_keys();
/// True when `key` (dotted, e.g. "time.cfl" or "bodies[0].name") is one of `roots` or lies below one.
bool key_under(const std::string& key, const std::vector<std::string>& roots);

/// One leaf of a case whose value differs between two cases.
struct CaseDifference {
  std::string key;  ///< dotted path, e.g. "bodies[1].rectangle.max[0]"
  std::string a, b; ///< the values as written; "(absent)" for a missing key
  std::string text() const { return key + ": " + a + " vs " + b; }
};
/// The differences between two resolved cases (CaseSpec::resolved_yaml) outside restart_free_keys(), by
/// key (numbers compare by value). Empty: the same case for a restart.
std::vector<CaseDifference> case_differences(const std::string& yaml_a, const std::string& yaml_b);

}  // namespace mpsfsi
