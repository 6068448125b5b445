// The implementation of SolidSolver (solid/solid_solver.hpp): its state, SolidSolver::Impl, and the constants the
// solid's source files share. Internal to solid/ (included only by solid/*.cpp): solid/solid_solver.cpp holds the
// public class and the step, with the overview of the method; solid/solid_structure.cpp the construction and
// the bond lists; solid/solid_fragments.cpp the contact and the fragment labels; solid/solid_output.cpp the
// output fields and the diagnostics.
#pragma once

#include "solid/solid_solver.hpp"

#include "core/collectives.hpp"
#include "core/distribution.hpp"
#include "core/neighbours.hpp"
#include "core/particles.hpp"
#include "core/rotation.hpp"
#include "core/tank_motion.hpp"
#include "core/wall_motion.hpp"
#include "solid/solid_parameters.hpp"

#include <Eigen/Geometry>
#include <mpi.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

namespace mpsfsi {

namespace solid_detail {

inline constexpr Real n_c = 0.5;  ///< surface threshold of eq. 48
/// Entries of a symmetric dim x dim matrix, the diagonal first (internal::coef's order).
inline constexpr int n_sym = dim * (dim + 1) / 2;

/// The solid's internal per-particle fields (names starting with '_' are not written unless asked for). They
/// travel with a particle between ranks and into checkpoints: everything the solid knows of a particle.
namespace internal {
inline constexpr const char* x0 = "_solid_x0";            ///< reference position (the bonds' r0, eq. 25)
inline constexpr const char* inv_n0 = "_solid_inv_n0";    ///< 1 / n0_i of solid.normalisation
inline constexpr const char* n_bonds0 = "_solid_bonds0";  ///< bonds in the reference configuration
inline constexpr const char* broken = "_solid_broken";    ///< broken bonds: bit k for the lattice offset k (offset_slot)
inline constexpr const char* pn = "_solid_pn";            ///< p_i / n0_i of this step (eq. 33, 38)
inline constexpr const char* label = "_solid_label";      ///< fragment label (smallest global id of the fragment)
/// Corrected strain weights: the independent entries of the symmetric B_i, the diagonal first.
#if MPSFSI_DIM == 2
inline constexpr const char* coef[] = {"_solid_bxx", "_solid_byy", "_solid_bxy"};
#else
inline constexpr const char* coef[] = {"_solid_bxx", "_solid_byy", "_solid_bzz", "_solid_bxy", "_solid_bxz", "_solid_byz"};
#endif
}  // namespace internal

}  // namespace solid_detail

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
  std::vector<Real>* f_coef[solid_detail::n_sym] = {};
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
  /// The lowest rank's non-empty message on every rank (this process's alone without a distribution).
  std::string agreed(const std::string& local) const { return comm != MPI_COMM_NULL ? agreed_message(comm, local) : local; }
  /// Refreshes the solid ghosts' fields (the only ghosts the solid reads).
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

}  // namespace mpsfsi
