// Explicit rotation-aware elastic MPS with brittle fracture and contact (seed 004 §4.2, §4.4;
// seed 000 §2). Implements, per bond (i, j) of the reference configuration:
//   u_ij = r_ij - R((theta_i + theta_j)/2) r0_ij                     (seed 004 eq. 25; seed 000 eq. 7-10)
//   normal / shear parts and strains, sigma = 2 mu eps, tau = 2 mu gamma   (eq. 26-29, 31-32)
//   tr(eps)_i = d/n0_i sum u_ij . r_ij / (|r0_ij| |r_ij|) w0_ij, p_i = -lambda tr(eps)_i  (eq. 30, 33)
//   rho dv/dt = 2d/n0 sum (sigma_ij + tau_ij)/|r0| w0 - 2d/n0 sum p_ij e_ij/|r0| w0    (eq. 36-38)
//   I domega/dt = 1/2 sum r_ij x F_ij, F_ij the shear force, I = rho l0^(2+d)/6         (eq. 41-44)
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
// * cos and sin of the mean angle come from per-particle half-angle cos/sin by the addition theorem:
//   two trig calls per particle per step instead of two per bond.
// * Bonds are stored once per pair (j > i) in CSR with r0, 1/|r0|, w0/|r0| and the pair stiffness.
#include "solid/solid_solver.hpp"

#include "core/binary_io.hpp"
#include "core/files.hpp"
#include "core/kernel.hpp"
#include "core/neighbours.hpp"
#include "core/operators.hpp"
#include "core/rotation.hpp"
#include "solid/sources.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <fstream>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace mpsfsi {

namespace {

constexpr Real n_c = 0.5;  ///< surface threshold of eq. 48

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

struct SolidSolver::Impl {
  struct Load {
    SolidLoadSpec spec;
    std::vector<LocalIndex> members;  ///< solid indices
  };

  ParticleSet& p;
  Real dp = 0;
  Real volume = 0;        ///< l0^d: particle volume per unit thickness
  Real n0_lattice = 0;
  Real n_max = 0;         ///< n_i^max of eq. 48
  Real k_contact = 0;     ///< contact spring [N/m per unit thickness]
  Real dt_factor = 0.2;
  Real c_p_max = 0;
  Real damping_time = 0;    ///< Kelvin-Voigt retardation time eta of the bonds [s] (0: none)
  bool plane_stress = false;
  Vec gravity = Vec::Zero();
  TankMotion tank;          ///< prescribed tank roll; clamped particles follow it
  std::size_t n_total = 0;  ///< particle count at the last gather (a change means pid must be re-resolved)

  // Per solid particle k (particle index pid[k]).
  std::vector<LocalIndex> pid;
  std::vector<GlobalId> gid;  ///< global id of solid k (to follow a reordering of the particle set)
  std::vector<Vec> x, v, x0, force;
  std::vector<Rotation> rotation;     ///< each particle's rotation (eq. 45-46; a scalar angle in 2D)
  std::vector<Angular> omega, torque;  ///< angular velocity and torque (the z component in 2D)
  std::vector<Real> tr, pn, ch, sh;
  std::vector<Real> mass, inertia, lambda, mu, inv_n0, n_now, eps_max;
  std::vector<std::uint8_t> clamped, surface;

  // Bonds, once per pair (i < j), CSR over i.
  std::vector<std::size_t> b_off;
  std::vector<LocalIndex> b_j;
  std::vector<Vec> b_r0;
  std::vector<Real> b_inv_r0, b_wr, b_k, b_w0;
  /// Volumetric strain weights of the bond on each side: tr(eps)_i = sum_j b_vi un_ij (eq. 30): d/n0_i w0/|r0|,
  /// or with solid.volumetric_strain = corrected w0/|r0| e0^T B_i e0 (exact trace of a linear field).
  std::vector<Real> b_vi, b_vj;
  std::vector<std::uint8_t> b_intact;
  std::vector<Vec> b_ce;  ///< scratch: V d w0/|r0| e_ij of this step
  std::size_t n_broken = 0;

  std::vector<Load> loads;

  struct Source {
    SourceSpec spec;
    std::vector<LocalIndex> members;  ///< solid indices
    std::vector<Vec> g;               ///< force per unit amplitude s(t) (solid/sources.hpp)
  };
  std::vector<Source> sources;

  // Contact scratch.
  std::vector<Vec> s_x;
  std::vector<LocalIndex> s_k;
  NeighbourList s_nl;
  CellGrid s_grid;

  // Output.
  std::vector<Real>* f_theta = nullptr;
  std::vector<Real>* f_omega = nullptr;
  std::vector<Real>* f_von_mises = nullptr;
  std::vector<Real>* f_pressure = nullptr;
  std::vector<Real>* f_fragment = nullptr;
  std::vector<Real>* f_surface = nullptr;
  std::vector<Vec>* f_displacement = nullptr;
  std::vector<Vec>* f_load = nullptr;
  std::vector<int> fragment;  ///< per solid particle, at the last prepare_output
  std::size_t n_frag = 0;
  std::vector<int> uf_parent;
  std::string out_dir;
  bool csv_started = false;
  bool breakable = false;  ///< some material has a fracture strain: fragments.csv is written

