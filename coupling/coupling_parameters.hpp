// The parameters of the fluid-solid coupling (docs/case-format.md `coupling`), owned by the coupling:
// the case parser (io/case_file.cpp) fills and checks them, the run loop reads them.
#pragma once

#include "core/types.hpp"

namespace mpsfsi {

/// The acceleration of an implicit coupling's iterations (coupling/acceleration.hpp).
enum class AccelerationKind { constant, aitken, iqn_ils };

struct AccelerationParameters {
  AccelerationKind kind = AccelerationKind::iqn_ils;
  Real relaxation = 0.5;  ///< omega of `constant`, and of the first iteration of aitken and iqn-ils; in (0, 1]
  int reuse = 8;          ///< iqn-ils: past windows whose columns are kept, >= 0
  int max_columns = 100;  ///< iqn-ils: at most this many columns (the newest), >= 1
  Real filter = 1e-2;     ///< iqn-ils: a column's part orthogonal to the newer ones below filter |column| is dropped; [0, 1)
};

struct CouplingParameters {
  int subcycles = 1;            ///< solid sub-steps per fluid step; 0 means "auto"
  Real solid_damping = 0.5;     ///< Kelvin-Voigt bond damping of the solid, eta = beta dp / c_p (SolidSolver::set_damping)
  Real load_relaxation = 1.0;   ///< FsiOptions::load_relaxation
};

}  // namespace mpsfsi
