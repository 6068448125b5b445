// Explicit rotation-aware elastic MPS with brittle fracture and contact (seed 004 §4.2, §4.4;
// seed 000 §2). Implements, per bond (i, j) of the reference configuration:
//   u_ij = r_ij - R_ij r0_ij, R_ij the pair's mean rotation            (seed 004 eq. 25; seed 000 eq. 7-10)
//   normal / shear parts and strains, sigma = 2 mu eps, tau = 2 mu gamma   (eq. 26-29, 31-32)
//   tr(eps)_i = d/n0_i sum u_ij . r_ij / (|r0_ij| |r_ij|) w0_ij, p_i = -lambda tr(eps)_i  (eq. 30, 33)
//   rho dv/dt = 2d/n0 sum (sigma_ij + tau_ij)/|r0| w0 - 2d/n0 sum p_ij e_ij/|r0| w0    (eq. 36-38)
//   I domega/dt = 1/2 sum r_ij x F_ij, F_ij the shear force, I = rho l0^(2+d)/6         (eq. 41-44)
//   (in 3D omega and the torque are vectors and I is the cube's isotropic inertia tensor)
//   symplectic Euler for (v, x) and (omega, theta)                                      (eq. 39-40, 45-46)
//   a bond breaks for good when its normal strain exceeds eps_max                       (eq. 47)
//   surface particles: n_i < n_max - n_c, n_c = 0.5, irreversible                        (eq. 48)
//   unbonded surface pairs closer than l0 repel                                          (§4.4)
//
// Implementation notes (see docs/validation.md, "Solid"):
// * Pair normalisation. Seed 004 uses each particle's n_i^0; taken literally the force of i on j is
//   then not the opposite of the force of j on i near surfaces, and momentum is not conserved. Pair
//   terms therefore use (1/n_i^0 + 1/n_j^0)/2 in place of 1/n_i^0, and the pressure pair term uses
//   p_i/n_i^0 + p_j/n_j^0 in place of 2 p_ij / n_i^0 (identical in the interior). With this choice the
//   forces derive, to first order, from the energy sum_bonds K |u|^2/2 + sum_i V lambda tr_i^2/2,
//   and momentum and angular momentum are conserved to round-off by the symplectic Euler update.
//   "lattice" normalisation (one n0, seed 000) is available too.
// * Volumetric strain at free surfaces (solid.volumetric_strain = corrected, docs/validation.md "Lamb's
//   problem"): eq. 30 with a truncated neighbourhood misses the trace of the strain (at a flat surface it
//   weighs the normal strain about half), so with a large lambda a traction-free strain is not an
//   equilibrium of the surface rows and Rayleigh waves come out ~7 % weak. `corrected` computes tr_i with
//   per-bond weights that make it exact for linear fields and keeps the pair form of the pressure force.
// * 2D: cos and sin of the mean angle come from per-particle half-angle cos/sin by the addition theorem:
//   two trig calls per particle per step instead of two per bond. 3D: each particle's rotation vector becomes
//   a unit quaternion once per step; a bond's mean rotation is their normalised sum (the geodesic midpoint,
//   docs/validation.md "Solid in 3D").
// * Distributed over ranks (core/distribution.hpp): each rank advances its owned particles; a particle's bonds
//   are stored with it (CSR, both directions) and computed at both ends with operations that are symmetric or
//   odd in the exchange of the pair, so both ends, on one rank or two, compute the same numbers and a bond breaks
//   on both sides in the same step. What the solid knows of a particle travels with it in particle fields: its reference
//   position, 1/n0, the reference bond count and the broken bonds (one bit per lattice offset within re).
// * The sums over a particle's bonds and contacts run in order of the partner's global id, so a step gives
//   the same particle state on any rank count.
#include "solid/solid_solver.hpp"

#include "core/binary_io.hpp"
#include "core/collectives.hpp"
#include "core/distribution.hpp"
#include "core/files.hpp"
#include "core/kernel.hpp"
#include "core/neighbours.hpp"
#include "core/operators.hpp"
#include "core/ramp.hpp"
#include "core/rotation.hpp"
#include "core/text.hpp"
#include "core/wall_motion.hpp"
#include "solid/sources.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>

namespace mpsfsi {

namespace {

constexpr Real n_c = 0.5;  ///< surface threshold of eq. 48
/// solid.normalisation = mean: n0 = a n_i^0 + (1 - a) n0_lattice. A face row parallel to a uniaxial stress
/// has the axial stiffness of an interior row for a = 0.46 in 2D (taken as 1/2) and a = 0.585 on a face,
/// 0.600 on an edge in 3D (re = 2.1; docs/validation.md, "Solid in 3D").
constexpr Real surface_blend = dim == 2 ? 0.5 : 0.6;

/// The solid's internal per-particle fields (names starting with '_' are not written unless asked for). They
/// travel with a particle between ranks and into checkpoints: everything the solid knows of a particle.
namespace internal {
constexpr const char* x0 = "_solid_x0";            ///< reference position (the bonds' r0, eq. 25)
constexpr const char* inv_n0 = "_solid_inv_n0";    ///< 1 / n0_i of solid.normalisation
constexpr const char* n_bonds0 = "_solid_bonds0";  ///< bonds in the reference configuration
constexpr const char* broken = "_solid_broken";    ///< broken bonds: bit k for the lattice offset k (offset_slot)
constexpr const char* pn = "_solid_pn";            ///< p_i / n0_i of this step (eq. 33, 38)
constexpr const char* label = "_solid_label";      ///< fragment label (smallest global id of the fragment)
/// Corrected strain weights: the independent entries of the symmetric B_i, the diagonal first.
#if MPSFSI_DIM == 2
constexpr const char* coef[] = {"_solid_bxx", "_solid_byy", "_solid_bxy"};
#else
constexpr const char* coef[] = {"_solid_bxx", "_solid_byy", "_solid_bzz", "_solid_bxy", "_solid_bxz", "_solid_byz"};
#endif
}  // namespace internal

/// Entries of a symmetric dim x dim matrix: (a, b) of entry c, diagonal first (internal::coef's order).
constexpr int n_sym = dim * (dim + 1) / 2;
using SymVec = Eigen::Matrix<Real, n_sym, 1>;
constexpr int sym_a[6] = {0, 1, dim == 2 ? 0 : 2, 0, 0, 1};
constexpr int sym_b[6] = {0, 1, dim == 2 ? 1 : 2, 1, 2, 2};
/// (e e^T)_c for each entry c, and with the off-diagonal entries doubled (e^T B e = doubled . (B_c)).
SymVec outer_entries(const Vec& e, const Real off_diagonal) {
  SymVec s;
  for (int c = 0; c < n_sym; ++c) s[c] = e[sym_a[c]] * e[sym_b[c]] * (c < dim ? 1 : off_diagonal);
  return s;
}

}  // namespace

LameConstants lame_constants(const SolidMaterial& m, const SolidParameters& numerics) {
  LameConstants l;
  if (m.vp && m.vs) {
    l.mu = m.rho * *m.vs * *m.vs;
    l.lambda = m.rho * (*m.vp * *m.vp - 2 * *m.vs * *m.vs);
    return l;
  }
  const Real E = numerics.modulus(m);
  l.mu = E / (2 * (1 + m.nu));
  l.lambda = E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu));
  if (numerics.plane_stress) l.lambda = 2 * l.lambda * l.mu / (l.lambda + 2 * l.mu);
  return l;
}

Real p_wave_speed(const SolidMaterial& m, const SolidParameters& numerics) {
  const LameConstants l = lame_constants(m, numerics);
  return std::sqrt((l.lambda + 2 * l.mu) / m.rho);
}

Real solid_interaction_radius(const SolidSetup& setup) { return 1.25 * setup.parameters.re * setup.dp; }

struct SolidSolver::Impl {
  struct MaterialConstants {
    Real lambda = 0, mu = 0, mass = 0, inertia = 0, eps_max = 0;
  };
  struct Load {
    SolidLoadSpec spec;
    std::vector<std::size_t> members;  ///< owned solid indices k, renewed with the bonds
  };
  struct Source {
    SourceSpec spec;
    std::vector<GlobalId> id;  ///< the stencil's particles (on every rank: a few dozen)
    std::vector<Vec> g;        ///< force per unit amplitude s(t) (solid/sources.hpp)
    std::vector<std::pair<std::size_t, std::size_t>> members;  ///< (owned k, stencil entry), renewed with the bonds
  };

