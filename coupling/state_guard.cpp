// The run's watch over its state after each step (coupling/state_guard.hpp).
#include "coupling/state_guard.hpp"

#include "core/text.hpp"
#include "coupling/simulation.hpp"
#include "solid/solid_solver.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace mpsfsi {

StateGuard::StateGuard(const CaseSpec& spec, const ParticleSet& particles, MPI_Comm comm)
    : spec_(spec), p_(particles), comm_(comm) {
  MPI_Comm_size(comm, &n_ranks_);
  for (const auto& m : spec.fluid_materials) fluid_limit_ = std::max(fluid_limit_, m.c);
  for (const auto& m : spec.solid_materials) solid_limit_.push_back(p_wave_speed(m, spec.solid));
  initial_fluid_ = fluid_per_body(false);  // the scene is whole on every rank here
}

void StateGuard::check(const std::size_t step, const Real t) const {
  for (std::size_t i = 0; i < p_.n_owned(); ++i) {
    const auto where = [&] {
      return fmt::format("particle {} ({} of body '{}') at {}", p_.global_id[i], to_string(p_.kind[i]),
                         p_.bodies[p_.body[i]].name, show_point(p_.position[i]));
    };
    if (!p_.position[i].allFinite() || !p_.velocity[i].allFinite())
      throw RunFailure(fmt::format("step {} (t = {:.6g} s): {} has a non-finite position or velocity; the run went "
                                   "unstable (reduce dt or the CFL number)",
                                   step, t, where()));
    const Real speed = p_.velocity[i].norm();
    if (p_.kind[i] == ParticleKind::fluid && fluid_limit_ > 0 && speed > fluid_limit_)
      throw RunFailure(fmt::format("step {} (t = {:.6g} s): {} moves at {:.4g} m/s, faster than the fluid's sound "
                                   "speed c = {:.4g} m/s: runaway velocity (reduce dt or the CFL number, or raise c)",
                                   step, t, where(), speed, fluid_limit_));
    if (p_.kind[i] == ParticleKind::solid) {
      const auto m = static_cast<std::size_t>(p_.material[i]);
      if (m < solid_limit_.size() && speed > solid_limit_[m])
        // A clamped particle moves with the tank: its speed is the prescribed motion's, not the solver's.
        throw RunFailure(
            p_.clamped[i] != 0
                ? fmt::format("step {} (t = {:.6g} s): {} is clamped and moves at {:.4g} m/s with the prescribed "
                              "tank motion, faster than the P-wave speed {:.4g} m/s of its material: the tank_motion "
                              "is too violent for the solid to follow (expected a motion whose wall speed stays well "
                              "below that speed: a smaller amplitude or a longer period)",
                              step, t, where(), speed, solid_limit_[m])
                : fmt::format("step {} (t = {:.6g} s): {} moves at {:.4g} m/s, faster than the P-wave speed "
                              "{:.4g} m/s of its material: runaway velocity (reduce the solid dt)",
                              step, t, where(), speed, solid_limit_[m]));
      if (!spec_.domain.contains(p_.position[i]))
        throw RunFailure(fmt::format("step {} (t = {:.6g} s): {} left the domain {}", step, t, where(),
                                     show_box(spec_.domain)));
    }
  }
}

std::vector<std::size_t> StateGuard::fluid_per_body(const bool over_ranks) const {
  std::vector<unsigned long long> n(p_.bodies.size(), 0);
  for (std::size_t i = 0; i < p_.n_owned(); ++i)
    if (p_.kind[i] == ParticleKind::fluid) ++n[p_.body[i]];
  if (over_ranks && n_ranks_ > 1)
    MPI_Allreduce(MPI_IN_PLACE, n.data(), static_cast<int>(n.size()), MPI_UNSIGNED_LONG_LONG, MPI_SUM, comm_);
  return {n.begin(), n.end()};
}

// A fluid body that lost more than fluid.max_loss of its particles through the domain's boundary stops the
// run: the fluid fell or was flung out, and what is left is not the case that was asked for.
void StateGuard::check_losses(const std::size_t step, const Real t, const Real dt, const std::string& limit) const {
  const std::vector<std::size_t> now = fluid_per_body(true);
  for (std::size_t b = 0; b < now.size(); ++b) {
    if (initial_fluid_[b] == 0) continue;
    const std::size_t lost = initial_fluid_[b] - std::min(now[b], initial_fluid_[b]);
    const Real share = static_cast<Real>(lost) / static_cast<Real>(initial_fluid_[b]);
    if (share > spec_.fluid.max_loss)
      throw RunFailure(fmt::format(
          "step {} (t = {:.6g} s): {} of the {} particles ({:.1f} %) of fluid body '{}' have left the domain "
          "{}, more than fluid.max_loss = {:g} %; the fluid fell or was flung out "
          "(dt {:.3g} s limited by {}: check time.dt_max, time.cfl and the gravity, and that the walls hold the "
          "fluid)",
          step, t, lost, initial_fluid_[b], 100 * share, p_.bodies[b].name, show_box(spec_.domain),
          100 * spec_.fluid.max_loss, dt, limit));
  }
}

// The copy costs about as much as a cheap solid step (docs/performance.md, ## Lamb's problem); the frame a
// failure writes is then at most k steps older than the failing step (its time is in the message).
void StateGuard::keep_last_good(const Real t, const std::size_t step) {
  const auto now = Clock::now();
  if (have_last_good_) step_seconds_ = std::chrono::duration<double>(now - last_step_start_).count();
  last_step_start_ = now;
  if (have_last_good_ && ++steps_since_copy_ < copy_every_) return;
  last_good_ = p_;
  last_good_t_ = t;
  last_good_step_ = step;
  have_last_good_ = true;
  steps_since_copy_ = 0;
  const double copy_seconds = seconds_since(now);
  last_step_start_ = Clock::now();  // the step's time without the copy
  if (step_seconds_ > 0)
    copy_every_ = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(copy_seconds / (0.02 * step_seconds_))));
  if (n_ranks_ > 1) {  // every rank copies at the same steps: a failure writes one state of all pieces
    unsigned long long every = copy_every_;
    MPI_Allreduce(MPI_IN_PLACE, &every, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, comm_);
    copy_every_ = every;
  }
}

}  // namespace mpsfsi