  Impl(const SolidSetup& setup, ParticleSet& particles);
  std::size_t n() const { return pid.size(); }
  void gather();
  void scatter();
  void compute_half_angles();
  /// Relative displacement of bond b = (i, j) with the pair's mean rotation removed,
  /// u_ij = r_ij - R((theta_i + theta_j)/2) r0_ij (eq. 25), from the half-angle cosines and sines.
  Vec bond_displacement(const std::size_t i, const std::size_t j, const std::size_t b) const {
    const Real c = ch[i] * ch[j] - sh[i] * sh[j];  // cos((theta_i + theta_j)/2)
    const Real s = sh[i] * ch[j] + ch[i] * sh[j];  // sin((theta_i + theta_j)/2)
    const Vec r0 = b_r0[b];
    const Vec r = x[j] - x[i];
    return Vec(r[0] - (c * r0[0] - s * r0[1]), r[1] - (s * r0[0] + c * r0[1]));
  }
  /// Call f(i, j, b, r_ij, u_ij) for every intact bond b = (i, j), each pair once (not the hot step loop,
  /// which also breaks bonds).
  template <class F>
  void for_each_intact_bond(F&& f) const {
    for (std::size_t i = 0; i < n(); ++i)
      for (std::size_t b = b_off[i]; b < b_off[i + 1]; ++b) {
        if (!b_intact[b]) continue;
        const auto j = static_cast<std::size_t>(b_j[b]);
        f(i, j, b, Vec(x[j] - x[i]), bond_displacement(i, j, b));
      }
  }
  /// b_vi, b_vj: d/n0_i w0/|r0| (eq. 30 with the n0 of solid.normalisation) or, `corrected`, the weights
  /// w0/|r0| e0^T B_i e0 with B_i such that sum_j w0 (e0^T B_i e0) e0 e0^T = I: then sum_j b_vi un_ij is the
  /// trace of any linear displacement field also where the neighbourhood is truncated (a free surface);
  /// in the interior of the lattice B_i = d/n0 I, the same as eq. 30.
  void set_volumetric_weights(bool corrected);
  /// Index of the bond (i, j) in the CSR, or npos.
  std::size_t find_bond(LocalIndex i, LocalIndex j) const;
  void contact_forces(std::size_t& n_contacts);
  void compute_fragments();
  SolidStepReport advance(Real t, Real dt);
};

SolidSolver::Impl::Impl(const SolidSetup& setup, ParticleSet& particles) : p(particles) {
  const SolidParameters& solid = setup.parameters;
  dp = setup.dp;
  volume = std::pow(dp, dim);
  const Real re = solid.re * dp;
  n0_lattice = lattice_constants(dp, re).n0;
  dt_factor = solid.dt_factor;
  plane_stress = solid.plane_stress;
  gravity = setup.gravity;
  tank = make_tank_motion(setup.tank_motion);
  n_total = p.size();
  const SolidNormalisation norm = solid.normalisation;

  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::solid) {
      pid.push_back(static_cast<LocalIndex>(i));
      gid.push_back(p.global_id[i]);
    }
  const std::size_t ns = n();

  f_theta = &p.add_scalar_field("rotation");
  f_omega = &p.add_scalar_field("angular_velocity");
  f_von_mises = &p.add_scalar_field("von_mises");
  f_pressure = &p.add_scalar_field("solid_pressure");
  f_fragment = &p.add_scalar_field("fragment", -1);
  f_surface = &p.add_scalar_field(solid_fields::surface);
  f_displacement = &p.add_vector_field("displacement");
  f_load = &p.add_vector_field(solid_fields::load);

  x.resize(ns);
  v.resize(ns);
  x0.resize(ns);
  force.assign(ns, Vec::Zero());
  rotation.resize(ns);
  for (auto* a : {&omega, &torque, &tr, &pn, &ch, &sh, &mass, &inertia, &lambda, &mu, &inv_n0, &n_now, &eps_max})
    a->assign(ns, 0);
  clamped.assign(ns, 0);
  surface.assign(ns, 0);
  fragment.assign(ns, 0);
  uf_parent.resize(ns);

