// The run's watch over its state after each step: non-finite positions or velocities, runaway speeds
// (faster than the fluid's sound speed or a solid's P-wave speed), solid particles leaving the domain, and
// fluid bodies that lose more than fluid.max_loss through the domain's boundary; and the copy of the last
// good state that a failed run writes as its last frame, taken every few steps at a bounded cost.
#pragma once

#include "core/particles.hpp"
#include "core/stopwatch.hpp"
#include "io/case.hpp"

#include <mpi.h>

#include <string>
#include <vector>

namespace mpsfsi {

class StateGuard {
 public:
  /// `particles` is the run's particle set, whole (before it is distributed): the fluid bodies' initial
  /// counts are taken from it.
  StateGuard(const CaseSpec& spec, const ParticleSet& particles, MPI_Comm comm);

  /// Throws RunFailure naming the first owned particle with a non-finite state, a runaway speed, or (a solid
  /// particle) outside the domain, after `step` at t.
  void check(std::size_t step, Real t) const;
  /// Throws RunFailure when a fluid body has lost more than fluid.max_loss of its particles (a collective);
  /// `dt` and `limit` are the step's, for the message.
  void check_losses(std::size_t step, Real t, Real dt, const std::string& limit) const;

  /// Before a step from (t, step): keeps a copy of the particle set as the last good state, every k steps,
  /// with k from the measured copy and step times such that the copies take at most ~2 % of the run (the same
  /// k on every rank, a collective).
  void keep_last_good(Real t, std::size_t step);
  const ParticleSet& last_good() const { return last_good_; }
  Real last_good_t() const { return last_good_t_; }
  std::size_t last_good_step() const { return last_good_step_; }

 private:
  /// Fluid particles of each body (by body index), over the ranks (sum) or on this rank.
  std::vector<std::size_t> fluid_per_body(bool over_ranks) const;

  const CaseSpec& spec_;
  const ParticleSet& p_;
  MPI_Comm comm_;
  int n_ranks_ = 1;
  /// Speed above which a particle counts as runaway: the fluid's sound speed c (the weakly compressible
  /// model is meaningless beyond Mach 1) and the solid's P-wave speed per solid material (particle speed =
  /// wave speed means strains of order one).
  Real fluid_limit_ = 0;
  std::vector<Real> solid_limit_;
  std::vector<std::size_t> initial_fluid_;  ///< fluid particles per body at the start of the case
  ParticleSet last_good_;
  Real last_good_t_ = 0;
  std::size_t last_good_step_ = 0;    ///< steps done when last_good_ was taken
  bool have_last_good_ = false;
  std::size_t copy_every_ = 1, steps_since_copy_ = 0;
  double step_seconds_ = 0;           ///< wall time of the last step (without the copy)
  Clock::time_point last_step_start_;
};

}  // namespace mpsfsi
