// The parameters of the fluid-solid coupling (docs/case-format.md `coupling`), owned by the coupling:
// the case parser (io/case_file.cpp) fills and checks them, the run loop reads them.
#pragma once

#include "core/types.hpp"

namespace mpsfsi {

struct CouplingParameters {
  int subcycles = 1;            ///< solid sub-steps per fluid step; 0 means "auto"
  Real solid_damping = 0.5;     ///< Kelvin-Voigt bond damping of the solid, eta = beta dp / c_p (SolidSolver::set_damping)
  Real load_relaxation = 1.0;   ///< FsiOptions::load_relaxation
};

}  // namespace mpsfsi
