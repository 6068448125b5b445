// The time control of a run (case file key `time`, filled by io/case_file.cpp): end time and a fixed or
// an adaptive (CFL) time step. Read by the fluid (fluid_stable_dt) and the run loop.
#pragma once

#include "core/types.hpp"

#include <optional>

namespace mpsfsi {

struct TimeSpec {
  Real end = 1;                 ///< end time [s]
  std::optional<Real> dt;       ///< fixed fluid time step [s], or
  std::optional<Real> cfl;      ///< Courant number C of seed 004 eq. 52 (adaptive dt)
  Real dt_max = 1e-3;           ///< upper bound of an adaptive dt [s]
};

}  // namespace mpsfsi