  ParticleSet& p;
  Distribution* dist = nullptr;  ///< null: this process holds the whole solid
  MPI_Comm comm = MPI_COMM_NULL;
  Real dp = 0, re = 0;
  Real volume = 0;        ///< l0^d: particle volume per unit thickness
  Real n0_lattice = 0;
  Real n_max = 0;         ///< n_i^max of eq. 48 (over all ranks)
  Real k_contact = 0;     ///< contact spring [N/m per unit thickness]
  Real dt_factor = 0.2;
  Real c_p_max = 0;
  Real damping_time = 0;  ///< Kelvin-Voigt retardation time eta of the bonds [s] (0: none)
  bool plane_stress = false, corrected = false, breakable = false;
  Vec gravity = Vec::Zero();
  Real gravity_ramp = 0;  ///< [s]: gravity times ramp_factor(t, gravity_ramp) (core/ramp.hpp)
  TankMotion tank;
  /// By body index: the wall motion a body's clamped particles follow (SolidSetup::clamp_motions; none: the tank's).
  std::vector<WallMotion> clamp_motion;
  std::vector<WallMotionState> clamp_state;  ///< each body's clamp_motion at the end of the current step
  std::vector<Rotation> clamp_rotation;      ///< ... its rotation there
  std::vector<MaterialConstants> mat;
  std::size_t n_broken = 0;  ///< bonds broken so far (all ranks)
  std::size_t n_broken_stored = 0;  ///< n_broken at the last iteration checkpoint

  // Lattice offsets within re: bit slot of the bond to the particle at x0_i + dp * offset.
  int o_range = 0;
  std::vector<int> o_slot;  ///< dense over [-o_range, o_range]^d; -1: not a bond direction

  // Fields.
  std::vector<Vec>* f_x0 = nullptr;
  std::vector<Real>* f_inv_n0 = nullptr;
  std::vector<Real>* f_bonds0 = nullptr;
  std::vector<Real>* f_broken = nullptr;
  std::vector<Real>* f_pn = nullptr;
  std::vector<Real>* f_label = nullptr;
  std::vector<Real>* f_coef[n_sym] = {};
  std::vector<Angular>* f_theta = nullptr;  ///< rotation vector (the angle in 2D)
  std::vector<Angular>* f_omega = nullptr;
  std::vector<Real>* f_von_mises = nullptr;
  std::vector<Real>* f_pressure = nullptr;
  std::vector<Real>* f_fragment = nullptr;
  std::vector<Real>* f_surface = nullptr;
  std::vector<Vec>* f_displacement = nullptr;
  std::vector<Vec>* f_load = nullptr;

  // Local structure, renewed when the particle set changed (migration, ghosts, reorder, restart).
  std::vector<GlobalId> seen_gid;  ///< global ids of the set at the last renewal (owned, then ghosts)
  std::size_t seen_owned = 0;
  /// Solid particles held here, in order of local index: the owned ones first (k < n(): solid index k of the
  /// bonds and per-owned arrays), then the ghosts (contact candidates, rotations).
  std::vector<LocalIndex> local;
  std::size_t n_own = 0;
  // Bonds of each owned solid particle k (both directions: every rank computes its own particles' forces),
  // CSR over k, sorted by the partner's global id.
  std::vector<std::size_t> b_off;
  std::vector<LocalIndex> b_j;
  std::vector<Vec> b_r0;            ///< x0_j - x0_i
  std::vector<Real> b_inv_r0, b_wr, b_k, b_vi;
  std::vector<std::uint8_t> b_slot_i;  ///< bit slot of the offset i -> j
  std::vector<std::uint8_t> b_intact;
  std::vector<Real> b_ce;           ///< scratch: V d w0/|r0| / |r_ij| of this step (times r_ij: eq. 38's direction)
  // Per owned k.
  std::vector<Vec> force;
  std::vector<Angular> torque;
  std::vector<Real> tr;
  std::vector<std::uint8_t> new_surface;
  // Per local particle (size of the set): its rotation, as cos and sin of half the angle in 2D, a unit
  // quaternion in 3D.
#if MPSFSI_DIM == 2
  std::vector<Real> ch, sh;
#else
  std::vector<Eigen::Quaternion<Real>> q_rot;
#endif
  std::vector<Load> loads;
  std::vector<Source> sources;
  // Contact scratch.
  std::vector<Vec> s_x;
  std::vector<LocalIndex> s_i;
  std::vector<std::pair<GlobalId, LocalIndex>> s_pairs;
  NeighbourList s_nl;
  CellGrid s_grid;

  // Fragments (at the last prepare_output).
  std::size_t n_frag = 0;
  std::string out_dir;
  bool csv_started = false;

  Impl(const SolidSetup& setup, ParticleSet& particles, Distribution* distribution);
  std::size_t n() const { return n_own; }
  int n_ranks() const { return dist ? dist->n_ranks() : 1; }
  bool is_solid(const std::size_t i) const { return p.kind[i] == ParticleKind::solid; }
  std::uint64_t broken_bits(const std::size_t i) const { return static_cast<std::uint64_t>((*f_broken)[i]); }
  void set_broken_bit(const std::size_t i, const int slot) {
    (*f_broken)[i] = static_cast<Real>(broken_bits(i) | (std::uint64_t{1} << slot));
  }
  /// Bit slot of the reference offset r0 (x0_j - x0_i), or -1 when r0 is not dp times a lattice offset in range.
  int slot_of(const Vec& r0) const {
    std::size_t k = 0, stride = 1;
    for (int a = 0; a < dim; ++a) {
      const Real q = r0[a] / dp;
      const long o = std::lround(q);
      if (std::abs(q - static_cast<Real>(o)) > 1e-6 || std::abs(o) > o_range) return -1;
      k += static_cast<std::size_t>(o + o_range) * stride;
      stride *= static_cast<std::size_t>(2 * o_range + 1);
    }
    return o_slot[k];
  }
  template <class T>
  void allreduce(T* values, int n, MPI_Datatype type, MPI_Op op) const {
    if (comm != MPI_COMM_NULL) MPI_Allreduce(MPI_IN_PLACE, values, n, type, op, comm);
  }
  /// Refreshes the solid ghosts' fields (the only ghosts the solid reads).
  /// The lowest rank's non-empty message on every rank (this process's alone without a distribution).
  std::string agreed(const std::string& local) const { return comm != MPI_COMM_NULL ? agreed_message(comm, local) : local; }
  void exchange(const std::vector<std::string>& fields) {
    if (dist && dist->n_ranks() > 1) dist->exchange_ghosts(p, fields, ParticleKind::solid);
  }
  /// Owners and ghosts current for a solid step (migration and new ghosts when due, else the ghosts' state
  /// refreshed), then the local structure renewed if the set changed.
  void sync();
  bool set_changed() const;
  /// Owned and local solid lists, bonds, load and source members from the particle set.
  void renew_structure();
  void compute_rotations();
  /// Particle i's rotation as compute_rotations left it for this step.
  Rotation rotation_of(const std::size_t i) const {
#if MPSFSI_DIM == 2
    return Rotation((*f_theta)[i]);
#else
    return Rotation(q_rot[i]);
#endif
  }
  /// Relative displacement u_ij = r_ij - R_ij r0_ij (eq. 25) and r_ij of bond b of owned particle i, R_ij the
  /// pair's mean rotation: R((theta_i + theta_j)/2) in 2D, in 3D the geodesic midpoint of the two rotations,
  /// the unit quaternion (q_i + q_j) / |q_i + q_j| (q_j's sign chosen so that q_i . q_j >= 0), which is
  /// R((theta_i + theta_j)/2) for rotations about one axis. Every operation is symmetric (the mean rotation) or
  /// odd (r, r0) in the exchange of i and j, so the other end computes exactly -u_ij and -r_ij, bit for bit.
  void bond_state(const std::size_t i, const std::size_t b, Vec& r, Vec& u) const {
    const auto j = static_cast<std::size_t>(b_j[b]);
    const Vec r0 = b_r0[b];
    r = p.position[j] - p.position[i];
#if MPSFSI_DIM == 2
    const Real cs = ch[i] * ch[j] - sh[i] * sh[j];  // cos((theta_i + theta_j)/2)
    const Real sn = sh[i] * ch[j] + ch[i] * sh[j];  // sin((theta_i + theta_j)/2)
    u = Vec(r[0] - (cs * r0[0] - sn * r0[1]), r[1] - (sn * r0[0] + cs * r0[1]));
#else
    const auto& qi = q_rot[i].coeffs();
    const auto& qj = q_rot[j].coeffs();
    const Eigen::Matrix<Real, 4, 1> sum = qi.dot(qj) >= 0 ? Eigen::Matrix<Real, 4, 1>(qi + qj) : Eigen::Matrix<Real, 4, 1>(qi - qj);
    const Eigen::Quaternion<Real> mean(Eigen::Matrix<Real, 4, 1>(sum / sum.norm()));
    u = r - mean * r0;
#endif
  }
  /// Call f(k, i, j, b, r_ij, u_ij) for every intact bond of every owned solid particle.
  template <class F>
  void for_each_intact_bond(F&& f) const {
    for (std::size_t k = 0; k < n(); ++k) {
      const auto i = static_cast<std::size_t>(local[k]);
      for (std::size_t b = b_off[k]; b < b_off[k + 1]; ++b) {
        if (!b_intact[b]) continue;
        Vec r, u;
        bond_state(i, b, r, u);
        f(k, i, static_cast<std::size_t>(b_j[b]), b, r, u);
      }
    }
  }
  bool bonded(const std::size_t k, const LocalIndex j) const {
    for (std::size_t b = b_off[k]; b < b_off[k + 1]; ++b)
      if (b_j[b] == j) return b_intact[b] != 0;
    return false;
  }
  void contact_forces(std::size_t& n_contacts);
  /// Fragment labels (field _solid_label) and their count n_frag. Collective.
  void compute_fragments();
  SolidStepReport advance(Real t, Real dt);
  const MaterialConstants& material_of(const std::size_t i) const { return mat[static_cast<std::size_t>(p.material[i])]; }
};

