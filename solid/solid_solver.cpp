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
//
// This file: the public SolidSolver, the material law and the step (advance). The state the solid's files
// share is SolidSolver::Impl (solid/solid_solver_impl.hpp); the construction and the bond lists are in
// solid/solid_structure.cpp, the contact and the fragments in solid/solid_fragments.cpp, the output fields and
// the diagnostics in solid/solid_output.cpp.
#include "solid/solid_solver_impl.hpp"

#include "core/binary_io.hpp"
#include "core/ramp.hpp"
#include "solid/sources.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mpsfsi {

using solid_detail::n_c;
namespace internal = solid_detail::internal;

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
