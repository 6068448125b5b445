// The coupling schemes of a fluid-solid run, as objects in the manner of preCICE's coupling schemes. One call
// of advance() is one coupled time window from t to t + dt: the fluid step, the interface load (eq. 50) and the
// solid's sub-steps.
//   explicit  once: the fluid sees the solid at its mid-step prediction (x + u dt / 2, u the solid's mean
//             velocity of the last step), the solid takes the load of that fluid step.
//   implicit  fixed-point iterations on the solid's displacement d over the step: the fluid sees the solid
//             where it is at the step's end, x + d_k, with velocity d_k / dt (the pressure solve constrains the
//             fluid's density at the step's end), the solid takes that fluid step's load and answers with its
//             displacement H(d_k); the step is repeated from its saved start (save / restore of the particle
//             arrays and of the solvers' iteration state) with d_{k+1} from the acceleration
//             (coupling/acceleration.hpp) until |H(d_k) - d_k| <= tolerance |H(d_k)|. The first iterate is the
//             displacement at the solid's mean velocity of the last step.
// docs/architecture.md explains one coupled time step.
#pragma once

#include "core/types.hpp"
#include "coupling/acceleration.hpp"
#include "coupling/coupling_parameters.hpp"
#include "fluid/fluid_solver.hpp"

#include <mpi.h>

#include <array>
#include <memory>
#include <string>

namespace mpsfsi {

class BinaryReader;
class BinaryWriter;
class Distribution;
class FsiInterface;
class ParticleSet;
class SolidSolver;

/// What one coupled time window did.
struct CouplingWindow {
  FluidStepReport fluid;   ///< the fluid step of the accepted iteration
  int iterations = 1;      ///< coupled steps run (1 for the explicit scheme)
  bool converged = true;   ///< the implicit scheme met its tolerance within max_iterations
  Real residual = 0;       ///< the implicit scheme's last relative residual |H(d) - d| / |H(d)|
  double t_fluid = 0, t_solid = 0, t_coupling = 0;  ///< wall time of the participants and the interface [s]
};

/// The participants of a coupled run (one shared particle set; see coupling/fsi_interface.hpp).
struct CouplingParticipants {
  Real dp;  ///< the case's particle spacing (the scale of a displacement that counts as none)
  ParticleSet& particles;
  Distribution& distribution;
  FluidSolver& fluid;
  SolidSolver& solid;
  FsiInterface& interface;
  /// The fluid and the solid behind the participant API, in that order.
  std::array<Participant*, 2> participants() const;
};

class CouplingScheme {
 public:
  virtual ~CouplingScheme() = default;
  /// One coupled time window from t to t + dt with n_sub solid sub-steps. A collective.
  virtual CouplingWindow advance(Real t, Real dt, int n_sub) = 0;
  /// "explicit" or "implicit".
  virtual std::string name() const = 0;
  /// Checkpoints, between windows: the scheme and what it carries from window to window (the implicit scheme's
  /// acceleration). save_state is a collective that writes the same bytes on every rank.
  virtual void save_state(BinaryWriter& out) const;
  virtual void load_state(BinaryReader& in);
};

/// The scheme the parameters name. The implicit scheme's acceleration is the parameters' unless one is given.
std::unique_ptr<CouplingScheme> make_coupling_scheme(const CouplingParameters& parameters,
                                                     const CouplingParticipants& participants,
                                                     std::unique_ptr<Acceleration> acceleration = nullptr);

}  // namespace mpsfsi
