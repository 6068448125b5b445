// The participant API of a partitioned run, in the manner of preCICE's: what a coupling scheme and the run's
// checkpoints ask of each solver (the fluid, the solid) besides its typed interface data and its own step
// (FluidSolver::advance, SolidSolver::advance, each with its own report). The particle arrays are not part of it:
// the run keeps them (one shared particle set), so a participant saves only what it carries beside them.
#pragma once

#include "core/types.hpp"

namespace mpsfsi {

class BinaryReader;
class BinaryWriter;

class Participant {
 public:
  virtual ~Participant() = default;

  /// Largest admissible dt of the participant's own step now [s].
  virtual Real stable_dt() const = 0;

  /// An implicit coupling's window: keep what repeating the coming step needs besides the particle arrays
  /// (preCICE's "write iteration checkpoint"). One checkpoint is kept; a new call replaces it.
  virtual void store_iteration_checkpoint() = 0;
  /// Back to the last store_iteration_checkpoint (preCICE's "read iteration checkpoint"): with the particle
  /// arrays the caller puts back, the repeated step is bit for bit the first one given the same interface data.
  virtual void reload_iteration_checkpoint() = 0;

  /// Run checkpoints: what the participant carries from step to step besides the particle arrays, in its own
  /// named section. All ranks call both, in the same order.
  virtual void save_state(BinaryWriter& out) const = 0;
  /// Returns false when the coming steps cannot be bit for bit those of the original run (the continuation
  /// then agrees with it to the solvers' tolerances).
  virtual bool load_state(BinaryReader& in) = 0;
};

}  // namespace mpsfsi