SolidSolver::Impl::Impl(const SolidSetup& setup, ParticleSet& particles, Distribution* distribution)
    : p(particles), dist(distribution) {
  if (dist) comm = dist->comm();
  const SolidParameters& solid = setup.parameters;
  dp = setup.dp;
  volume = std::pow(dp, dim);
  re = solid.re * dp;
  n0_lattice = lattice_constants(dp, re).n0;
  dt_factor = solid.dt_factor;
  plane_stress = solid.plane_stress;
  corrected = solid.volumetric_strain == VolumetricStrain::corrected;
  gravity = setup.gravity;
  gravity_ramp = setup.gravity_ramp;
  tank = make_tank_motion(setup.tank_motion);
  clamp_motion.assign(p.bodies.size(), WallMotion());
  for (const auto& [name, motion] : setup.clamp_motions)
    for (std::size_t k = 0; k < p.bodies.size(); ++k)
      if (p.bodies[k].name == name) clamp_motion[k] = WallMotion(motion);
  clamp_state.assign(p.bodies.size(), WallMotionState());
  clamp_rotation.assign(p.bodies.size(), Rotation());

  // Lattice offsets within re, in lexicographic order: the bit slots of the broken-bond flags.
  o_range = static_cast<int>(std::ceil(solid.re));
  const int width = 2 * o_range + 1;
  o_slot.assign(static_cast<std::size_t>(std::pow(width, dim)), -1);
  int n_slots = 0;
  for (std::size_t k = 0; k < o_slot.size(); ++k) {
    Vec o;
    std::size_t q = k;
    for (int a = 0; a < dim; ++a) {
      o[a] = static_cast<Real>(static_cast<int>(q % static_cast<std::size_t>(width)) - o_range);
      q /= static_cast<std::size_t>(width);
    }
    const Real r = o.norm() * dp;
    if (r > 0 && weight(r, re) > 0) o_slot[k] = n_slots++;
  }
  if (n_slots > 52)
    throw SetupError(fmt::format("{}: solid.re = {} gives {} bonds per particle; at most 52 are supported", setup.origin,
                                 solid.re, n_slots));

  f_x0 = &p.add_vector_field(internal::x0);
  f_inv_n0 = &p.add_scalar_field(internal::inv_n0);
  f_bonds0 = &p.add_scalar_field(internal::n_bonds0);
  f_broken = &p.add_scalar_field(internal::broken);
  f_pn = &p.add_scalar_field(internal::pn);
  f_label = &p.add_scalar_field(internal::label);
  if (corrected)
    for (int c = 0; c < n_sym; ++c) f_coef[c] = &p.add_scalar_field(internal::coef[c]);
  f_theta = &add_angular_field(p, "rotation");
  f_omega = &add_angular_field(p, "angular_velocity");
  f_von_mises = &p.add_scalar_field("von_mises");
  f_pressure = &p.add_scalar_field("solid_pressure");
  f_fragment = &p.add_scalar_field("fragment", -1);
  f_surface = &p.add_scalar_field(solid_fields::surface);
  f_displacement = &p.add_vector_field("displacement");
  f_load = &p.add_vector_field(solid_fields::load);

  // Ghosts of the initial scene (positions = reference positions) within the halo.
  if (dist && dist->n_ranks() > 1) {
    p.drop_ghosts();
    dist->build_ghosts(p);
  }

  std::string error;
  std::vector<LameConstants> lame;
  for (const auto& m : setup.materials) {
    lame.push_back(lame_constants(m, solid));
    MaterialConstants c;
    c.lambda = lame.back().lambda;
    c.mu = lame.back().mu;
    c.mass = m.rho * volume;
    c.inertia = m.rho * volume * dp * dp / 6;  // eq. 44; in 3D the cube's inertia tensor is this times I
    c.eps_max = m.fracture_strain ? *m.fracture_strain : std::numeric_limits<Real>::infinity();
    mat.push_back(c);
  }
  Real mu_max = 0;
  std::vector<std::uint8_t> used(mat.size(), 0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!is_solid(i)) continue;
    const int m = p.material[i];
    if (m < 0 || m >= static_cast<int>(setup.materials.size())) {
      if (error.empty()) error = fmt::format("{}: solid particle {} has no solid material", setup.origin, p.global_id[i]);
      continue;
    }
    used[static_cast<std::size_t>(m)] = 1;
    (*f_x0)[i] = p.position[i];
  }
  error = agreed(error);
  if (!error.empty()) throw SetupError(error);
  allreduce(used.data(), static_cast<int>(used.size()), MPI_UINT8_T, MPI_MAX);
  for (std::size_t m = 0; m < mat.size(); ++m) {
    if (!used[m]) continue;
    mu_max = std::max(mu_max, mat[m].mu);
    c_p_max = std::max(c_p_max, p_wave_speed(setup.materials[m], solid));
    if (std::isfinite(mat[m].eps_max)) breakable = true;
    if (!(mat[m].lambda + 2 * mat[m].mu > 0) || !(mat[m].mu > 0))
      throw SetupError(fmt::format("{}: solid material '{}': expected mu > 0 and lambda + 2 mu > 0 (check vp > sqrt(2) vs)",
                                   setup.origin, setup.materials[m].name));
  }

  // Initial spin: a body given an angular velocity rotates rigidly, so its particles spin with it.
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    if (!is_solid(i)) continue;
    const std::string& body = p.bodies[p.body[i]].name;
    for (const auto& b : setup.spins)
      if (b.body == body && !p.clamped[i]) (*f_omega)[i] = b.angular_velocity;
    (*f_theta)[i] = angular_zero();
  }

  // Reference bonds of the owned particles: neighbours within re of the same body (eq. 25, r0 and w0 fixed);
  // n0_i is eq. 8's number density over them.
  std::vector<LocalIndex> all;
  std::vector<Vec> x0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (is_solid(i)) {
      all.push_back(static_cast<LocalIndex>(i));
      x0.push_back((*f_x0)[i]);
    }
  NeighbourList nl;
  build_neighbour_list(x0, re, nl);
  std::vector<Real> n0(p.size(), 0);
  Real n_max_local = 0;
  for (std::size_t q = 0; q < all.size(); ++q) {
    const auto i = static_cast<std::size_t>(all[q]);
    if (i >= p.n_owned()) continue;
    const auto same_body = [&](const std::size_t r) { return p.body[static_cast<std::size_t>(all[r])] == p.body[i]; };
    Eigen::Matrix<Real, n_sym, n_sym> m = Eigen::Matrix<Real, n_sym, n_sym>::Zero();
    int count = 0;
    for_each_pair(x0, nl, re, q, same_body, [&](std::size_t, const Vec& r0, Real, const Real w0) {
      n0[i] += w0;
      ++count;
      if (slot_of(r0) < 0 && error.empty())
        error = fmt::format("{}: body '{}' is not on a lattice of spacing dp = {} m (solid particles {} and a neighbour "
                            "at {} m): the solid's bonds follow the lattice offsets",
                            setup.origin, p.bodies[p.body[i]].name, dp, p.global_id[i], show_point(r0));
      const Vec e = r0.normalized();
      m += w0 * outer_entries(e, 1) * outer_entries(e, 2).transpose();  // e e^T by entry; e^T B e = col . B
    });
    (*f_bonds0)[i] = count;
    n_max_local = std::max(n_max_local, n0[i]);
    const SolidNormalisation norm = solid.normalisation;
    const Real n0_used = norm == SolidNormalisation::particle  ? n0[i]
                         : norm == SolidNormalisation::lattice ? n0_lattice
                                                               : surface_blend * n0[i] + (1 - surface_blend) * n0_lattice;
    (*f_inv_n0)[i] = n0_used > 0 ? 1 / n0_used : 0;
    if (corrected) {
      // B_i with sum_j w0 (e0^T B_i e0) e0 e0^T = I over i's bonds; too few bond directions (a particle with
      // bonds along one line): NaN, eq. 30 is kept.
      const Eigen::FullPivLU<Eigen::Matrix<Real, n_sym, n_sym>> lu(m);
      const bool ok = lu.rank() == n_sym && std::abs(lu.determinant()) > 1e-9 * std::pow(m.norm(), n_sym);
      SymVec identity = SymVec::Zero();
      identity.head(dim).setOnes();
      const SymVec coef = ok ? SymVec(lu.solve(identity)) : SymVec::Constant(std::numeric_limits<Real>::quiet_NaN());
      for (int c = 0; c < n_sym; ++c) (*f_coef[c])[i] = coef[c];
    }
  }
  error = agreed(error);
  if (!error.empty()) throw SetupError(error);
  allreduce(&n_max_local, 1, MPI_DOUBLE, MPI_MAX);
  n_max = std::max(n_max_local, n0_lattice);
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    if (is_solid(i)) (*f_surface)[i] = n0[i] < n_max - n_c;

  // Contact spring: contact_stiffness times the stiffness of a nearest-neighbour bond of the stiffest material.
  k_contact = solid.contact_stiffness * volume * 4 * dim * mu_max * weight(dp, re) / (dp * dp * n0_lattice);

  // Loads: checked here over all ranks; their members follow the particles (renew_structure).
  for (const auto& ls : setup.loads) {
    unsigned long long counts[2] = {0, 0};  // particles of the body, of the body in the region
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (!is_solid(i) || p.bodies[p.body[i]].name != ls.body) continue;
      ++counts[0];
      if (ls.region.contains((*f_x0)[i])) ++counts[1];
    }
    allreduce(counts, 2, MPI_UNSIGNED_LONG_LONG, MPI_SUM);
    if (counts[0] == 0)
      throw SetupError(fmt::format("{}: solid load '{}': body '{}' is not a solid body with particles", setup.origin,
                                   ls.name, ls.body));
    if (counts[1] == 0)
      throw SetupError(fmt::format("{}: solid load '{}': no particle of body '{}' lies in its region", setup.origin,
                                   ls.name, ls.body));
    const Real norm = ls.direction.norm();
    if (!(norm > 0)) throw SetupError(fmt::format("{}: solid load '{}': direction must be non-zero", setup.origin, ls.name));
    Load load{ls, {}};
    load.spec.direction /= norm;
    loads.push_back(std::move(load));
  }
  // Seismic sources: the force pattern over the body's particles around the source point, built from the
  // candidates of every rank (gathered, in order of global id) so that it is the same on any rank count.
  for (const auto& ss : setup.sources) {
    std::vector<double> mine;  // (gid, x0...) of this rank's owned candidates within the source radius
    unsigned long long n_body = 0;
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (!is_solid(i) || p.bodies[p.body[i]].name != ss.body) continue;
      ++n_body;
      if (((*f_x0)[i] - ss.position).norm() > ss.radius * (1 + 1e-9) + dp) continue;
      mine.push_back(static_cast<double>(p.global_id[i]));
      for (int a = 0; a < dim; ++a) mine.push_back((*f_x0)[i][a]);
    }
    allreduce(&n_body, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM);
    if (n_body == 0)
      throw SetupError(fmt::format("{}: source '{}': body '{}' is not a solid body with particles", setup.origin, ss.name,
                                   ss.body));
    const std::vector<double> gathered = comm != MPI_COMM_NULL ? all_gather(comm, mine) : mine;
    std::vector<std::pair<GlobalId, Vec>> cand;
    for (std::size_t q = 0; q < gathered.size(); q += 1 + dim) {
      Vec x;
      for (int a = 0; a < dim; ++a) x[a] = gathered[q + 1 + static_cast<std::size_t>(a)];
      cand.emplace_back(static_cast<GlobalId>(gathered[q]), x);
    }
    std::sort(cand.begin(), cand.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<Vec> cx;
    std::vector<std::size_t> ck;
    for (const auto& c : cand) {
      ck.push_back(cx.size());
      cx.push_back(c.second);
    }
    const VectorStencil st = source_stencil(ss, cx, ck);
    Source src{ss, {}, st.value, {}};
    for (const std::size_t k : st.index) src.id.push_back(cand[k].first);
    sources.push_back(std::move(src));
  }
  // The ghosts get the reference data of their owners.
  std::vector<std::string> reference = {internal::x0, internal::inv_n0, internal::n_bonds0, "rotation", "angular_velocity",
                                        solid_fields::surface};
  if (corrected)
    for (const char* c : internal::coef) reference.emplace_back(c);
  exchange(reference);
  renew_structure();
}

