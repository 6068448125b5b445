// Builds the core TankMotion from the case file's TankMotionSpec (header only, so that fluid/ and solid/,
// which do not link io/, can use it).
#pragma once

#include "core/tank_motion.hpp"
#include "io/case.hpp"

#include <utility>

namespace mpsfsi {

/// The tank motion of a case; a table is the one read and checked when the case was parsed.
inline TankMotion make_tank_motion(const TankMotionSpec& spec) {
  TankMotionParams q;
  q.pivot = spec.pivot;
  switch (spec.type) {
    case TankMotionType::none: return TankMotion();
    case TankMotionType::sine_roll:
      q.type = TankMotionParams::Type::sine_roll;
      q.amplitude = spec.amplitude;
      q.period = spec.period;
      break;
    case TankMotionType::table:
      q.type = TankMotionParams::Type::table;
      q.time = spec.time;
      q.angle = spec.angle;
      break;
  }
  return TankMotion(std::move(q));
}

}  // namespace mpsfsi