  std::vector<LameConstants> lame;
  for (const auto& m : setup.materials) lame.push_back(lame_constants(m, solid));
  Real mu_max = 0;
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(pid[k]);
    const int mat = p.material[i];
    if (mat < 0 || mat >= static_cast<int>(setup.materials.size()))
      throw SetupError(fmt::format("{}: solid particle {} has no solid material", setup.origin, p.global_id[i]));
    const auto& m = setup.materials[static_cast<std::size_t>(mat)];
    x0[k] = p.position[i];
    mass[k] = m.rho * volume;
    inertia[k] = m.rho * volume * dp * dp / 6;  // eq. 44
    lambda[k] = lame[static_cast<std::size_t>(mat)].lambda;
    mu[k] = lame[static_cast<std::size_t>(mat)].mu;
    mu_max = std::max(mu_max, mu[k]);
    c_p_max = std::max(c_p_max, p_wave_speed(m, solid));
    eps_max[k] = m.fracture_strain ? *m.fracture_strain : std::numeric_limits<Real>::infinity();
    clamped[k] = p.clamped[i];
    if (!(lambda[k] + 2 * mu[k] > 0) || !(mu[k] > 0))
      throw SetupError(fmt::format("{}: solid material '{}': expected mu > 0 and lambda + 2 mu > 0 (check vp > sqrt(2) vs)",
                                  setup.origin, m.name));
  }
  breakable = std::any_of(eps_max.begin(), eps_max.end(), [](const Real e) { return std::isfinite(e); });

  // Initial spin: a body given an angular velocity rotates rigidly, so its particles spin with it.
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(pid[k]);
    const std::string& body = p.bodies[p.body[i]].name;
    for (const auto& b : setup.spins)
      if (b.body == body && !clamped[k]) omega[k] = b.angular_velocity;
    (*f_omega)[i] = omega[k];
    (*f_theta)[i] = 0;
  }

  // Bonds: reference neighbours within re of the same body (eq. 25, r0 and w0 fixed).
  NeighbourList nl;
  build_neighbour_list(x0, re, nl);
  std::vector<Real> n0(ns, 0);
  b_off.assign(ns + 1, 0);
  for (std::size_t i = 0; i < ns; ++i) {
    b_off[i] = b_j.size();
    const auto body_i = p.body[static_cast<std::size_t>(pid[i])];
    const auto same_body = [&](const std::size_t j) { return p.body[static_cast<std::size_t>(pid[j])] == body_i; };
    // The pair loop of the operator layer: n0_i is eq. 8's number density over the bonds.
    for_each_pair(x0, nl, re, i, same_body, [&](const std::size_t j, const Vec& r0, Real, const Real w0) {
      n0[i] += w0;
      if (j < i) return;
      b_j.push_back(static_cast<LocalIndex>(j));
      b_r0.push_back(r0);
      b_inv_r0.push_back(1 / r0.norm());
      b_wr.push_back(w0 / r0.norm());
      b_w0.push_back(w0);
    });
  }
  b_off[ns] = b_j.size();
  n_max = 0;
  for (std::size_t i = 0; i < ns; ++i) {
    n_max = std::max(n_max, n0[i]);
    const Real n0_used = norm == SolidNormalisation::particle ? n0[i] : norm == SolidNormalisation::lattice ? n0_lattice : 0.5 * (n0[i] + n0_lattice);
    inv_n0[i] = n0_used > 0 ? 1 / n0_used : 0;
    n_now[i] = n0[i];
  }
  n_max = std::max(n_max, n0_lattice);
  for (std::size_t i = 0; i < ns; ++i) {
    surface[i] = n0[i] < n_max - n_c;
    (*f_surface)[static_cast<std::size_t>(pid[i])] = surface[i];
  }
  b_k.resize(b_j.size());
  for (std::size_t i = 0; i < ns; ++i) {
    for (std::size_t b = b_off[i]; b < b_off[i + 1]; ++b) {
      const auto j = static_cast<std::size_t>(b_j[b]);
      assert(j > i && "bonds are stored once, at the smaller index");
      assert(mu[i] == mu[j] && "bonds join particles of one body and material");
      // Force on i: V 2d/n0 2 mu u/|r0| w0/|r0| with 1/n0 -> (1/n0_i + 1/n0_j)/2 (eq. 36-37).
      b_k[b] = volume * 2 * dim * mu[i] * b_wr[b] * b_inv_r0[b] * (inv_n0[i] + inv_n0[j]);
    }
  }
  set_volumetric_weights(solid.volumetric_strain == VolumetricStrain::corrected);
  b_intact.assign(b_j.size(), 1);
  b_ce.assign(b_j.size(), Vec::Zero());

  // Contact spring: contact_stiffness times the stiffness of a nearest-neighbour bond of the stiffest material.
  k_contact = solid.contact_stiffness * volume * 4 * dim * mu_max * weight(dp, re) / (dp * dp * n0_lattice);

  for (const auto& ls : setup.loads) {
    Load load{ls, {}};
    bool body_found = false;
    for (std::size_t k = 0; k < ns; ++k) {
      const auto i = static_cast<std::size_t>(pid[k]);
      if (p.bodies[p.body[i]].name != ls.body) continue;
      body_found = true;
      if (ls.region.contains(x0[k])) load.members.push_back(static_cast<LocalIndex>(k));
    }
    if (!body_found)
      throw SetupError(fmt::format("{}: solid load '{}': body '{}' is not a solid body with particles", setup.origin,
                                  ls.name, ls.body));
    if (load.members.empty())
      throw SetupError(fmt::format("{}: solid load '{}': no particle of body '{}' lies in its region", setup.origin,
                                  ls.name, ls.body));
    const Real norm = ls.direction.norm();
    if (!(norm > 0)) throw SetupError(fmt::format("{}: solid load '{}': direction must be non-zero", setup.origin, ls.name));
    load.spec.direction /= norm;
    loads.push_back(std::move(load));
  }
  // Seismic sources: the force pattern over the body's particles around the source point.
  for (const auto& ss : setup.sources) {
    std::vector<std::size_t> candidates;
    for (std::size_t k = 0; k < ns; ++k)
      if (p.bodies[p.body[static_cast<std::size_t>(pid[k])]].name == ss.body) candidates.push_back(k);
    if (candidates.empty())
      throw SetupError(fmt::format("{}: source '{}': body '{}' is not a solid body with particles", setup.origin, ss.name,
                                  ss.body));
    const VectorStencil st = source_stencil(ss, x0, candidates);
    Source src{ss, {}, st.value};
    for (const std::size_t k : st.index) src.members.push_back(static_cast<LocalIndex>(k));
    sources.push_back(std::move(src));
  }
  s_x.reserve(ns);
  s_k.reserve(ns);
}