bool SolidSolver::Impl::set_changed() const {
  if (p.size() != seen_gid.size() || p.n_owned() != seen_owned) return true;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.global_id[i] != seen_gid[i]) return true;
  return false;
}

void SolidSolver::Impl::sync() {
  if (dist) dist->renew(p, {"position", "velocity", "rotation", solid_fields::surface}, ParticleKind::solid);
  if (set_changed()) renew_structure();
}

void SolidSolver::Impl::renew_structure() {
  seen_gid = p.global_id;
  seen_owned = p.n_owned();
  n_own = 0;
  local.clear();
  std::vector<Vec> x0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!is_solid(i)) continue;
    n_own += i < p.n_owned();
    local.push_back(static_cast<LocalIndex>(i));
    x0.push_back((*f_x0)[i]);
  }
  const std::size_t ns = n();
  NeighbourList nl;
  build_neighbour_list(x0, re, nl);
  b_off.assign(ns + 1, 0);
  b_j.clear();
  b_r0.clear();
  b_inv_r0.clear();
  b_wr.clear();
  b_k.clear();
  b_vi.clear();
  b_slot_i.clear();
  std::vector<std::pair<GlobalId, LocalIndex>> partners;
  std::string error;
  // Row k of the list is owned particle k (the owned ones come first in `local`).
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(local[k]);
    b_off[k] = b_j.size();
    partners.clear();
    for (std::size_t q = nl.begin(k); q < nl.end(k); ++q) {
      const auto j = static_cast<std::size_t>(local[static_cast<std::size_t>(nl.index[q])]);
      if (p.body[j] == p.body[i] && in_support(((*f_x0)[j] - (*f_x0)[i]).squaredNorm(), re))
        partners.emplace_back(p.global_id[j], static_cast<LocalIndex>(j));
    }
    std::sort(partners.begin(), partners.end());
    const std::uint64_t broken = broken_bits(i);
    const Real inv_n0_i = (*f_inv_n0)[i];
    const MaterialConstants& mi = material_of(i);
    for (const auto& [gj, jl] : partners) {
      const auto j = static_cast<std::size_t>(jl);
      const Vec r0 = (*f_x0)[j] - (*f_x0)[i];
      const int slot_i = slot_of((*f_x0)[j] - (*f_x0)[i]);
      [[maybe_unused]] const int slot_j = slot_of((*f_x0)[i] - (*f_x0)[j]);
      assert(slot_i >= 0 && slot_j >= 0 && "bonds join lattice neighbours (checked at setup)");
      if (broken & (std::uint64_t{1} << slot_i)) continue;
      assert(!(broken_bits(j) & (std::uint64_t{1} << slot_j)) && "a bond is broken on both sides or on neither");
      const Real len = r0.norm();
      const Real w0 = re / len - 1;
      b_j.push_back(jl);
      b_r0.push_back(r0);
      b_inv_r0.push_back(1 / len);
      b_wr.push_back(w0 / len);
      b_slot_i.push_back(static_cast<std::uint8_t>(slot_i));
      // Force on i: V 2d/n0 2 mu u/|r0| w0/|r0| with 1/n0 -> (1/n0_i + 1/n0_j)/2 (eq. 36-37).
      b_k.push_back(volume * 2 * dim * mi.mu * (w0 / len) / len * (inv_n0_i + (*f_inv_n0)[j]));
      // Volumetric strain weight of i (eq. 30): d/n0_i w0/|r0|, or with corrected weights w0/|r0| e0^T B_i e0.
      Real vi = dim * inv_n0_i * w0 / len;
      if (corrected && !std::isnan((*f_coef[0])[i])) {
        const Vec e = r0 / len;
        const SymVec col = outer_entries(e, 2);
        vi = 0;
        for (int c = 0; c < n_sym; ++c) vi += (*f_coef[c])[i] * col[c];
        vi *= w0 / len;
      }
      b_vi.push_back(vi);
    }
    // Every intact bond of the reference configuration must be in reach: a missing partner would silently
    // free the particle.
    const std::size_t n_intact = b_j.size() - b_off[k];
    const auto expected = static_cast<std::size_t>((*f_bonds0)[i]) - static_cast<std::size_t>(__builtin_popcountll(broken));
    if (n_intact < expected && error.empty())
      error = fmt::format("solid: particle {} has {} of its {} intact bonds within reach on rank {}: a bonded neighbour is "
                          "farther than the halo ({:.3g} m); the body was stretched beyond its bonds' range (the run went "
                          "unstable; reduce dt)",
                          p.global_id[i], n_intact, expected, dist ? dist->rank() : 0,
                          dist ? dist->settings().halo_width : 0.0);
  }
  b_off[ns] = b_j.size();
  // Thrown on this rank alone (renewals are local: a rank's set may change while another's does not); the run
  // loop stops every rank on an exception within a step.
  if (!error.empty()) throw std::runtime_error(error);
  b_intact.assign(b_j.size(), 1);
  b_ce.assign(b_j.size(), 0);
  force.assign(ns, Vec::Zero());
  torque.assign(ns, angular_zero());
  tr.assign(ns, 0);
  new_surface.assign(ns, 0);
