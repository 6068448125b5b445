// The explicit elastic solid of seed 004 §4.2/§4.4 and seed 000 §2 (rotation-aware MPS with brittle
// fracture and contact), as a participant of the run loop: the driver asks for a stable dt and
// advances it one sub-step at a time. External loads (e.g. from the fluid) arrive in the vector
// field "solid_load" (force per particle [N per unit thickness]).
#pragma once

#include "core/particles.hpp"
#include "io/case.hpp"

#include <memory>

namespace mpsfsi {

struct SolidStepReport {
  std::size_t n_broken = 0;    ///< bonds broken so far
  Real max_speed = 0;          ///< largest solid particle speed [m/s]
};

class SolidSolver {
 public:
  /// Builds the bonds (reference configuration) and registers the solid's fields on `particles`.
  SolidSolver(const CaseSpec& spec, ParticleSet& particles);
  ~SolidSolver();
  SolidSolver(const SolidSolver&) = delete;
  SolidSolver& operator=(const SolidSolver&) = delete;

  /// Stable explicit time step of the solid (the constant used is documented in the .cpp).
  Real stable_dt() const;
  /// One explicit step from t to t + dt (seed 004 eq. 25-46).
  SolidStepReport advance(Real t, Real dt);
  /// Called by the driver just before an output frame: refresh derived fields (stress, fragments).
  void prepare_output(Real t);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mpsfsi
