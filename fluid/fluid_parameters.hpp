// The parameters of the fluid (docs/case-format.md `fluid_materials` and `fluid`), owned by the fluid:
// the case parser (io/case_file.cpp) fills and checks them, the fluid solver reads them. Each option
// enum has its one name table here (the parser's choices and the run log's names).
#pragma once

#include "core/enum_names.hpp"
#include "core/geometry.hpp"
#include "core/kernel.hpp"
#include "core/tank_motion.hpp"
#include "core/time_spec.hpp"
#include "core/wall_motion.hpp"
#include "core/types.hpp"

#include <string>
#include <vector>

namespace mpsfsi {



/// The particle fields the fluid writes that others read (the coupling, the probes, the output): declared
/// here once, used by name everywhere.
namespace fluid_fields {
inline constexpr const char* pressure = "pressure";          ///< [Pa], fluid and boundary particles
inline constexpr const char* free_surface = "free_surface";  ///< 1 on free-surface rows (p = 0)
}  // namespace fluid_fields

struct FluidMaterial {
  std::string name;
  Real rho = 1000;    ///< density [kg/m3]
  Real nu = 1e-6;     ///< kinematic viscosity [m2/s]
  Real c = 20;        ///< sound speed of the weak-compressibility term alpha = 1/(rho c^2) [m/s]
  Real kappa = 0.2;   ///< relaxation of the PPE source term (seed 004 eq. 23)
};

/// Model of the lateral-wall friction (LateralWallFriction).
enum class LateralWallModel { stokes, poiseuille };
inline const NameTable<LateralWallModel>& lateral_wall_model_names() {
  static const NameTable<LateralWallModel> t = {{"stokes", LateralWallModel::stokes},
                                                {"poiseuille", LateralWallModel::poiseuille}};
  return t;
}
inline std::string_view to_string(const LateralWallModel v) { return name_of(lateral_wall_model_names(), v); }

/// Pressure gradient of the correction step: the minimum-pressure gradient (eq. 9 with p_min) or the
/// corrected gradient (eq. 14-15).
enum class PressureGradient { min_pressure, corrected };
inline const NameTable<PressureGradient>& pressure_gradient_names() {
  static const NameTable<PressureGradient> t = {{"min_pressure", PressureGradient::min_pressure},
                                                {"corrected", PressureGradient::corrected}};
  return t;
}
inline std::string_view to_string(const PressureGradient v) { return name_of(pressure_gradient_names(), v); }

/// The pressure scheme. projection (the default): the projection of the number density (docs/validation.md,
/// ## Fluid): the force on particle k is -(1/rho)(d/C) sum_i p_i dn_i/dx_k (the constraint force of the
/// density, Wendland's kernel), and the PPE matrix is (1 - alpha) G + alpha s L_g, G = (d/C) N N^T / n0 with
/// N_ik = dn_i/dx_k built from that same operator and L_g its long-wave match (projection_stabilisation);
/// rows with a negative pressure become free-surface rows and compressed free-surface rows become rows again
/// (a complementarity active set); wall and solid rows hold their non-fluid density at its initial value, and
/// those with no fluid in reach hold p = 0; the first step starts the fluid from its equilibrium
/// (start_from_rest in fluid/fluid_solver.cpp). standard: the PPE with the Laplacian of eq. 12 and the gradient
/// of `gradient` for the force (no force-free state at rest).
enum class FluidScheme { standard, projection };
inline const NameTable<FluidScheme>& fluid_scheme_names() {
  static const NameTable<FluidScheme> t = {{"standard", FluidScheme::standard}, {"projection", FluidScheme::projection}};
  return t;
}
inline std::string_view to_string(const FluidScheme v) { return name_of(fluid_scheme_names(), v); }

/// The number-density kernel of the projection (core/kernel.hpp).
inline const NameTable<DensityKernel>& density_kernel_names() {
  static const NameTable<DensityKernel> t = {{"mps", DensityKernel::mps}, {"wendland", DensityKernel::wendland}};
  return t;
}
inline std::string_view to_string(const DensityKernel v) { return name_of(density_kernel_names(), v); }

/// Krylov solver of the pressure solve.
enum class KrylovSolver { cg, gmres };
inline const NameTable<KrylovSolver>& krylov_solver_names() {
  static const NameTable<KrylovSolver> t = {{"cg", KrylovSolver::cg}, {"gmres", KrylovSolver::gmres}};
  return t;
}
inline std::string_view to_string(const KrylovSolver v) { return name_of(krylov_solver_names(), v); }

/// Preconditioner of the pressure solve (fluid/pressure_solver.hpp PressureSolverSettings).
enum class Preconditioner { muelu, chebyshev, ilu, jacobi, sgs, ssor, none };
inline const NameTable<Preconditioner>& preconditioner_names() {
  static const NameTable<Preconditioner> t = {
      {"muelu", Preconditioner::muelu}, {"chebyshev", Preconditioner::chebyshev}, {"ilu", Preconditioner::ilu},
      {"jacobi", Preconditioner::jacobi}, {"sgs", Preconditioner::sgs},          {"ssor", Preconditioner::ssor},
      {"none", Preconditioner::none}};
  return t;
}
inline std::string_view to_string(const Preconditioner v) { return name_of(preconditioner_names(), v); }

/// Quasi-2D friction of the two lateral walls (front and back) of a narrow tank, which a 2D model does
/// not have: the fluid velocity relative to the tank decays at the rate k (dv/dt = -k (v - v_wall)).
/// stokes: oscillating laminar boundary layers (Stokes' second problem) on both walls, the part of the
/// wall shear in phase with the velocity, k = sqrt(2 nu omega) / gap, omega = 2 pi frequency.
/// poiseuille: steady laminar flow between the walls (Hele-Shaw), k = 12 nu / gap^2.
struct LateralWallFriction {
  Real gap = 0;                 ///< distance between the lateral walls [m]; 0: off
  LateralWallModel model = LateralWallModel::stokes;
  Real frequency = 0;           ///< stokes: oscillation frequency [Hz] (default: 1 / period of a sine_roll)
};

/// The numerical parameters of the fluid (case file key `fluid`).
struct FluidParameters {
  Real re_gradient = 2.1;       ///< effective radius for density/gradient, in units of dp
  Real re_laplacian = 4.0;      ///< effective radius for the Laplacian, in units of dp
  Real beta1 = 0.97;            ///< free surface: n_i < beta1 n0 ...
  Real beta2 = 0.85;            ///< ... and N_i < beta2 N0
  PressureGradient gradient = PressureGradient::min_pressure;
  FluidScheme scheme = FluidScheme::projection;
  /// projection: the most solves of one step while the active set changes.
  int max_active_set_solves = 6;
  /// projection: the share alpha of the pressure stabilisation, the PPE matrix (1 - alpha) G + alpha s L_g
  /// (L_g the Laplacian of eq. 12 at re_gradient, s its long-wave match to G). 0: the exact projection; 1 (the
  /// default): the scaled Laplacian alone, whose G is then built in the first step only (start_from_rest).
  Real projection_stabilisation = 1.0;
  /// projection: the kernel of the number density that the projection constrains, and its radius in dp.
  DensityKernel projection_kernel = DensityKernel::wendland;
  Real projection_radius = 2.0;
  KrylovSolver solver = KrylovSolver::cg;
  /// Default ssor (Eisenstat SSOR, omega 1.4, with the coarse level of coarse_size): the fastest measured on
  /// the dam break (docs/performance.md, "Pressure solve" and "Parallel runs").
  Preconditioner preconditioner = Preconditioner::ssor;
  Real tolerance = 1e-8;                  ///< relative residual of the pressure solve
  /// Absolute stop of the pressure solve tied to the incompressibility error: the solve also stops when
  /// the RMS over the rows of r_i dt^2 / rho (the density error, as a fraction of n0, that the residual r
  /// leaves after the correction) is below this. 0: off (relative tolerance only). Its effect on the
  /// iterations and the results: docs/performance.md (## Fluid).
  Real density_tolerance = 1e-6;
  int max_iterations = 500;
  int preconditioner_rebuild_every = 1;   ///< full preconditioner setup every N steps, kept in between
  /// sgs / ssor: side of the coarse groups of the two-level solve, in units of dp (square cells of space;
  /// 0: one level). At least re_laplacian, so that a row meets at most 3^dim groups. 8: the fastest
  /// measured (docs/performance.md, ## Parallel runs).
  Real coarse_size = 8;
  LateralWallFriction lateral_walls;      ///< quasi-2D lateral-wall friction (off by default)
  /// The largest share of a fluid body's particles that may leave the domain before the run stops (exit 3).
  Real max_loss = 0.05;
};

/// Everything the fluid solver (fluid/fluid_solver.hpp) is set up from; io/ builds it from a case
/// (fluid_setup in io/case.hpp).
struct FluidSetup {
  Real dp = 0;                          ///< particle spacing l0 [m]
  Vec gravity = Vec::Zero();
  Real gravity_ramp = 0;                ///< [s]: gravity times ramp_factor(t, gravity_ramp) (core/ramp.hpp)
  Rect domain;                          ///< fluid particles leaving it are removed
  TimeSpec time;
  std::vector<FluidMaterial> materials; ///< indexed by ParticleSet::material of the fluid particles
  FluidParameters parameters;
  TankMotionSpec tank_motion;           ///< moves the wall particles
  /// Walls that move on their own, by their body's name (ParticleSet::bodies): their particles follow the motion.
  std::vector<std::pair<std::string, WallMotionSpec>> wall_motions;
};

}  // namespace mpsfsi