#if MPSFSI_DIM == 2
  ch.assign(p.size(), 1);
  sh.assign(p.size(), 0);
#else
  q_rot.assign(p.size(), Eigen::Quaternion<Real>::Identity());
#endif
  // Loads and sources: members among the owned particles.
  for (auto& load : loads) {
    load.members.clear();
    for (std::size_t k = 0; k < ns; ++k) {
      const auto i = static_cast<std::size_t>(local[k]);
      if (p.bodies[p.body[i]].name == load.spec.body && load.spec.region.contains((*f_x0)[i])) load.members.push_back(k);
    }
  }
  for (auto& src : sources) {
    src.members.clear();
    for (std::size_t q = 0; q < src.id.size(); ++q) {
      const LocalIndex i = p.local_index(src.id[q]);
      if (i >= 0 && static_cast<std::size_t>(i) < p.n_owned())
        src.members.emplace_back(static_cast<std::size_t>(std::lower_bound(local.begin(), local.begin() + static_cast<std::ptrdiff_t>(n_own), i) - local.begin()), q);
    }
  }
}

void SolidSolver::Impl::compute_rotations() {
  for (const LocalIndex li : local) {
    const auto i = static_cast<std::size_t>(li);
#if MPSFSI_DIM == 2
    ch[i] = std::cos(0.5 * (*f_theta)[i]);
    sh[i] = std::sin(0.5 * (*f_theta)[i]);
#else
    q_rot[i] = Rotation::from_vector((*f_theta)[i]).quaternion();
#endif
  }
}

void SolidSolver::Impl::contact_forces(std::size_t& n_contacts) {
  // Surface flags as of the start of the step (the ghosts' from the exchange), so that every rank count
  // sees the same pairs.
  const auto& surface = *f_surface;
  s_x.clear();
  s_i.clear();
  for (const LocalIndex li : local) {
    if (surface[static_cast<std::size_t>(li)] == 0) continue;
    s_x.push_back(p.position[static_cast<std::size_t>(li)]);
    s_i.push_back(li);
  }
  std::string error;
  if (s_x.size() >= 2) {
    // Guard the cell grid: a blown-up state (dt too large) would ask for an absurd number of cells.
    Vec lo = s_x[0], hi = s_x[0];
    bool finite = true;
    for (const Vec& y : s_x) {
      finite = finite && y.allFinite();
      lo = lo.cwiseMin(y);
      hi = hi.cwiseMax(y);
    }
    const Vec cells = (hi - lo) / dp + Vec::Ones();
    if (!finite)
      error = "solid: a surface particle has a non-finite position; the run went unstable (reduce dt)";
    else if (cells.prod() > 16.0 * static_cast<Real>(s_x.size()) + 4e6)
      error = fmt::format(
          "solid: the surface particles spread over a box of sides {} m ({:.3g} contact cells of side dp for {} particles); "
          "the run went unstable (reduce dt) or fragments flew too far apart (shrink the domain)",
          show_point(hi - lo), cells.prod(), s_x.size());
  }
  if (!error.empty()) throw std::runtime_error(error);
  if (s_x.size() < 2) return;
  build_neighbour_list(s_x, dp, s_nl, s_grid);
  const Real d_min = 0.05 * dp;
  // The owned surface particles come first in s_i, in order of k.
  std::size_t k = 0;
  for (std::size_t q = 0; q < s_x.size(); ++q) {
    const auto i = static_cast<std::size_t>(s_i[q]);
    if (i >= p.n_owned()) break;
    while (static_cast<std::size_t>(local[k]) != i) ++k;
    s_pairs.clear();
    for (std::size_t e = s_nl.begin(q); e < s_nl.end(q); ++e) {
      const LocalIndex j = s_i[static_cast<std::size_t>(s_nl.index[e])];
      if (bonded(k, j)) continue;  // adjacent on one surface
      s_pairs.emplace_back(p.global_id[static_cast<std::size_t>(j)], j);
    }
    std::sort(s_pairs.begin(), s_pairs.end());  // the same sum in the same order on any rank count
    for (const auto& [gj, jl] : s_pairs) {
      const auto j = static_cast<std::size_t>(jl);
      // Pair in order of global id (a, b): both ends compute the same force.
      const bool i_first = p.global_id[i] < gj;
      const std::size_t a = i_first ? i : j, c = i_first ? j : i;
      const Vec r = p.position[c] - p.position[a];
      const Real d = r.norm();
      // Direction: along r; for coincident particles fall back to the reference direction.
      Vec e = d > 1e-12 * dp ? Vec(r / d) : Vec((*f_x0)[c] - (*f_x0)[a]);
      if (d <= 1e-12 * dp) e = e.norm() > 0 ? Vec(e.normalized()) : Vec(Vec::UnitX());
      // Repulsion k (l0 - d) l0/d: linear near contact, stiffening without bound as d -> 0.
      const Real mag = k_contact * (dp - d) * dp / std::max(d, d_min);
      force[k] -= (i_first ? mag : -mag) * e;
      if (i_first) ++n_contacts;
    }
  }
}

