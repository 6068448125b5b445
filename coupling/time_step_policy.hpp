// The time step of a run (one part of the run loop, coupling/simulation.cpp): the fluid's stable dt, or the
// solid's in a run without fluid, clipped to the end time, and the solid's sub-cycles in a coupled run. Rank 0
// decides and every rank takes its step, so that all ranks advance alike.
#pragma once

#include "core/types.hpp"

#include <mpi.h>

#include <optional>
#include <string>

namespace mpsfsi {

class FluidSolver;
class SolidSolver;

/// One step as the policy decides it.
struct StepPlan {
  Real dt = 0;
  std::string limit;            ///< what set dt: a fluid limit ("cfl", "dt_max", ...), "solid stability", "fixed", "end time"
  int n_sub = 1;                ///< solid sub-steps per fluid step (coupled runs)
  bool subcycles_raised = false;  ///< the case's sub-cycles would exceed the solid's stable dt and were raised
  Real solid_stable_dt = 0;     ///< the solid's stable dt (coupled runs)
};

/// The case's controls of the step: end time, a fixed solid dt (runs without fluid), the requested sub-cycles
/// (0: auto).
struct TimeStepControls {
  Real end_time = 1;
  std::optional<Real> solid_dt;
  int subcycles = 1;
};

class TimeStepPolicy {
 public:
  TimeStepPolicy(const TimeStepControls& controls, MPI_Comm comm) : controls_(controls), comm_(comm) {}

  /// The step from time t (a collective: rank 0's plan is broadcast). `fluid` and `solid` may be null (a run
  /// without that part); the stable dt of each is that of its last step.
  StepPlan plan(Real t, const FluidSolver* fluid, const SolidSolver* solid) const;

 private:
  TimeStepControls controls_;
  MPI_Comm comm_;
};

}  // namespace mpsfsi
