// The structure of the solid (SolidSolver::Impl, solid/solid_solver_impl.hpp): its construction from the setup
// (the fields, the materials, the reference bonds with n0 of eq. 8 and the corrected strain weights, the surface
// flags of eq. 48, the contact spring, the loads and the seismic sources) and each rank's bond lists (CSR over
// its owned solid particles, in order of the partner's global id), renewed from the particle fields whenever the
// particle set changed.
#include "solid/solid_solver_impl.hpp"

#include "core/kernel.hpp"
#include "core/operators.hpp"
#include "core/text.hpp"
#include "solid/sources.hpp"

#include <Eigen/Dense>
#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace mpsfsi {

using solid_detail::n_c;
using solid_detail::n_sym;
namespace internal = solid_detail::internal;

namespace {

/// solid.normalisation = mean: n0 = a n_i^0 + (1 - a) n0_lattice. A face row parallel to a uniaxial stress
/// has the axial stiffness of an interior row for a = 0.46 in 2D (taken as 1/2) and a = 0.585 on a face,
/// 0.600 on an edge in 3D (re = 2.1; docs/validation.md, "Solid in 3D").
constexpr Real surface_blend = dim == 2 ? 0.5 : 0.6;

/// A symmetric dim x dim matrix by its entries: entry c is (sym_a[c], sym_b[c]), the diagonal first (internal::coef's
/// order).
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

}  // namespace mpsfsi