SolidStepReport SolidSolver::Impl::advance(const Real t, const Real dt) {
  sync();
  compute_rotations();
  const std::size_t ns = n();
  std::fill(force.begin(), force.end(), Vec::Zero());
  std::fill(torque.begin(), torque.end(), angular_zero());
  std::fill(tr.begin(), tr.end(), 0.0);
  std::fill(new_surface.begin(), new_surface.end(), 0);
  unsigned long long counts[2] = {0, 0};  // bonds broken in this step, contacts

  // Pass 1: bond displacement (eq. 25-29), fracture (eq. 47), volumetric strain sums (eq. 30),
  // normal + shear forces (eq. 36-37) and the torques that cancel the shear couple (eq. 41-43). Each rank
  // computes its own particles' bonds; both ends of a bond see the same numbers bit for bit (bond_state), so
  // a bond breaks on both sides in the same step and the two forces are exactly opposite.
  const Real vd = volume * dim;
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(local[k]);
    const Real eps_max = material_of(i).eps_max;
    Vec fi = Vec::Zero();
    Angular ti = angular_zero();
    Real tri = 0;
    bool broke = false;
    for (std::size_t b = b_off[k]; b < b_off[k + 1]; ++b) {
      if (!b_intact[b]) continue;
      const auto j = static_cast<std::size_t>(b_j[b]);
      Vec r, u;
      bond_state(i, b, r, u);
      const Real inv_r = 1 / std::sqrt(r.squaredNorm());
      const Real un = u.dot(r) * inv_r;  // |(u_ij)_n| with sign (eq. 26), the same from either end
      if (un * b_inv_r0[b] > eps_max) {  // eq. 47: the bond breaks for good
        b_intact[b] = 0;
        set_broken_bit(i, b_slot_i[b]);
        broke = true;
        if (p.global_id[i] < p.global_id[j]) ++counts[0];
        continue;
      }
      tri += b_vi[b] * un;
      Vec fe = b_k[b] * u;  // sigma_ij + tau_ij term, force on i
      // Kelvin-Voigt bond damping: eta times the bond's normal stretch rate, same stiffness; rigid
      // translation and rotation give no normal stretch rate and are not damped.
      if (damping_time > 0) fe += (b_k[b] * damping_time * (p.velocity[j] - p.velocity[i]).dot(r) * inv_r * inv_r) * r;
      fi += fe;
      ti += 0.5 * cross(r, fe);  // -1/2 M_ij, M_ij = -r_ij x F_ij (eq. 42-43), the same for both ends
      b_ce[b] = vd * b_wr[b] * inv_r;
    }
    force[k] = fi;
    torque[k] = ti;
    tr[k] = tri;
    if (broke) {  // eq. 48 over the intact bonds, irreversible
      Real n_now = 0;
      for (std::size_t b = b_off[k]; b < b_off[k + 1]; ++b)
        if (b_intact[b]) n_now += b_wr[b] / b_inv_r0[b];  // w0
      new_surface[k] = n_now < n_max - n_c;
    }
  }
  // Pressure p_i = -lambda tr(eps)_i (eq. 30, 33); pn holds p_i / n0_i, which the ghosts need.
  auto& pn = *f_pn;
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(local[k]);
    pn[i] = -material_of(i).lambda * tr[k] * (*f_inv_n0)[i];
  }
  exchange({internal::pn});
  // Pass 2: pressure term (eq. 38) in the pair form -V d w0/|r0| (p_i/n0_i + p_j/n0_j) e_ij. With the eq. 30
  // weights this is the gradient of sum_i V lambda tr_i^2 / 2. With corrected weights (exact trace) the force
  // keeps these weights: at a flat free surface the pressure then balances the bonds' normal force exactly
  // when sigma_yy = 0 (a uniform traction-free strain is an equilibrium, docs/validation.md), at the price of
  // a pressure force that is no longer exactly an energy gradient near surfaces.
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(local[k]);
    Vec fi = Vec::Zero();
    const Vec xi = p.position[i];
    for (std::size_t b = b_off[k]; b < b_off[k + 1]; ++b) {
      if (!b_intact[b]) continue;
      const auto j = static_cast<std::size_t>(b_j[b]);
      fi -= (pn[i] + pn[j]) * (b_ce[b] * Vec(p.position[j] - xi));
    }
    force[k] += fi;
  }

  SolidStepReport report;
  std::size_t n_contacts = 0;
  contact_forces(n_contacts);
  counts[1] = n_contacts;
  for (std::size_t k = 0; k < ns; ++k)
    if (new_surface[k]) (*f_surface)[static_cast<std::size_t>(local[k])] = 1;

  // External loads: gravity, the coupling's per-particle force, pressure pulses, seismic sources.
  const Vec g = gravity * ramp_factor(t, gravity_ramp);
  const bool has_gravity = g.squaredNorm() > 0;
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(local[k]);
    if (has_gravity) force[k] += material_of(i).mass * g;
    force[k] += (*f_load)[i];
  }
  for (const auto& load : loads) {
    const Real arg = (t - load.spec.time) / load.spec.width;
    const Vec f = load.spec.peak * std::exp(-arg * arg) * std::pow(dp, dim - 1) * load.spec.direction;
    for (const std::size_t k : load.members) force[k] += f;
  }
  for (const auto& src : sources) {
    const Real a = src.spec.amplitude * wavelet_value(src.spec.wavelet, t);
    if (a == 0) continue;
    for (const auto& [k, q] : src.members) force[k] += a * src.g[q];
  }

  // Symplectic Euler (eq. 39-40, 45-46); clamped particles are attached to the tank: they follow its
  // prescribed roll about the pivot (at rest without a tank motion), or to the moving wall their clamp reaches into.
  Real v2_max = 0;
  const auto [tank_theta, tank_omega] = tank.at(t + dt);
  for (std::size_t b = 0; b < clamp_motion.size(); ++b)
    if (clamp_motion[b].moving()) {
      clamp_state[b] = clamp_motion[b].at(t + dt);
      clamp_rotation[b] = clamp_motion[b].rotation(t + dt);
    }
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(local[k]);
    if (p.clamped[i] && clamp_motion[p.body[i]].moving()) {
      const WallMotionState& m = clamp_state[p.body[i]];
      p.position[i] = m.place((*f_x0)[i]);
      p.velocity[i] = m.velocity_of((*f_x0)[i]);
      (*f_theta)[i] = clamp_rotation[p.body[i]].log();
      (*f_omega)[i] = m.spin;
      continue;
    }
    if (p.clamped[i]) {
      p.position[i] = tank.place((*f_x0)[i], tank_theta);
      p.velocity[i] = tank.velocity_at(p.position[i], tank_omega);
      (*f_theta)[i] = tank.rotation_at(tank_theta).log();
      (*f_omega)[i] = tank.spin(tank_omega);
      continue;
    }
    const MaterialConstants& m = material_of(i);
    p.velocity[i] += (dt / m.mass) * force[k];
    p.position[i] += dt * p.velocity[i];
    (*f_omega)[i] += (dt / m.inertia) * torque[k];
    (*f_theta)[i] = (Rotation::from_vector(dt * (*f_omega)[i]) * rotation_of(i)).log();  // eq. 46
    v2_max = std::max(v2_max, p.velocity[i].squaredNorm());
  }
  // The step's totals in one collective (a sub-step does little work between its collectives): bonds broken
  // and contacts summed, the largest speed.
  if (n_ranks() > 1) {
    const double mine[3] = {static_cast<double>(counts[0]), static_cast<double>(counts[1]), v2_max};
    std::vector<double> all(3 * static_cast<std::size_t>(n_ranks()));
    MPI_Allgather(mine, 3, MPI_DOUBLE, all.data(), 3, MPI_DOUBLE, comm);
    counts[0] = counts[1] = 0;
    for (std::size_t q = 0; q < all.size(); q += 3) {
      counts[0] += static_cast<unsigned long long>(all[q]);
      counts[1] += static_cast<unsigned long long>(all[q + 1]);
      v2_max = std::max(v2_max, all[q + 2]);
    }
  }
  n_broken += counts[0];
  report.n_broken = n_broken;
  report.n_contacts = counts[1];
  report.max_speed = std::sqrt(v2_max);
  return report;
}

