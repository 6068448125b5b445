// Wall-clock timing of the phases of a step (the run summary's split and the solvers' phase times).
#pragma once

#include <chrono>

namespace mpsfsi {

using Clock = std::chrono::steady_clock;

/// Seconds of wall time since t0.
inline double seconds_since(const Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace mpsfsi