void SolidSolver::Impl::gather() {
  // Another module may have reordered the particle set (ParticleSet::reorder) or removed particles
  // (the fluid removes particles that leave the domain; solid particles are never removed): follow
  // the global ids. Bonds refer to solid indices k, which do not change.
  bool moved = p.size() != n_total;
  n_total = p.size();
  for (std::size_t k = 0; k < n() && !moved; ++k) moved = p.global_id[static_cast<std::size_t>(pid[k])] != gid[k];
  if (moved) {
    for (std::size_t k = 0; k < n(); ++k) {
      pid[k] = p.local_index(gid[k]);
      if (pid[k] < 0) throw std::logic_error("SolidSolver: a solid particle disappeared from the particle set");
    }
  }
  for (std::size_t k = 0; k < n(); ++k) {
    const auto i = static_cast<std::size_t>(pid[k]);
    x[k] = p.position[i];
    v[k] = p.velocity[i];
    rotation[k] = Rotation((*f_theta)[i]);
    omega[k] = (*f_omega)[i];
  }
}

void SolidSolver::Impl::scatter() {
  for (std::size_t k = 0; k < n(); ++k) {
    const auto i = static_cast<std::size_t>(pid[k]);
    p.position[i] = x[k];
    p.velocity[i] = v[k];
    (*f_theta)[i] = rotation[k].angle();
    (*f_omega)[i] = omega[k];
    (*f_surface)[i] = surface[k];  // eq. 48, current after every step (the coupling reads it)
  }
}

void SolidSolver::Impl::compute_half_angles() {
  for (std::size_t k = 0; k < n(); ++k) {
    ch[k] = std::cos(0.5 * rotation[k].angle());
    sh[k] = std::sin(0.5 * rotation[k].angle());
  }
}

void SolidSolver::Impl::set_volumetric_weights(const bool corrected) {
  const std::size_t nb = b_j.size();
  b_vi.resize(nb);
  b_vj.resize(nb);
  for (std::size_t i = 0; i < n(); ++i)
    for (std::size_t b = b_off[i]; b < b_off[i + 1]; ++b) {
      b_vi[b] = dim * inv_n0[i] * b_wr[b];
      b_vj[b] = dim * inv_n0[static_cast<std::size_t>(b_j[b])] * b_wr[b];
    }
  if (!corrected) return;
  // Per particle: the 3 x 3 system for (B_xx, B_yy, B_xy) of sum_j w0 (e^T B e) e e^T = I over its bonds.
  std::vector<Eigen::Matrix3d> m(n(), Eigen::Matrix3d::Zero());
  const auto add = [&](const std::size_t k, const Real w, const Vec& e) {
    const Eigen::Vector3d row(e[0] * e[0], e[1] * e[1], e[0] * e[1]);  // e e^T as (xx, yy, xy)
    const Eigen::Vector3d col(e[0] * e[0], e[1] * e[1], 2 * e[0] * e[1]);  // e^T B e = col . (Bxx, Byy, Bxy)
    m[k] += w * row * col.transpose();
  };
  for (std::size_t i = 0; i < n(); ++i)
    for (std::size_t b = b_off[i]; b < b_off[i + 1]; ++b) {
      const Vec e = b_r0[b] * b_inv_r0[b];
      add(i, b_w0[b], e);
      add(static_cast<std::size_t>(b_j[b]), b_w0[b], e);
    }
  std::vector<Eigen::Vector3d> coef(n());
  std::vector<std::uint8_t> ok(n(), 0);
  for (std::size_t k = 0; k < n(); ++k) {
    const Eigen::FullPivLU<Eigen::Matrix3d> lu(m[k]);
    // Too few bond directions (a particle with bonds along one line): keep eq. 30.
    if (lu.rank() < 3 || !(std::abs(lu.determinant()) > 1e-9 * std::pow(m[k].norm(), 3))) continue;
    coef[k] = lu.solve(Eigen::Vector3d(1, 1, 0));
    ok[k] = 1;
  }
  const auto weight_of = [&](const std::size_t k, const std::size_t b, const Real fallback) {
    if (!ok[k]) return fallback;
    const Vec e = b_r0[b] * b_inv_r0[b];
    return b_wr[b] * (coef[k][0] * e[0] * e[0] + coef[k][1] * e[1] * e[1] + 2 * coef[k][2] * e[0] * e[1]);
  };
  for (std::size_t i = 0; i < n(); ++i)
    for (std::size_t b = b_off[i]; b < b_off[i + 1]; ++b) {
      b_vi[b] = weight_of(i, b, b_vi[b]);
      b_vj[b] = weight_of(static_cast<std::size_t>(b_j[b]), b, b_vj[b]);
    }
}