void SolidSolver::Impl::compute_fragments() {
  // Connected components of the intact bonds: union-find over this rank's particles, labels = smallest
  // global id of a component; across ranks the ghosts' labels are exchanged until no label changes.
  sync();
  const std::size_t nl = p.size();
  std::vector<std::size_t> parent(nl);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](std::size_t a) {
    while (parent[a] != a) {
      parent[a] = parent[parent[a]];
      a = parent[a];
    }
    return a;
  };
  for (std::size_t k = 0; k < n(); ++k)
    for (std::size_t b = b_off[k]; b < b_off[k + 1]; ++b) {
      if (!b_intact[b]) continue;
      const std::size_t ra = find(static_cast<std::size_t>(local[k])), rb = find(static_cast<std::size_t>(b_j[b]));
      if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
    }
  auto& label = *f_label;
  std::vector<GlobalId> root_label(nl, std::numeric_limits<GlobalId>::max());
  for (const LocalIndex li : local) {
    const auto i = static_cast<std::size_t>(li);
    auto& l = root_label[find(i)];
    l = std::min(l, p.global_id[i]);
  }
  for (int round = 0;; ++round) {
    for (std::size_t k = 0; k < n(); ++k) {
      const auto i = static_cast<std::size_t>(local[k]);
      label[i] = static_cast<Real>(root_label[find(i)]);
    }
    if (n_ranks() == 1) break;
    exchange({internal::label});
    int changed = 0;
    for (const LocalIndex li : local) {
      const auto i = static_cast<std::size_t>(li);
      if (i < p.n_owned()) continue;
      auto& l = root_label[find(i)];
      const auto g = static_cast<GlobalId>(label[i]);
      if (g < l) {
        l = g;
        changed = 1;
      }
    }
    allreduce(&changed, 1, MPI_INT, MPI_MAX);
    if (!changed) break;
    if (round > 100000) throw std::logic_error("solid: the fragment labels do not settle");
  }
  // Each fragment has one particle whose global id is its label.
  unsigned long long n_roots = 0;
  for (std::size_t k = 0; k < n(); ++k) {
    const auto i = static_cast<std::size_t>(local[k]);
    n_roots += static_cast<GlobalId>(label[i]) == p.global_id[i];
  }
  allreduce(&n_roots, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM);
  n_frag = n_roots;
}

// ---------------------------------------------------------------------------------------------

SolidSolver::SolidSolver(const SolidSetup& setup, ParticleSet& particles) : impl_(std::make_unique<Impl>(setup, particles, nullptr)) {}
SolidSolver::SolidSolver(const SolidSetup& setup, ParticleSet& particles, Distribution& distribution)
    : impl_(std::make_unique<Impl>(setup, particles, &distribution)) {}
SolidSolver::~SolidSolver() = default;

void SolidSolver::set_damping(const Real beta) {
  if (!(beta >= 0)) throw std::invalid_argument("SolidSolver::set_damping: beta must be >= 0");
  impl_->damping_time = impl_->c_p_max > 0 ? beta * impl_->dp / impl_->c_p_max : 0;
}

Real SolidSolver::damping_time() const { return impl_->damping_time; }

Real SolidSolver::stable_dt() const {
  if (!(impl_->c_p_max > 0)) throw std::logic_error("SolidSolver::stable_dt: no solid particles");
  return impl_->dt_factor * impl_->dp / impl_->c_p_max;
}

void SolidSolver::set_interface_load(const SolidLoadData& data) {
  ParticleSet& p = impl_->p;
  auto& load = *impl_->f_load;
  if (data.force.size() != data.ids.size())
    throw std::logic_error(fmt::format("SolidSolver::set_interface_load: {} ids and {} forces", data.ids.size(),
                                       data.force.size()));
  const std::vector<LocalIndex> at =
      owned_in_order(p, ParticleKind::solid, data.ids, "SolidSolver::set_interface_load");
  for (std::size_t k = 0; k < at.size(); ++k) load[static_cast<std::size_t>(at[k])] = data.force[k];
}

SolidStepReport SolidSolver::advance(const Real t, const Real dt) {
  if (!(dt > 0)) throw std::invalid_argument(fmt::format("SolidSolver::advance: dt = {} must be positive", dt));
  return impl_->advance(t, dt);
}

void SolidSolver::set_output_directory(const std::string& dir, const bool append) {
  impl_->out_dir = dir;
  impl_->csv_started = append;
}

void SolidSolver::save_state(BinaryWriter& out) const {
  // Everything else the solid knows of a particle is in its particle arrays (reference position, broken bonds,
  // surface flag, rotation), which the checkpoint holds by global id.
  out.section("solid");
  out.u64(impl_->n_broken);
}

bool SolidSolver::load_state(BinaryReader& in) {
  in.expect_section("solid");
  impl_->n_broken = in.u64("the broken-bond count");
  impl_->seen_gid.clear();  // the particle set was replaced: renew the structure at the next use
  return true;
}

void SolidSolver::store_iteration_checkpoint() { impl_->n_broken_stored = impl_->n_broken; }

void SolidSolver::reload_iteration_checkpoint() {
  impl_->n_broken = impl_->n_broken_stored;
  impl_->seen_gid.clear();  // the particle arrays were put back: renew the structure at the next use
}

void SolidSolver::prepare_output(const Real t) {
  Impl& m = *impl_;
  m.compute_fragments();  // (renews owners, ghosts and bonds first)
  m.compute_rotations();
  const std::size_t ns = m.n();
  // Strain tensor eps_i = sym(d/n0_i sum w0/|r0| u_ij (x) e_ij): its trace is eq. 30.
  std::vector<Mat> grad(ns, Mat::Zero());
  m.for_each_intact_bond([&](std::size_t k, std::size_t, std::size_t, std::size_t b, const Vec& r, const Vec& u) {
    grad[k] += m.b_wr[b] * u * (r / r.norm()).transpose();
  });
  // Fragment numbers: labels ordered by size (largest first), ties by label (the fragment's first particle).
  struct Sums {
    Real count = 0, mass = 0;
    Vec mx = Vec::Zero();
    Real body = 0;
  };
  std::map<GlobalId, Sums> local_sums;
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(m.local[k]);
    auto& s = local_sums[static_cast<GlobalId>((*m.f_label)[i])];
    const Real mass = m.material_of(i).mass;
    s.count += 1;
    s.mass += mass;
    s.mx += mass * m.p.position[i];
    s.body = m.p.body[i];
  }
  const int width = 3 + dim + 1;
  std::vector<double> mine;
  for (const auto& [l, s] : local_sums) {
    mine.push_back(static_cast<double>(l));
    mine.push_back(s.count);
    mine.push_back(s.mass);
    for (int a = 0; a < dim; ++a) mine.push_back(s.mx[a]);
    mine.push_back(s.body);
  }
  const std::vector<double> all = m.comm != MPI_COMM_NULL ? all_gather(m.comm, mine) : mine;
  std::map<GlobalId, Sums> sums;
  for (std::size_t q = 0; q < all.size(); q += width) {
    auto& s = sums[static_cast<GlobalId>(all[q])];
    s.count += all[q + 1];
    s.mass += all[q + 2];
    for (int a = 0; a < dim; ++a) s.mx[a] += all[q + 3 + static_cast<std::size_t>(a)];
    s.body = all[q + 3 + dim];
  }
  std::vector<std::pair<GlobalId, Sums>> order(sums.begin(), sums.end());
  std::stable_sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.second.count > b.second.count; });
  std::map<GlobalId, int> number;
  for (std::size_t f = 0; f < order.size(); ++f) number[order[f].first] = static_cast<int>(f);
  m.n_frag = order.size();

  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(m.local[k]);
    const Impl::MaterialConstants& mc = m.material_of(i);
    const Mat g = dim * (*m.f_inv_n0)[i] * grad[k];
    const Mat eps = 0.5 * (g + g.transpose());
    const Real tr_eps = eps.trace();
    const Mat sigma = 2 * mc.mu * eps + mc.lambda * tr_eps * Mat::Identity();
