// The parameters of the fluid-solid coupling (docs/case-format.md `coupling`), owned by the coupling:
// the case parser (io/case_file.cpp) fills and checks them, the run loop reads them.
#pragma once

#include "core/enum_names.hpp"
#include "core/types.hpp"

namespace mpsfsi {

/// The acceleration of an implicit coupling's iterations (coupling/acceleration.hpp).
enum class AccelerationKind { constant, aitken, iqn_ils };

inline const NameTable<AccelerationKind>& acceleration_kind_names() {
  static const NameTable<AccelerationKind> t = {
      {"constant", AccelerationKind::constant}, {"aitken", AccelerationKind::aitken}, {"iqn-ils", AccelerationKind::iqn_ils}};
  return t;
}

struct AccelerationParameters {
  AccelerationKind kind = AccelerationKind::iqn_ils;
  Real relaxation = 0.5;  ///< omega of `constant`, and of the first iteration of aitken and iqn-ils; in (0, 1]
  int reuse = 8;          ///< iqn-ils: past windows whose columns are kept, >= 0
  int max_columns = 100;  ///< iqn-ils: at most this many columns (the newest), >= 1
  Real filter = 1e-2;     ///< iqn-ils: a column's part orthogonal to the newer ones below filter |column| is dropped; [0, 1)
};

/// The coupling scheme (coupling/coupling_scheme.hpp).
enum class CouplingSchemeKind { explicit_scheme, implicit_scheme };

inline const NameTable<CouplingSchemeKind>& coupling_scheme_names() {
  static const NameTable<CouplingSchemeKind> t = {{"explicit", CouplingSchemeKind::explicit_scheme},
                                                  {"implicit", CouplingSchemeKind::implicit_scheme}};
  return t;
}

/// What a time window of the implicit scheme does when it has not converged in max_iterations.
enum class NonConvergence { proceed, stop };

inline const NameTable<NonConvergence>& non_convergence_names() {
  static const NameTable<NonConvergence> t = {{"continue", NonConvergence::proceed}, {"stop", NonConvergence::stop}};
  return t;
}

struct ImplicitCouplingParameters {
  AccelerationParameters acceleration;
  Real tolerance = 1e-3;     ///< converged when |H(d) - d| <= tolerance |H(d)|, d the solid's displacement over the step
  int max_iterations = 20;   ///< coupled steps per window at most
  NonConvergence on_max_iterations = NonConvergence::proceed;  ///< proceed (said once, counted) or stop the run
};

struct CouplingParameters {
  CouplingSchemeKind scheme = CouplingSchemeKind::explicit_scheme;
  ImplicitCouplingParameters implicit;
  int subcycles = 1;            ///< solid sub-steps per fluid step; 0 means "auto"
  Real solid_damping = 0.5;     ///< Kelvin-Voigt bond damping of the solid, eta = beta dp / c_p (SolidSolver::set_damping)
  Real load_relaxation = 1.0;   ///< FsiOptions::load_relaxation
};

}  // namespace mpsfsi