std::size_t SolidSolver::Impl::find_bond(const LocalIndex a, const LocalIndex b) const {
  const auto lo = static_cast<std::size_t>(std::min(a, b));
  const LocalIndex hi = std::max(a, b);
  for (std::size_t q = b_off[lo]; q < b_off[lo + 1]; ++q)
    if (b_j[q] == hi) return q;
  return std::numeric_limits<std::size_t>::max();
}

void SolidSolver::Impl::contact_forces(std::size_t& n_contacts) {
  s_x.clear();
  s_k.clear();
  for (std::size_t k = 0; k < n(); ++k) {
    if (!surface[k]) continue;
    s_x.push_back(x[k]);
    s_k.push_back(static_cast<LocalIndex>(k));
  }
  if (s_x.size() < 2) return;
  // Guard the cell grid: a blown-up state (dt too large) would ask for an absurd number of cells.
  Vec lo = s_x[0], hi = s_x[0];
  for (const Vec& y : s_x) {
    if (!y.allFinite()) throw std::runtime_error("solid: a surface particle has a non-finite position; the run went unstable (reduce dt)");
    lo = lo.cwiseMin(y);
    hi = hi.cwiseMax(y);
  }
  const Vec cells = (hi - lo) / dp + Vec::Ones();
  if (cells[0] * cells[1] > 16.0 * static_cast<Real>(n()) + 4e6)
    throw std::runtime_error(fmt::format(
        "solid: the surface particles spread over {:.3g} x {:.3g} m ({:.3g} contact cells of side dp for {} particles); "
        "the run went unstable (reduce dt) or fragments flew too far apart (shrink the domain)",
        hi[0] - lo[0], hi[1] - lo[1], cells[0] * cells[1], n()));
  build_neighbour_list(s_x, dp, s_nl, s_grid);
  const Real d_min = 0.05 * dp;
  for (std::size_t a = 0; a < s_x.size(); ++a) {
    for (std::size_t q = s_nl.begin(a); q < s_nl.end(a); ++q) {
      const auto c = static_cast<std::size_t>(s_nl.index[q]);
      if (c <= a) continue;
      const LocalIndex i = s_k[a], j = s_k[c];
      const std::size_t b = find_bond(i, j);
      if (b != std::numeric_limits<std::size_t>::max() && b_intact[b]) continue;  // adjacent on one surface
      const Vec r = x[static_cast<std::size_t>(j)] - x[static_cast<std::size_t>(i)];
      const Real d = r.norm();
      // Direction: along r; for coincident particles fall back to the reference direction.
      Vec e = d > 1e-12 * dp ? Vec(r / d) : Vec(x0[static_cast<std::size_t>(j)] - x0[static_cast<std::size_t>(i)]);
      if (d <= 1e-12 * dp) e = e.norm() > 0 ? Vec(e.normalized()) : Vec(1, 0);
      // Repulsion k (l0 - d) l0/d: linear near contact, stiffening without bound as d -> 0.
      const Real mag = k_contact * (dp - d) * dp / std::max(d, d_min);
      force[static_cast<std::size_t>(i)] -= mag * e;
      force[static_cast<std::size_t>(j)] += mag * e;
      ++n_contacts;
    }
  }
}

