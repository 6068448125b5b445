// A smooth start of a load (the case's gravity_ramp): the factor in [0, 1] that multiplies the load at time t.
#pragma once

#include "core/types.hpp"

#include <cmath>

namespace mpsfsi {

/// (1 - cos(pi t / ramp)) / 2 for 0 < t < ramp, 0 before, 1 after; 1 at every t when ramp <= 0 (no ramp).
/// Its derivative vanishes at both ends, so a load switched on with it starts no oscillation of a system
/// whose periods are much shorter than the ramp.
inline Real ramp_factor(const Real t, const Real ramp) {
  if (!(ramp > 0) || t >= ramp) return 1;
  if (t <= 0) return 0;
  return 0.5 * (1 - std::cos(pi * t / ramp));
}

}  // namespace mpsfsi
