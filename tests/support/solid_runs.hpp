// A helper of the solid's unit tests (2D and 3D): advance a solid and record its contacts. Header-only; tests
// include it as "support/solid_runs.hpp".
#pragma once

#include "solid/solid_solver.hpp"

#include <algorithm>
#include <limits>

namespace mpsfsi::test {

struct ContactRecord {
  std::size_t max_contacts = 0;                       ///< most unbonded pairs in contact in one step
  Real closest = std::numeric_limits<Real>::max();   ///< smallest distance between fragments seen [m]
};

/// n_steps steps of the solid's stable dt from t = 0; the distance between fragments is sampled every `every` steps.
inline ContactRecord advance_recording_contacts(SolidSolver& solid, const int n_steps, const int every = 1) {
  ContactRecord r;
  const Real dt = solid.stable_dt();
  for (int k = 0; k < n_steps; ++k) {
    r.max_contacts = std::max(r.max_contacts, solid.advance(k * dt, dt).n_contacts);
    if (k % every == 0) r.closest = std::min(r.closest, solid.min_distance_between_fragments());
  }
  return r;
}

/// The total energy's range over a run, and the time reached.
struct EnergyRecord {
  Real e_min = 0, e_max = 0;  ///< smallest and largest total energy sampled (the start included) [J]
  Real t = 0;                 ///< time at the end [s]
};

/// n_steps steps of the solid's stable dt from t = 0; the total energy is sampled every `every` steps.
inline EnergyRecord advance_recording_energy(SolidSolver& solid, const int n_steps, const int every) {
  EnergyRecord r;
  r.e_min = r.e_max = solid.diagnostics().total();
  const Real dt = solid.stable_dt();
  for (int step = 0; step < n_steps; ++step) {
    solid.advance(r.t, dt);
    r.t += dt;
    if (step % every == 0) {
      const Real e = solid.diagnostics().total();
      r.e_min = std::min(r.e_min, e);
      r.e_max = std::max(r.e_max, e);
    }
  }
  return r;
}

/// Mean velocity component `axis` of the particles of body `body`.
inline Real mean_velocity(const ParticleSet& p, const int body, const int axis) {
  Real sum = 0;
  int n = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.body[i] == body) sum += p.velocity[i][axis], ++n;
  return n ? sum / n : 0;
}

}  // namespace mpsfsi::test