SolidStepReport SolidSolver::Impl::advance(const Real t, const Real dt) {
  gather();
  compute_half_angles();
  const std::size_t ns = n();
  std::fill(force.begin(), force.end(), Vec::Zero());
  std::fill(torque.begin(), torque.end(), 0.0);
  std::fill(tr.begin(), tr.end(), 0.0);

  // Pass 1: bond displacement (eq. 25-29), fracture (eq. 47), volumetric strain sums (eq. 30),
  // normal + shear forces (eq. 36-37) and the torques that cancel the shear couple (eq. 41-43).
  const Real vd = volume * dim;
  for (std::size_t i = 0; i < ns; ++i) {
    const Vec xi = x[i];
    Vec fi = Vec::Zero();
    Real ti = 0, tri = 0;
    for (std::size_t b = b_off[i]; b < b_off[i + 1]; ++b) {
      if (!b_intact[b]) continue;
      const auto j = static_cast<std::size_t>(b_j[b]);
      const Vec r = x[j] - xi;
      const Vec u = bond_displacement(i, j, b);
      const Real inv_r = 1 / std::sqrt(r.squaredNorm());
      const Real un = u.dot(r) * inv_r;  // |(u_ij)_n| with sign (eq. 26)
      if (un * b_inv_r0[b] > eps_max[i]) {  // eq. 47: the bond breaks for good
        b_intact[b] = 0;
        ++n_broken;
        n_now[i] -= b_w0[b];
        n_now[j] -= b_w0[b];
        assert(n_now[i] > -1e-9 && n_now[j] > -1e-9 && "n_i is a sum over intact bonds");
        if (n_now[i] < n_max - n_c) surface[i] = 1;  // eq. 48, irreversible
        if (n_now[j] < n_max - n_c) surface[j] = 1;
        continue;
      }
      tri += b_vi[b] * un;
      tr[j] += b_vj[b] * un;
      Vec fe = b_k[b] * u;  // sigma_ij + tau_ij term, force on i
      // Kelvin-Voigt bond damping: eta times the bond's normal stretch rate, same stiffness; rigid
      // translation and rotation give no normal stretch rate and are not damped.
      if (damping_time > 0) fe += (b_k[b] * damping_time * (v[j] - v[i]).dot(r) * inv_r * inv_r) * r;
      fi += fe;
      force[j] -= fe;
      const Real tq = 0.5 * cross(r, fe);  // -1/2 M_ij, M_ij = -r_ij x F_ij (eq. 42-43), same for j
      ti += tq;
      torque[j] += tq;
      b_ce[b] = (vd * b_wr[b] * inv_r) * r;
    }
    force[i] += fi;
    torque[i] += ti;
    tr[i] += tri;
  }
  // Pressure p_i = -lambda tr(eps)_i (eq. 30, 33); pn holds p_i / n0_i.
  for (std::size_t i = 0; i < ns; ++i) pn[i] = -lambda[i] * tr[i] * inv_n0[i];
  // Pass 2: pressure term (eq. 38) in the pair form -V d w0/|r0| (p_i/n0_i + p_j/n0_j) e_ij. With the eq. 30
  // weights this is the gradient of sum_i V lambda tr_i^2 / 2. With corrected weights (exact trace) the force
  // keeps these weights: at a flat free surface the pressure then balances the bonds' normal force exactly
  // when sigma_yy = 0 (a uniform traction-free strain is an equilibrium, docs/validation.md), at the price of
  // a pressure force that is no longer exactly an energy gradient near surfaces.
  for (std::size_t i = 0; i < ns; ++i) {
    Vec fi = Vec::Zero();
    const Real pi = pn[i];
    for (std::size_t b = b_off[i]; b < b_off[i + 1]; ++b) {
      if (!b_intact[b]) continue;
      const auto j = static_cast<std::size_t>(b_j[b]);
      const Vec g = (pi + pn[j]) * b_ce[b];
      fi -= g;
      force[j] += g;
    }
    force[i] += fi;
  }

  SolidStepReport report;
  contact_forces(report.n_contacts);

  // External loads: gravity, the coupling's per-particle force, pressure pulses, seismic sources.
  const bool has_gravity = gravity.squaredNorm() > 0;
  for (std::size_t k = 0; k < ns; ++k) {
    if (has_gravity) force[k] += mass[k] * gravity;
    force[k] += (*f_load)[static_cast<std::size_t>(pid[k])];
  }
  for (const auto& load : loads) {
    const Real arg = (t - load.spec.time) / load.spec.width;
    const Vec f = load.spec.peak * std::exp(-arg * arg) * std::pow(dp, dim - 1) * load.spec.direction;
    for (const auto k : load.members) force[static_cast<std::size_t>(k)] += f;
  }
  for (const auto& src : sources) {
    const Real a = src.spec.amplitude * wavelet_value(src.spec.wavelet, t);
    if (a == 0) continue;
    for (std::size_t q = 0; q < src.members.size(); ++q) force[static_cast<std::size_t>(src.members[q])] += a * src.g[q];
  }

  // Symplectic Euler (eq. 39-40, 45-46); clamped particles are attached to the tank: they follow its
  // prescribed roll about the pivot (at rest without a tank motion).
  Real v2_max = 0;
  const auto [tank_theta, tank_omega] = tank.at(t + dt);
  for (std::size_t k = 0; k < ns; ++k) {
    if (clamped[k]) {
      x[k] = tank.place(x0[k], tank_theta);
      v[k] = tank.velocity_at(x[k], tank_omega);
      rotation[k] = Rotation(tank_theta);
      omega[k] = tank_omega;
      continue;
    }
    v[k] += (dt / mass[k]) * force[k];
    x[k] += dt * v[k];
    omega[k] += (dt / inertia[k]) * torque[k];
    rotation[k] = Rotation::from_vector(dt * omega[k]) * rotation[k];  // eq. 46
    v2_max = std::max(v2_max, v[k].squaredNorm());
  }
  scatter();
  report.n_broken = n_broken;
  report.max_speed = std::sqrt(v2_max);
  return report;
}

