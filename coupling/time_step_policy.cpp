// The time step of a run (time_step_policy.hpp).
#include "coupling/time_step_policy.hpp"

#include "coupling/fsi_interface.hpp"
#include "fluid/fluid_solver.hpp"
#include "solid/solid_solver.hpp"

namespace mpsfsi {

StepPlan TimeStepPolicy::plan(const Real t, const FluidSolver* fluid, const SolidSolver* solid) const {
  StepPlan s;
  s.limit = "fixed";
  if (fluid) {
    s.dt = fluid->stable_dt(&s.limit);
  } else if (solid) {
    s.dt = controls_.solid_dt ? *controls_.solid_dt : solid->stable_dt();
    s.limit = controls_.solid_dt ? "fixed" : "solid stability";
  }
  if (controls_.end_time - t < s.dt) {
    s.dt = controls_.end_time - t;
    s.limit = "end time";
  }
  if (fluid && solid) {
    // The solid's limit: stable_dt() = solid.dt_factor dp / c_p. A requested N that would exceed it is raised.
    s.solid_stable_dt = solid->stable_dt();
    const SubcycleChoice choice = choose_subcycles(controls_.subcycles, s.dt, s.solid_stable_dt);
    s.n_sub = choice.n;
    s.subcycles_raised = choice.raised;
  }
  int n_ranks = 1;
  MPI_Comm_size(comm_, &n_ranks);
  if (n_ranks > 1) {  // rank 0 decides the step for all (and alone reports its limit)
    Real step[2] = {s.dt, static_cast<Real>(s.n_sub)};
    MPI_Bcast(step, 2, MPI_DOUBLE, 0, comm_);
    s.dt = step[0];
    s.n_sub = static_cast<int>(step[1]);
  }
  return s;
}

}  // namespace mpsfsi
