// The pressure scheme of a fluid step (fluid.scheme, fluid/fluid_parameters.hpp FluidScheme): the rows of the
// pressure system and the correction that the pressure makes to the velocities and positions. Two strategies
// behind one interface: `standard` (seed 004 eq. 23 with the gradient of eq. 9 or 14-15,
// fluid/standard_scheme.cpp) and `projection` (the exact projection of the number density with its active set,
// fluid/projection_scheme.cpp). Internal to fluid/: FluidSolver calls these hooks in the order of
// docs/architecture.md, "One coupled time step".
#pragma once

#include "fluid/fluid_core.hpp"

#include <memory>

namespace mpsfsi::fluid_detail {

class PressureScheme {
 public:
  virtual ~PressureScheme() = default;

  /// The radius of the near list (the pairs the rows and the correction use) [m].
  virtual Real near_radius() const = 0;
  /// Whether the ghosts of this role need their near rows in the coming step (an owned row or correction reads
  /// their pairs); the owned particles always have theirs.
  virtual bool ghost_needs_row(Role role) const = 0;
  /// Whether every particle with a pressure row needs its pairs within re_laplacian (FluidCore::build_wide_list).
  virtual bool rows_need_wide_list() const = 0;
  /// How far from the fluid a wall or dummy particle can be and still change a row that is read, its own or
  /// another's (FluidCore::leave_out_far_walls) [m]; 0: every one takes part.
  virtual Real wall_reach() const { return 0; }
  /// The first step only, before the walls move in it: the initial state (the projection's references and
  /// start positions), with the near list of that state.
  virtual void initial_state(FluidStepReport&) {}
  /// Whether a particle flagged free-surface in the last step stays flagged (the active set's warm start).
  virtual bool keeps_surface() const { return false; }
  /// After the free-surface check, before its flags are refreshed at the ghosts.
  virtual void after_surface() {}
  /// After the flags are current at the ghosts, before the first assembly.
  virtual void prepare(Real /*dt*/, FluidStepReport&) {}
  /// The rows of FluidCore::sys and their right-hand side, after FluidCore::number_rows; called again after
  /// update_rows changed rows (the same rows, numbered once per step).
  virtual void assemble(Real dt) = 0;
  /// The pressure a free-surface row holds.
  virtual Real surface_value(std::size_t /*i*/) const { return 0; }
  /// Pressure solves of one step at most (an active set re-solves while its rows change).
  virtual int max_solves() const { return 1; }
  /// Updates the rows after a solve (the ghosts' pressures current); whether any changed on any rank.
  virtual bool update_rows(int /*solves*/, Real /*dt*/, FluidStepReport&) { return false; }
  /// After the last solve, the pressures current at the ghosts.
  virtual void after_solve(Real /*dt*/) {}
  /// The pressure's correction of the fluid particles' velocities and positions.
  virtual void correct(Real dt) = 0;
};

std::unique_ptr<PressureScheme> make_standard_scheme(FluidCore& core, const FluidParameters& parameters);
std::unique_ptr<PressureScheme> make_projection_scheme(FluidCore& core, const FluidParameters& parameters);

}  // namespace mpsfsi::fluid_detail