#if MPSFSI_DIM == 2
    const Real szz = m.plane_stress ? 0.0 : mc.lambda * tr_eps;  // out of plane: plane stress, plane strain
    const Real shear2 = sigma(0, 1) * sigma(0, 1);
#else
    const Real szz = sigma(2, 2);
    const Real shear2 = sigma(0, 1) * sigma(0, 1) + sigma(0, 2) * sigma(0, 2) + sigma(1, 2) * sigma(1, 2);
#endif
    const Real sxx = sigma(0, 0), syy = sigma(1, 1);
    (*m.f_von_mises)[i] = std::sqrt(0.5 * ((sxx - syy) * (sxx - syy) + (syy - szz) * (syy - szz) + (szz - sxx) * (szz - sxx)) +
                                    3 * shear2);
    (*m.f_pressure)[i] = -mc.lambda * tr_eps;
    (*m.f_displacement)[i] = m.p.position[i] - (*m.f_x0)[i];
    (*m.f_fragment)[i] = number[static_cast<GlobalId>((*m.f_label)[i])];
  }
  const bool writes = m.dist == nullptr || m.dist->rank() == 0;
  if (m.out_dir.empty() || !m.breakable || !writes) return;
  // fragments.csv (bodies that can break): one row per fragment and output time.
  const std::string path = m.out_dir + "/fragments.csv";
  std::ofstream out(path, m.csv_started ? std::ios::app : std::ios::trunc);
  check_written(out, path, "fragment table");
  if (!m.csv_started) out << (dim == 2 ? "time,n_fragments,fragment,body,particles,mass,centroid_x,centroid_y\n"
                                        : "time,n_fragments,fragment,body,particles,mass,centroid_x,centroid_y,centroid_z\n");
  m.csv_started = true;
  for (std::size_t f = 0; f < order.size(); ++f) {
    const auto& s = order[f].second;
    const Vec c = s.mx / s.mass;
    out << fmt::format("{:.9g},{},{},{},{},{:.9g}", t, m.n_frag, f, m.p.bodies[static_cast<std::size_t>(s.body)].name,
                       static_cast<std::size_t>(s.count), s.mass);
    for (int a = 0; a < dim; ++a) out << fmt::format(",{:.9g}", c[a]);
    out << "\n";
  }
  out.flush();
  check_written(out, path, "fragment table");
}

SolidDiagnostics SolidSolver::diagnostics() const {
  Impl& m = *impl_;
  m.sync();
  m.compute_rotations();
  SolidDiagnostics d;
  const std::size_t ns = m.n();
  std::vector<Real> tr(ns, 0);
  // Each bond is seen from both ends: half of its energy at each.
  m.for_each_intact_bond([&](std::size_t k, std::size_t, std::size_t, std::size_t b, const Vec& r, const Vec& u) {
    tr[k] += m.b_vi[b] * u.dot(r) / r.norm();
    d.strain += 0.25 * m.b_k[b] * u.squaredNorm();
  });
  const auto& surface = *m.f_surface;
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(m.local[k]);
    const Impl::MaterialConstants& mc = m.material_of(i);
    const Vec& x = m.p.position[i];
    const Vec& v = m.p.velocity[i];
    const Angular omega = (*m.f_omega)[i];
    d.strain += 0.5 * m.volume * mc.lambda * tr[k] * tr[k];
    d.momentum += mc.mass * v;
    d.angular_momentum += mc.mass * cross(x, v) + mc.inertia * omega;
    d.kinetic += 0.5 * mc.mass * v.squaredNorm();
#if MPSFSI_DIM == 2
    d.rotational += 0.5 * mc.inertia * omega * omega;
#else
    d.rotational += 0.5 * mc.inertia * omega.squaredNorm();
#endif
    // Contact energy: U(d) = k l0 (l0 ln(l0/d) - (l0 - d)) for unbonded surface pairs closer than l0, half at each end.
    if (surface[i] == 0) continue;
    for (const LocalIndex lj : m.local) {
      const auto j = static_cast<std::size_t>(lj);
      if (j == i || surface[j] == 0) continue;
      const Real dist = (m.p.position[j] - x).norm();
      if (dist >= m.dp || m.bonded(k, lj)) continue;
      d.contact += 0.5 * m.k_contact * m.dp * (m.dp * std::log(m.dp / dist) - (m.dp - dist));
    }
  }
  constexpr int n_ang = n_angular;
  constexpr int o = dim + n_ang;
  Real sums[o + 4];
  Real* const ang = angular_data(d.angular_momentum);
  for (int a = 0; a < dim; ++a) sums[a] = d.momentum[a];
  for (int a = 0; a < n_ang; ++a) sums[dim + a] = ang[a];
  sums[o] = d.kinetic;
  sums[o + 1] = d.rotational;
  sums[o + 2] = d.strain;
  sums[o + 3] = d.contact;
  m.allreduce(sums, o + 4, MPI_DOUBLE, MPI_SUM);
  for (int a = 0; a < dim; ++a) d.momentum[a] = sums[a];
  for (int a = 0; a < n_ang; ++a) ang[a] = sums[dim + a];
  d.kinetic = sums[o];
  d.rotational = sums[o + 1];
  d.strain = sums[o + 2];
  d.contact = sums[o + 3];
  return d;
}

std::size_t SolidSolver::n_fragments() const { return impl_->n_frag; }

Real SolidSolver::min_distance_between_fragments() const {
  Impl& m = *impl_;
  m.compute_fragments();
  const auto& label = *m.f_label;
  std::vector<Vec> x;
  for (const LocalIndex li : m.local) x.push_back(m.p.position[static_cast<std::size_t>(li)]);
  NeighbourList nl;
  build_neighbour_list(x, m.dp, nl);
  Real best = std::numeric_limits<Real>::infinity();
  for (std::size_t k = 0; k < m.n(); ++k) {  // row k: owned particle k
    const auto i = static_cast<std::size_t>(m.local[k]);
    for (std::size_t q = nl.begin(k); q < nl.end(k); ++q) {
      const auto j = static_cast<std::size_t>(m.local[static_cast<std::size_t>(nl.index[q])]);
      if (label[i] != label[j]) best = std::min(best, (x[static_cast<std::size_t>(nl.index[q])] - x[k]).norm());
    }
  }
  m.allreduce(&best, 1, MPI_DOUBLE, MPI_MIN);
  return best;
}

std::size_t SolidSolver::n_bonds() const {
  const Impl& m = *impl_;
  unsigned long long n = 0;
  for (std::size_t k = 0; k < m.n(); ++k)
    for (std::size_t b = m.b_off[k]; b < m.b_off[k + 1]; ++b)
      n += m.b_intact[b] && m.p.global_id[static_cast<std::size_t>(m.local[k])] < m.p.global_id[static_cast<std::size_t>(m.b_j[b])];
  m.allreduce(&n, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM);
  return n;
}

std::size_t SolidSolver::memory_bytes() const {
  const Impl& m = *impl_;
  const std::size_t ns = m.n();
  const std::size_t nb = m.b_j.size();
  const std::size_t per_particle = 2 * sizeof(LocalIndex) + sizeof(Vec) + sizeof(Angular) + sizeof(Real) + 1 +
                                   2 * sizeof(Real) + sizeof(GlobalId) + sizeof(Vec) + sizeof(LocalIndex);
  const std::size_t per_bond = sizeof(LocalIndex) + sizeof(Vec) + 5 * sizeof(Real) + 2;
  return ns * per_particle + nb * per_bond + (ns + 1) * sizeof(std::size_t) + m.s_nl.memory_bytes();
}

}  // namespace mpsfsi
