// The builders of the solvers' setups from a case (io/case.hpp fluid_setup, solid_setup): the fluid
// and the solid see their parameters (fluid/fluid_parameters.hpp, solid/solid_parameters.hpp), not the case.
#include "io/case.hpp"

namespace mpsfsi {

FluidSetup fluid_setup(const CaseSpec& spec) {
  FluidSetup s;
  s.dp = spec.dp;
  s.gravity = spec.gravity;
  s.gravity_ramp = spec.gravity_ramp;
  s.domain = spec.domain;
  s.time = spec.time;
  s.materials = spec.fluid_materials;
  s.parameters = spec.fluid;
  s.tank_motion = spec.tank_motion;
  for (const auto& w : spec.walls)
    if (w.motion.moving()) s.wall_motions.emplace_back(w.name, w.motion);
  return s;
}

SolidSetup solid_setup(const CaseSpec& spec) {
  SolidSetup s;
  s.origin = spec.file;
  s.dp = spec.dp;
  s.gravity = spec.gravity;
  s.gravity_ramp = spec.gravity_ramp;
  s.materials = spec.solid_materials;
  s.parameters = spec.solid;
  s.tank_motion = spec.tank_motion;
  for (const auto& b : spec.bodies) s.spins.push_back({b.name, b.angular_velocity});
  for (const auto& b : spec.bodies)
    for (const auto& w : spec.walls)
      if (!b.clamp_wall.empty() && w.name == b.clamp_wall) s.clamp_motions.emplace_back(b.name, w.motion);
  s.loads = spec.solid_loads;
  s.sources = spec.sources;
  return s;
}

}  // namespace mpsfsi
