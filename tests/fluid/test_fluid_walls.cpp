// Walls hold water (FluidCore::keep_out_of_walls): water thrown into the corner of its tank, fast, with the
// default scheme and the standard one, in a fixed and in a tilted tank; after every step no fluid particle is
// inside a wall, and some were put back (the situation arises, so the test can fail). Built in 2D (tests/fluid)
// and in 3D (tests/dim3), on the hydrostatic case of each.
#include "core/distribution.hpp"
#include "core/tank_motion.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

using namespace mpsfsi;

namespace {

struct Thrown {
  std::size_t n_inside = 0;    ///< fluid particles found inside a wall after a step (all steps)
  std::size_t n_put_back = 0;  ///< the solver's count
  Real deepest = 0;            ///< the largest depth past the tank's inner faces [m]
};

/// The hydrostatic case (dp 1 cm) without gravity, its water thrown at `speed` into the tank's lower corner at the
/// origin (along the diagonal), `n_steps` steps of the fluid's stable dt (CFL 0.2). With `tilt`, the tank stands
/// turned by that angle [rad] about that corner (in 3D about the axis -y, as the 3D sloshing cases roll; a table
/// motion that holds it there).
Thrown throw_into_corner(const std::string& scheme, const Real speed, const int n_steps, const Real tilt = 0) {
  const std::string file = dim == 2 ? "/cases/hydrostatic.yaml" : "/cases/3d/hydrostatic.yaml";
  CaseSpec spec = load_case(std::string(MPSFSI_SOURCE_DIR) + file,
                            {"fluid.scheme=" + scheme, dim == 2 ? "gravity=[0,0]" : "gravity=[0,0,0]", "dp=0.01"});
  if (tilt != 0) {
    spec.tank_motion.type = TankMotionType::table;
#if MPSFSI_DIM == 3
    spec.tank_motion.axis = -Vec::UnitY();
#endif
    spec.tank_motion.pivot = Vec::Zero();
    spec.tank_motion.time = {0.0, 10.0};
    spec.tank_motion.angle = {tilt, tilt};
  }
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  const TankMotion motion = make_tank_motion(spec.tank_motion);
  // The walls are placed by the solver's first step; the water is placed here.
  const Vec towards_corner = motion.place(Vec::Constant(-1.0), tilt) - motion.place(Vec::Zero(), tilt);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.kind[i] != ParticleKind::fluid) continue;
    p.position[i] = motion.place(p.position[i], tilt);
    p.velocity[i] = speed * towards_corner.normalized();
  }
  Distribution dist{MPI_COMM_SELF, {}};
  FluidSolver fluid{fluid_setup(spec), p, dist};
  const Rect inner = spec.walls.at(0).rect;
  Thrown out;
  Real t = 0;
  for (int step = 0; step < n_steps; ++step) {
    const Real dt = fluid.stable_dt();
    const FluidStepReport r = fluid.advance(t, dt);
    t += dt;
    out.n_put_back += r.n_put_back;
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (p.kind[i] != ParticleKind::fluid) continue;
      const Vec x = motion.to_tank_frame(p.position[i], tilt);
      const Real depth = std::max((inner.lo - x).maxCoeff(), (x - inner.hi).maxCoeff());
      out.deepest = std::max(out.deepest, depth);
      if (depth > 1e-9) ++out.n_inside;
    }
  }
  return out;
}

}  // namespace

TEST(Walls, WaterThrownIntoACornerStaysInTheTank) {
  for (const char* scheme : {"projection", "standard"}) {
    const Thrown t = throw_into_corner(scheme, 3.0, 40);
    EXPECT_EQ(t.n_inside, 0u) << scheme << ": deepest " << t.deepest << " m";
    EXPECT_GT(t.n_put_back, 0u) << scheme;
  }
}

TEST(Walls, WaterThrownIntoTheCornerOfATiltedTankStaysInTheTank) {
  const Thrown t = throw_into_corner("projection", 3.0, 40, 0.3);
  EXPECT_EQ(t.n_inside, 0u) << "deepest " << t.deepest << " m";
  EXPECT_GT(t.n_put_back, 0u);
}
