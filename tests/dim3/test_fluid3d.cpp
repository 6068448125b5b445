// Tests of the semi-implicit fluid in 3D (fluid/ with MPSFSI_DIM=3), in-process: water at
// rest in a box tank with dummy layers stays at rest and takes the hydrostatic pressure (the criteria of the
// 2D case cases/hydrostatic.yaml: largest speed below 1 % of sqrt(g h), pressure within 2 % of rho g (h - z)
// deeper than 3 dp, no particle lost) at 20 particles through the depth.
#include "core/distribution.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace mpsfsi {
namespace {

/// Water w x d x h at rest in an open box tank of the same footprint, gravity along -z.
CaseSpec hydrostatic_case(const Real dp, const Vec& water) {
  CaseSpec spec;
  spec.file = spec.name = "hydrostatic3d";
  spec.dp = dp;
  spec.domain = {Vec::Constant(-0.1), Vec(water[0] + 0.1, water[1] + 0.1, 2 * water[2] + 0.1)};
  spec.gravity = Vec(0, 0, -9.81);
  spec.time.cfl = 0.2;
  spec.time.dt_max = 1e-3;
  FluidMaterial m;
  m.name = "water";
  spec.fluid_materials.push_back(m);
  BodySpec b;
  b.name = "water";
  b.material = "water";
  b.rect = {Vec::Zero(), water};
  spec.bodies.push_back(b);
  WallSpec w;
  w.name = "tank";
  w.rect = {Vec::Zero(), Vec(water[0], water[1], 1.5 * water[2])};
  spec.walls.push_back(w);
  spec.fluid.tolerance = 1e-8;
  return spec;
}

TEST(Fluid3D, WaterAtRestStaysAtRestWithHydrostaticPressure) {
  const Real dp = 0.005, h = 0.1, g = 9.81;  // 20 x 10 x 20 particles
  const CaseSpec spec = hydrostatic_case(dp, Vec(0.1, 0.05, h));
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  Distribution dist{MPI_COMM_SELF, {}};
  FluidSolver fluid{fluid_setup(spec), p, dist};
  const std::size_t n_fluid = p.n_of_kind(ParticleKind::fluid);
  Real t = 0, v_max = 0;
  while (t < 1.0 - 1e-12) {
    const Real dt = std::min(fluid.stable_dt(), 1.0 - t);
    fluid.advance(t, dt);
    t += dt;
    if (t > 0.5)
      for (std::size_t i = 0; i < p.size(); ++i)
        if (p.kind[i] == ParticleKind::fluid) v_max = std::max(v_max, p.velocity[i].norm());
  }
  const auto& pressure = p.scalar_field("pressure");
  Real err_max = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.kind[i] != ParticleKind::fluid || h - p.position[i][2] < 3 * dp) continue;
    const Real exact = 1000 * g * (h - p.position[i][2]);
    const Real err = std::abs(pressure[i] - exact) / exact;
    err_max = std::max(err_max, err);
  }
  std::printf("3D hydrostatic, %zu fluid particles: largest speed over 0.5-1 s %.3e sqrt(g h), largest pressure error "
              "deeper than 3 dp %.3e\n", n_fluid, v_max / std::sqrt(g * h), err_max);
  EXPECT_EQ(p.n_of_kind(ParticleKind::fluid), n_fluid);
  EXPECT_LT(v_max, 0.01 * std::sqrt(g * h));
  EXPECT_LT(err_max, 0.02);
}

}  // namespace
}  // namespace mpsfsi