void SolidSolver::Impl::compute_fragments() {
  const std::size_t ns = n();
  std::iota(uf_parent.begin(), uf_parent.end(), 0);
  const auto find = [&](int a) {
    while (uf_parent[static_cast<std::size_t>(a)] != a) {
      uf_parent[static_cast<std::size_t>(a)] = uf_parent[static_cast<std::size_t>(uf_parent[static_cast<std::size_t>(a)])];
      a = uf_parent[static_cast<std::size_t>(a)];
    }
    return a;
  };
  for (std::size_t i = 0; i < ns; ++i) {
    for (std::size_t b = b_off[i]; b < b_off[i + 1]; ++b) {
      if (!b_intact[b]) continue;
      const int ra = find(static_cast<int>(i)), rb = find(b_j[b]);
      if (ra != rb) uf_parent[static_cast<std::size_t>(std::max(ra, rb))] = std::min(ra, rb);
    }
  }
  // Roots in order of first particle; then label by size (largest first), ties by first particle.
  std::vector<int> root_label(ns, -1);
  std::vector<int> roots;
  std::vector<std::size_t> sizes;
  for (std::size_t i = 0; i < ns; ++i) {
    const auto r = static_cast<std::size_t>(find(static_cast<int>(i)));
    if (root_label[r] < 0) {
      root_label[r] = static_cast<int>(roots.size());
      roots.push_back(static_cast<int>(r));
      sizes.push_back(0);
    }
    fragment[i] = root_label[r];
    ++sizes[static_cast<std::size_t>(root_label[r])];
  }
  std::vector<int> order(roots.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return sizes[static_cast<std::size_t>(a)] > sizes[static_cast<std::size_t>(b)];
  });
  std::vector<int> rank(roots.size());
  for (std::size_t q = 0; q < order.size(); ++q) rank[static_cast<std::size_t>(order[q])] = static_cast<int>(q);
  for (std::size_t i = 0; i < ns; ++i) fragment[i] = rank[static_cast<std::size_t>(fragment[i])];
  n_frag = roots.size();
  assert(ns == 0 || sizes[static_cast<std::size_t>(order[0])] >= sizes[static_cast<std::size_t>(order.back())]);
}

// ---------------------------------------------------------------------------------------------

SolidSolver::SolidSolver(const SolidSetup& setup, ParticleSet& particles) : impl_(std::make_unique<Impl>(setup, particles)) {
  impl_->compute_fragments();
}
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

SolidStepReport SolidSolver::advance(const Real t, const Real dt) {
  if (!(dt > 0)) throw std::invalid_argument(fmt::format("SolidSolver::advance: dt = {} must be positive", dt));
  return impl_->advance(t, dt);
}

void SolidSolver::set_output_directory(const std::string& dir, const bool append) {
  impl_->out_dir = dir;
  impl_->csv_started = append;
}

void SolidSolver::save_state(BinaryWriter& out) const {
  const Impl& m = *impl_;
  out.section("solid");
  out.array(m.gid);
  out.array(m.b_intact);
  out.u64(m.n_broken);
  out.array(m.n_now);
  out.array(m.surface);
}

void SolidSolver::load_state(BinaryReader& in) {
  Impl& m = *impl_;
  in.expect_section("solid");
  const auto gid = in.array<GlobalId>("the solid particle ids");
  if (gid != m.gid)
    in.fail(fmt::format("the checkpoint's solid has {} particles, this case's {} (or other ones)", gid.size(), m.gid.size()));
  auto intact = in.array<std::uint8_t>("the bond flags");
  if (intact.size() != m.b_intact.size())
    in.fail(fmt::format("the checkpoint's solid has {} bonds, this case's {}", intact.size(), m.b_intact.size()));
  const std::size_t n_broken = in.u64("the broken-bond count");
  auto n_now = in.array<Real>("the number densities", m.n());
  auto surface = in.array<std::uint8_t>("the surface flags", m.n());
  m.b_intact.swap(intact);
  m.n_broken = n_broken;
  m.n_now.swap(n_now);
  m.surface.swap(surface);
  m.gather();  // the particle set was replaced: follow the global ids
  m.compute_fragments();
}

void SolidSolver::prepare_output(const Real t) {
  Impl& m = *impl_;
  m.gather();
  m.compute_half_angles();
  const std::size_t ns = m.n();
  // Strain tensor eps_i = sym(d/n0_i sum w0/|r0| u_ij (x) e_ij): its trace is eq. 30.
  std::vector<Mat> grad(ns, Mat::Zero());
  m.for_each_intact_bond([&](std::size_t i, std::size_t j, std::size_t b, const Vec& r, const Vec& u) {
    const Mat g = m.b_wr[b] * u * (r / r.norm()).transpose();
    grad[i] += g;
    grad[j] += g;  // u_ji (x) e_ji = u_ij (x) e_ij
  });
  m.compute_fragments();
  for (std::size_t k = 0; k < ns; ++k) {
    const auto i = static_cast<std::size_t>(m.pid[k]);
    const Mat g = dim * m.inv_n0[k] * grad[k];
    const Mat eps = 0.5 * (g + g.transpose());
    const Real tr_eps = eps.trace();
    const Mat sigma = 2 * m.mu[k] * eps + m.lambda[k] * tr_eps * Mat::Identity();
    const Real szz = m.plane_stress ? 0.0 : m.lambda[k] * tr_eps;
    const Real sxx = sigma(0, 0), syy = sigma(1, 1), sxy = sigma(0, 1);
    (*m.f_von_mises)[i] = std::sqrt(0.5 * ((sxx - syy) * (sxx - syy) + (syy - szz) * (syy - szz) + (szz - sxx) * (szz - sxx)) +
                                    3 * sxy * sxy);
    (*m.f_pressure)[i] = -m.lambda[k] * tr_eps;
    (*m.f_displacement)[i] = m.x[k] - m.x0[k];
    (*m.f_fragment)[i] = m.fragment[k];
    (*m.f_surface)[i] = m.surface[k];
  }
  if (m.out_dir.empty() || !m.breakable) return;
  // fragments.csv (bodies that can break): one row per fragment and output time.
  std::vector<Real> f_mass(m.n_frag, 0);
  std::vector<Vec> f_centroid(m.n_frag, Vec::Zero());
  std::vector<std::size_t> f_count(m.n_frag, 0);
  std::vector<int> f_body(m.n_frag, -1);
  for (std::size_t k = 0; k < ns; ++k) {
    const auto f = static_cast<std::size_t>(m.fragment[k]);
    f_mass[f] += m.mass[k];
    f_centroid[f] += m.mass[k] * m.x[k];
    ++f_count[f];
    if (f_body[f] < 0) f_body[f] = m.p.body[static_cast<std::size_t>(m.pid[k])];
  }
  const std::string path = m.out_dir + "/fragments.csv";
  std::ofstream out(path, m.csv_started ? std::ios::app : std::ios::trunc);
  check_written(out, path, "fragment table");
  if (!m.csv_started) out << "time,n_fragments,fragment,body,particles,mass,centroid_x,centroid_y\n";
  m.csv_started = true;
  for (std::size_t f = 0; f < m.n_frag; ++f) {
    const Vec c = f_centroid[f] / f_mass[f];
    out << fmt::format("{:.9g},{},{},{},{},{:.9g},{:.9g},{:.9g}\n", t, m.n_frag, f,
                       m.p.bodies[static_cast<std::size_t>(f_body[f])].name, f_count[f], f_mass[f], c[0], c[1]);
  }
  out.flush();
  check_written(out, path, "fragment table");
}

