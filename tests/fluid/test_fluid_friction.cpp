// Unit tests of the quasi-2D lateral-wall friction (fluid.lateral_walls): the decay rates of the two models,
// and the exact decay of a lone particle's velocity relative to the tank over one step, with the tank at
// rest and with the tank rolling.
#include "core/tank_motion.hpp"
#include "core/distribution.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"
#include "core/tank_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace mpsfsi;

namespace {

constexpr Real two_pi = 6.283185307179586;

/// One fluid particle far from everything (no neighbours: a free-surface row, p = 0), no gravity.
std::string lone_particle_case(const std::string& extra) {
  return "name: lone\ndescription: one particle\nsource: tests\ndp: 0.01\n"
         "domain: {min: [-1, -1], max: [2, 2]}\ntime: {end: 1, dt: 1.0e-3}\ngravity: [0, 0]\n"
         "materials:\n  oil: {type: fluid, rho: 900, nu: 5.0e-5}\n"
         "bodies:\n  - {name: drop, kind: fluid, material: oil, rectangle: {min: [0.5, 0.5], max: [0.51, 0.51]}}\n" +
         extra;
}

/// The lone particle's velocity after one step of dt from velocity v0 at time t.
Vec velocity_after_step(const CaseSpec& spec, const Vec& v0, const Real t, const Real dt) {
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  std::size_t i_fluid = p.size();
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::fluid) i_fluid = i;
  EXPECT_LT(i_fluid, p.size());
  EXPECT_EQ(p.n_of_kind(ParticleKind::fluid), 1u);
  p.velocity[i_fluid] = v0;
  Distribution self(MPI_COMM_SELF, {});
  FluidSolver fluid(fluid_setup(spec), p, self);
  fluid.advance(t, dt);
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::fluid) return p.velocity[i];
  return Vec::Constant(std::nan(""));
}

}  // namespace

TEST(LateralWallFriction, Rates) {
  LateralWallFriction w;
  EXPECT_EQ(lateral_wall_friction_rate(w, 1e-6), 0.0);  // off
  w.gap = 0.039;
  w.frequency = 0.8;
  EXPECT_DOUBLE_EQ(lateral_wall_friction_rate(w, 5e-5), std::sqrt(2 * 5e-5 * two_pi * 0.8) / 0.039);
  w.model = LateralWallModel::poiseuille;
  EXPECT_DOUBLE_EQ(lateral_wall_friction_rate(w, 5e-5), 12 * 5e-5 / (0.039 * 0.039));
  w.model = static_cast<LateralWallModel>(99);  // no such model
  EXPECT_THROW(lateral_wall_friction_rate(w, 5e-5), std::invalid_argument);
}

TEST(LateralWallFriction, LoneParticleDecaysExactly) {
  const CaseSpec spec = parse_case(lone_particle_case("fluid: {lateral_walls: {gap: 0.01, model: poiseuille}}\n"), "lone");
  const Real k = 12 * 5e-5 / (0.01 * 0.01);  // 6 1/s
  const Real dt = 1e-3;
  const Vec v0(0.3, -0.2);
  const Vec v1 = velocity_after_step(spec, v0, 0.0, dt);
  EXPECT_NEAR(v1[0], v0[0] * std::exp(-k * dt), 1e-15);
  EXPECT_NEAR(v1[1], v0[1] * std::exp(-k * dt), 1e-15);
  // Without friction the velocity is unchanged (no gravity, no neighbours, no pressure).
  const Vec v_free = velocity_after_step(parse_case(lone_particle_case(""), "lone"), v0, 0.0, dt);
  EXPECT_EQ(v_free, v0);
}

TEST(LateralWallFriction, RelativeToTheRollingTank) {
  // A tank (walls far from the particle) rolling about (0.3, 0): the particle's velocity relaxes towards the
  // tank's rigid velocity at its position at the end of the step.
  const std::string extra =
      "walls:\n  - {name: tank, type: box, rectangle: {min: [-0.5, -0.5], max: [1.5, 1.5]}, open_top: false}\n"
      "tank_motion: {type: sine_roll, pivot: [0.3, 0], amplitude_deg: 4, period: 1.2}\n"
      "fluid: {lateral_walls: {gap: 0.039}}\n";
  const CaseSpec spec = parse_case(lone_particle_case(extra), "lone");
  const Real k = std::sqrt(2 * 5e-5 * two_pi / 1.2) / 0.039;
  const Real t = 0.1, dt = 1e-3;
  const Vec v0(0.05, 0.02);
  const Vec v1 = velocity_after_step(spec, v0, t, dt);
  const TankMotion motion = make_tank_motion(spec.tank_motion);
  // The wall velocity is taken at the particle's position at the start of the step, with the tank's
  // angular velocity at the end of the step (where the walls are moved to).
  Vec x0 = Vec::Zero();
  const Scene scene = build_scene(spec);
  for (std::size_t i = 0; i < scene.particles.size(); ++i)
    if (scene.particles.kind[i] == ParticleKind::fluid) x0 = scene.particles.position[i];
  const Vec v_wall = motion.velocity_at(x0, motion.angular_velocity(t + dt));
  // v1 = v_wall + (v0 - v_wall) e^{-k dt}: solve for the implied v_wall.
  const Real decay = std::exp(-k * dt);
  const Vec implied = (v1 - decay * v0) / (1 - decay);
  EXPECT_GT(v_wall.norm(), 0.1);  // the tank does move there
  EXPECT_NEAR(implied[0], v_wall[0], 1e-9);
  EXPECT_NEAR(implied[1], v_wall[1], 1e-9);
}