SolidDiagnostics SolidSolver::diagnostics() const {
  Impl& m = *impl_;
  m.gather();
  m.compute_half_angles();
  SolidDiagnostics d;
  const std::size_t ns = m.n();
  std::vector<Real> tr(ns, 0);
  m.for_each_intact_bond([&](std::size_t i, std::size_t j, std::size_t b, const Vec& r, const Vec& u) {
    const Real un = u.dot(r) / r.norm();
    tr[i] += m.b_vi[b] * un;
    tr[j] += m.b_vj[b] * un;
    d.strain += 0.5 * m.b_k[b] * u.squaredNorm();
  });
  for (std::size_t k = 0; k < ns; ++k) {
    const Real t = tr[k];
    d.strain += 0.5 * m.volume * m.lambda[k] * t * t;
    d.momentum += m.mass[k] * m.v[k];
    d.angular_momentum += m.mass[k] * cross(m.x[k], m.v[k]) + m.inertia[k] * m.omega[k];
    d.kinetic += 0.5 * m.mass[k] * m.v[k].squaredNorm();
    d.rotational += 0.5 * m.inertia[k] * m.omega[k] * m.omega[k];
  }
  // Contact energy: U(d) = k l0 (l0 ln(l0/d) - (l0 - d)) for unbonded surface pairs closer than l0.
  for (std::size_t i = 0; i < ns; ++i) {
    if (!m.surface[i]) continue;
    for (std::size_t j = i + 1; j < ns; ++j) {
      if (!m.surface[j]) continue;
      const Real dist = (m.x[j] - m.x[i]).norm();
      if (dist >= m.dp) continue;
      const std::size_t b = m.find_bond(static_cast<LocalIndex>(i), static_cast<LocalIndex>(j));
      if (b != std::numeric_limits<std::size_t>::max() && m.b_intact[b]) continue;
      d.contact += m.k_contact * m.dp * (m.dp * std::log(m.dp / dist) - (m.dp - dist));
    }
  }
  return d;
}

std::size_t SolidSolver::n_fragments() const { return impl_->n_frag; }

Real SolidSolver::min_distance_between_fragments() const {
  Impl& m = *impl_;
  m.gather();
  m.compute_fragments();
  NeighbourList nl;
  std::vector<Vec> x(m.n());
  for (std::size_t k = 0; k < m.n(); ++k) x[k] = m.p.position[static_cast<std::size_t>(m.pid[k])];
  build_neighbour_list(x, m.dp, nl);
  Real best = std::numeric_limits<Real>::infinity();
  for (std::size_t i = 0; i < m.n(); ++i)
    for (std::size_t q = nl.begin(i); q < nl.end(i); ++q) {
      const auto j = static_cast<std::size_t>(nl.index[q]);
      if (m.fragment[i] != m.fragment[j]) best = std::min(best, (x[j] - x[i]).norm());
    }
  return best;
}

std::size_t SolidSolver::n_bonds() const {
  return static_cast<std::size_t>(std::count(impl_->b_intact.begin(), impl_->b_intact.end(), std::uint8_t{1}));
}

std::size_t SolidSolver::memory_bytes() const {
  const Impl& m = *impl_;
  const std::size_t ns = m.n();
  const std::size_t nb = m.b_j.size();
  const std::size_t per_particle = sizeof(LocalIndex) + 4 * sizeof(Vec) + 14 * sizeof(Real) + 2 + sizeof(int) * 2 +
                                   sizeof(Vec) + sizeof(LocalIndex);  // + contact scratch
  const std::size_t per_bond = sizeof(LocalIndex) + 2 * sizeof(Vec) + 6 * sizeof(Real) + 1;
  return ns * per_particle + nb * per_bond + (ns + 1) * sizeof(std::size_t) + m.s_nl.memory_bytes();
}

}  // namespace mpsfsi
