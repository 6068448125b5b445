// Walls hold water (FluidCore::keep_out_of_walls): water thrown into the corner of its tank, fast, with the
// default scheme and the standard one, in a fixed and in a tilted tank; after every step no fluid particle is
// inside a wall, and some were put back (the situation arises, so the test can fail); and water thrown at an
// obstacle whose faces are off the lattice stays out of it. Built in 2D (tests/fluid) and in 3D (tests/dim3), on
// the hydrostatic case of each.
#include "core/distribution.hpp"
#include "core/tank_motion.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

using namespace mpsfsi;

namespace {

struct Thrown {
  std::size_t n_inside = 0;    ///< fluid particles found inside a wall after a step (all steps)
  std::size_t n_put_back = 0;  ///< the solver's count
  Real deepest = 0;            ///< the largest depth past the tank's inner faces [m]
  Real closest = std::numeric_limits<Real>::infinity();  ///< the closest pair of fluid particles near a face [dp]
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
  // The tank stands tilted from the start: every particle turned, the walls' untilted positions kept as the
  // references their motion turns (the field a run's walls keep, "wall_reference"), so that the first step
  // starts from the tilted tank, as a run starts from its case's geometry.
  if (tilt != 0) {
    auto& reference = p.add_vector_field("wall_reference");
    for (std::size_t i = 0; i < p.size(); ++i) reference[i] = p.position[i];
    for (std::size_t i = 0; i < p.size(); ++i) p.position[i] = motion.place(p.position[i], tilt);
  }
  const Vec towards_corner = motion.place(Vec::Constant(-1.0), tilt) - motion.place(Vec::Zero(), tilt);
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::fluid) p.velocity[i] = speed * towards_corner.normalized();
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
    // Particles put back into a corner must not land on one point: the closest pair within dp of a face.
    std::vector<Vec> near_faces;
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (p.kind[i] != ParticleKind::fluid) continue;
      const Vec x = motion.to_tank_frame(p.position[i], tilt);
      if (std::min((x - inner.lo).minCoeff(), (inner.hi - x).minCoeff()) < spec.dp) near_faces.push_back(x);
    }
    for (std::size_t a = 0; a < near_faces.size(); ++a)
      for (std::size_t b = a + 1; b < near_faces.size(); ++b)
        out.closest = std::min(out.closest, (near_faces[a] - near_faces[b]).norm() / spec.dp);
  }
  return out;
}

}  // namespace

TEST(Walls, WaterThrownIntoACornerStaysInTheTank) {
  for (const char* scheme : {"projection", "standard"}) {
    const Thrown t = throw_into_corner(scheme, 3.0, 40);
    EXPECT_EQ(t.n_inside, 0u) << scheme << ": deepest " << t.deepest << " m";
    EXPECT_GT(t.n_put_back, 0u) << scheme;
    EXPECT_GT(t.closest, 0.01) << scheme << ": particles put back onto one point";
  }
}

namespace {

// The still-water case of this build's dimension (water 0.2 m deep in a box 0.2 m wide, 0.1 m deep in 3D).
std::string hydrostatic_file() {
  return std::string(MPSFSI_SOURCE_DIR) + (dim == 2 ? "/cases/hydrostatic.yaml" : "/cases/3d/hydrostatic.yaml");
}

// A `walls=` override: that case's open box 0.3 m high and a block `step` from x0 to x1, `height` high, standing
// on its floor across the whole depth.
std::string tank_with_block(const Real x0, const Real x1, const Real height) {
  if (dim == 2)
    return fmt::format("walls=[{{name: box, type: box, rectangle: {{min: [0, 0], max: [0.2, 0.3]}}, open_top: true}}, "
                       "{{name: step, type: block, rectangle: {{min: [{}, 0], max: [{}, {}]}}}}]", x0, x1, height);
  return fmt::format("walls=[{{name: box, type: box, rectangle: {{min: [0, 0, 0], max: [0.2, 0.1, 0.3]}}, open_top: true}}, "
                     "{{name: step, type: block, rectangle: {{min: [{}, 0, 0], max: [{}, 0.1, {}]}}}}]", x0, x1, height);
}

}  // namespace

// Two fluid particles inside the walls in the corner between the floor and a block standing on it (two wall
// bodies), behind both faces, are put back (a step so short that nothing else moves them): each goes back in
// front of the faces, and they stay apart, not both onto the corner (where the kernel's 1/r would throw them
// apart at the next step).
TEST(Walls, ParticlesPutBackIntoTheCornerOfTwoWallsStayApart) {
  CaseSpec spec = load_case(hydrostatic_file(), {dim == 2 ? "gravity=[0,0]" : "gravity=[0,0,0]", "dp=0.01",
                                                 "bodies.water.subtract=[step]", tank_with_block(0.1, 0.14, 0.05)});
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  const Real dp = spec.dp;
  // The corner where the block's left face meets the floor (in 3D an edge along y: a point of it mid-depth).
  Vec corner = Vec::Zero();
  corner[0] = 0.1;
  if (dim == 3) corner[1] = 0.045;
  // The two fluid particles nearest that corner, moved behind both faces.
  std::vector<std::size_t> fluid;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::fluid) fluid.push_back(i);
  std::partial_sort(fluid.begin(), fluid.begin() + 2, fluid.end(), [&](const std::size_t a, const std::size_t b) {
    return (p.position[a] - corner).squaredNorm() < (p.position[b] - corner).squaredNorm();
  });
  const std::size_t a = fluid[0], b = fluid[1];
  p.position[a] = p.position[b] = corner;
  p.position[a][0] += 0.2 * dp;
  p.position[a][dim - 1] -= 0.3 * dp;
  p.position[b][0] += 0.3 * dp;
  p.position[b][dim - 1] -= 0.1 * dp;
  const auto gid_a = p.global_id[a], gid_b = p.global_id[b];
  Distribution dist{MPI_COMM_SELF, {}};
  FluidSolver fluid_solver{fluid_setup(spec), p, dist};
  const FluidStepReport r = fluid_solver.advance(0.0, 1e-6);
  EXPECT_EQ(r.n_put_back, 2u);
  // The solver may reorder the particles: they are found by global id.
  Vec xa = Vec::Constant(std::numeric_limits<Real>::quiet_NaN()), xb = xa;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    if (p.global_id[i] == gid_a) xa = p.position[i];
    if (p.global_id[i] == gid_b) xb = p.position[i];
  }
  for (const Vec& x : {xa, xb}) {
    EXPECT_LE(x[0], corner[0]) << x.transpose();  // in front of the block's face
    EXPECT_GE(x[dim - 1], 0.0) << x.transpose();  // above the floor
  }
  EXPECT_GT((xa - xb).norm(), 0.01 * dp) << xa.transpose() << " and " << xb.transpose();
}

// Water at rest around a block 10 dp wide standing on the floor (two wall bodies). The floor's wall particles
// under the block's middle are dry: no fluid particle reads their rows, which hold p = 0. Their pressure must
// not reach the water, neither through the dummies of their wall groups nor through the stabilisation's pairs
// with the block's wet rows (that would make the block's foot a sink: the water around it flows toward it).
// After 50 steps of 1 ms the water is at rest at the hydrostatic pressure.
TEST(Walls, WaterAtRestAroundABlockOnTheFloorStaysAtRest) {
  const CaseSpec spec = load_case(hydrostatic_file(), {"dp=0.01", "fluid.scheme=projection", "materials.water.c=1000",
                                                       "materials.water.kappa=1", "bodies.water.subtract=[step]",
                                                       tank_with_block(0.05, 0.15, 0.06)});
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  Distribution dist{MPI_COMM_SELF, {}};
  FluidSolver fluid{fluid_setup(spec), p, dist};
  for (int step = 0; step < 50; ++step) fluid.advance(step * 1e-3, 1e-3);
  const Real h = 0.2, g = 9.81, rho = 1000;
  const auto& pressure = p.scalar_field("pressure");
  Real v_max = 0, error = 0;
  std::size_t n_checked = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    if (p.kind[i] != ParticleKind::fluid) continue;
    v_max = std::max(v_max, p.velocity[i].norm());
    const Real y = p.position[i][dim - 1];
    if (y > h - 3 * spec.dp) continue;
    error = std::max(error, std::abs(pressure[i] - rho * g * (h - y)) / (rho * g * h));
    ++n_checked;
  }
  ASSERT_GT(n_checked, 50u);
  std::printf("  water around a block: largest speed %.4f m/s, largest pressure error %.4f rho g h\n", v_max, error);
  EXPECT_LT(v_max, 0.005 * std::sqrt(g * h));
  EXPECT_LT(error, 0.025);
}

TEST(Walls, WaterThrownIntoTheCornerOfATiltedTankStaysInTheTank) {
  const Thrown t = throw_into_corner("projection", 3.0, 40, 0.3);
  EXPECT_EQ(t.n_inside, 0u) << "deepest " << t.deepest << " m";
  EXPECT_GT(t.n_put_back, 0u);
  EXPECT_GT(t.closest, 0.01) << "particles put back onto one point";
}

namespace {

#if MPSFSI_DIM == 2
Vec vec(const Real x, const Real y) { return Vec(x, y); }
#else
Vec vec(const Real x, const Real y, const Real z) { return Vec(x, y, z); }
#endif

/// How deep x lies inside the simplex of `vertices` (a triangle in 2D, a tetrahedron in 3D): its distance behind
/// the nearest face (negative outside).
Real depth_in_simplex(const Vec& x, const std::vector<Vec>& vertices) {
  Real depth = std::numeric_limits<Real>::max();
  for (std::size_t opposite = 0; opposite < vertices.size(); ++opposite) {
    std::vector<Vec> face;
    for (std::size_t k = 0; k < vertices.size(); ++k)
      if (k != opposite) face.push_back(vertices[k]);
    Vec n;
#if MPSFSI_DIM == 2
    n = Vec(face[1][1] - face[0][1], face[0][0] - face[1][0]);
#else
    n = (face[1] - face[0]).cross(face[2] - face[0]);
#endif
    n.normalize();
    if (n.dot(vertices[opposite] - face[0]) < 0) n = -n;  // inward
    depth = std::min(depth, (x - face[0]).dot(n));
  }
  return depth;
}

/// The obstacle as a case file's wall: a polygon in 2D, an ASCII STL file (outward normals) in 3D, written to
/// `file` (empty in 2D).
std::string obstacle_wall(const std::vector<Vec>& v, std::string& file) {
  std::string points;
#if MPSFSI_DIM == 2
  for (const Vec& x : v) points += (points.empty() ? "" : ", ") + fmt::format("[{}, {}]", x[0], x[1]);
  return "{name: obstacle, type: polygon, polygon: {points: [" + points + "]}}";
#else
  const std::string path = file = (std::filesystem::temp_directory_path() /
                                   ("mpsfsi_test_fluid_walls_" + std::to_string(::getpid()) + ".stl")).string();
  std::string stl = "solid obstacle\n";
  for (std::size_t opposite = 0; opposite < v.size(); ++opposite) {
    std::vector<Vec> f;
    for (std::size_t k = 0; k < v.size(); ++k)
      if (k != opposite) f.push_back(v[k]);
    if ((f[1] - f[0]).cross(f[2] - f[0]).dot(v[opposite] - f[0]) > 0) std::swap(f[1], f[2]);  // outward
    stl += " facet normal 0 0 0\n  outer loop\n";
    for (const Vec& x : f) stl += fmt::format("   vertex {} {} {}\n", x[0], x[1], x[2]);
    stl += "  endloop\n endfacet\n";
  }
  std::ofstream(path) << stl + "endsolid obstacle\n";
  return "{name: obstacle, type: surface, surface: {file: " + path + "}}";
#endif
}

/// The water of the hydrostatic case (dp 1 cm, no gravity) around an obstacle whose faces are off the lattice
/// (`obstacle`'s vertices), thrown at `speed` along `direction`, 40 steps: after every step, the fluid particles
/// inside the obstacle (its true faces, not the cells).
Thrown throw_at_obstacle(const std::vector<Vec>& obstacle, const Vec& direction, const Real speed) {
  const std::string tank = dim == 2 ? "{name: box, type: box, rectangle: {min: [0, 0], max: [0.2, 0.3]}, open_top: true}"
                                    : "{name: box, type: box, rectangle: {min: [0, 0, 0], max: [0.2, 0.1, 0.3]}, "
                                      "open_top: true}";
  const std::string file = dim == 2 ? "/cases/hydrostatic.yaml" : "/cases/3d/hydrostatic.yaml";
  std::string surface_file;
  const std::string wall = obstacle_wall(obstacle, surface_file);
  CaseSpec spec = load_case(std::string(MPSFSI_SOURCE_DIR) + file,
                            {dim == 2 ? "gravity=[0,0]" : "gravity=[0,0,0]", "dp=0.01", "bodies.water.subtract=[obstacle]",
                             "walls=[" + tank + ", " + wall + "]"});
  Scene scene = build_scene(spec);
  if (!surface_file.empty()) std::filesystem::remove(surface_file);
  ParticleSet& p = scene.particles;
  std::size_t n_fluid = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.kind[i] != ParticleKind::fluid) continue;
    EXPECT_LE(depth_in_simplex(p.position[i], obstacle), surface_tolerance * spec.dp);  // outside, or on a face
    p.velocity[i] = speed * direction.normalized();
    ++n_fluid;
  }
  EXPECT_GT(n_fluid, 300u);
  Distribution dist{MPI_COMM_SELF, {}};
  FluidSolver fluid{fluid_setup(spec), p, dist};
  Thrown out;
  Real t = 0;
  for (int step = 0; step < 40; ++step) {
    const Real dt = fluid.stable_dt();
    out.n_put_back += fluid.advance(t, dt).n_put_back;
    t += dt;
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (p.kind[i] != ParticleKind::fluid) continue;
      const Real depth = depth_in_simplex(p.position[i], obstacle);
      out.deepest = std::max(out.deepest, depth);
      if (depth > 1e-9) ++out.n_inside;
    }
  }
  return out;
}

}  // namespace

// A wall whose faces are off the lattice: an obstacle standing free in the tank, a triangle (2D: sides at 16.7,
// 63.4 and 139.4 degrees) or a tetrahedron (3D). Its wall particles' cells stop short of its faces in places,
// and the put-back closes those gaps (the cells alone let water in: docs/validation.md, "Faces off the lattice
// hold water"). The water is thrown at it at 3 m/s; no fluid particle is ever inside it.
TEST(Walls, WaterThrownAtAnObstacleOffTheLatticeStaysOutOfIt) {
#if MPSFSI_DIM == 2
  const Thrown t = throw_at_obstacle({vec(0.04, 0.05), vec(0.14, 0.08), vec(0.09, 0.18)}, vec(0.3, -1.0), 3.0);
#else
  const Thrown t = throw_at_obstacle(
      {vec(0.04, 0.012, 0.05), vec(0.15, 0.027, 0.07), vec(0.085, 0.088, 0.06), vec(0.1, 0.045, 0.165)},
      vec(0.3, 0.2, -1.0), 3.0);
#endif
  EXPECT_EQ(t.n_inside, 0u) << "deepest " << t.deepest << " m";
  EXPECT_GT(t.n_put_back, 0u);
}

// The same with an obstacle resting on the tank's floor, its foot a face covered by the floor: a slope rising
// 0.07 m over 0.16 m from its toe on the floor to the tank's right wall (2D, a beach), a tetrahedron with a face
// on the floor (3D): the gaps at its foot, where it meets the floor, are closed too.
TEST(Walls, WaterThrownAtASlopeOnTheFloorStaysOutOfIt) {
#if MPSFSI_DIM == 2
  const Thrown t = throw_at_obstacle({vec(0.04, 0.0), vec(0.2, 0.0), vec(0.2, 0.07)}, vec(0.4, -1.0), 3.0);
#else
  const Thrown t = throw_at_obstacle(
      {vec(0.02, 0.01, 0.0), vec(0.18, 0.02, 0.0), vec(0.1, 0.09, 0.0), vec(0.11, 0.05, 0.07)}, vec(0.2, 0.1, -1.0),
      3.0);
#endif
  EXPECT_EQ(t.n_inside, 0u) << "deepest " << t.deepest << " m";
  EXPECT_GT(t.n_put_back, 0u);
}

namespace {

/// The hydrostatic case (dp 1 cm) with its box `height` tall, `n_steps` steps: the rows of the last step's
/// pressure system and the fluid particles' pressures and positions by global id (the water's ids come first and
/// do not depend on the box).
struct AtRest {
  std::size_t n_rows = 0, n_walls = 0, n_fluid = 0;
  std::vector<Real> pressure;
  std::vector<Vec> position;
};
AtRest water_at_rest(const Real height, const int n_steps) {
  const std::string file = dim == 2 ? "/cases/hydrostatic.yaml" : "/cases/3d/hydrostatic.yaml";
  const std::string top = fmt::format("{}", height);
  const CaseSpec spec = load_case(
      std::string(MPSFSI_SOURCE_DIR) + file,
      {"dp=0.01", "fluid.tolerance=1e-14", "fluid.density_tolerance=1e-16", "fluid.max_iterations=5000",
       dim == 2 ? "walls.box.rectangle.max=[0.2," + top + "]" : "walls.box.rectangle.max=[0.2,0.1," + top + "]",
       dim == 2 ? "domain.max=[0.25," + fmt::format("{}", height + 0.1) + "]"
                : "domain.max=[0.25,0.15," + fmt::format("{}", height + 0.1) + "]"});
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  Distribution dist{MPI_COMM_SELF, {}};
  FluidSolver fluid{fluid_setup(spec), p, dist};
  AtRest out;
  Real t = 0;
  for (int step = 0; step < n_steps; ++step) {
    const Real dt = fluid.stable_dt();
    out.n_rows = fluid.advance(t, dt).n_rows;
    t += dt;
  }
  out.n_fluid = p.n_of_kind(ParticleKind::fluid);
  out.n_walls = p.n_of_kind(ParticleKind::wall);
  out.pressure.assign(out.n_fluid, 0.0);
  out.position.assign(out.n_fluid, Vec::Zero());
  const auto& pressure = p.scalar_field("pressure");
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    if (p.kind[i] != ParticleKind::fluid) continue;
    const auto id = static_cast<std::size_t>(p.global_id[i]);
    EXPECT_LT(id, out.n_fluid);
    if (id >= out.n_fluid) continue;
    out.pressure[id] = pressure[i];
    out.position[id] = p.position[i];
  }
  return out;
}

}  // namespace

// The default scheme leaves the walls far from the water out of the step (FluidCore::leave_out_far_walls): water
// at rest in its box, whose walls all lie within the reach of the water and take part, and the same water in the
// box made 1 m tall. The tall box's step has exactly the short box's rows (its walls beyond the reach have none),
// and the water's pressures and positions are the short box's to the solver's round-off: walls left out that a
// row needed would change them.
TEST(Walls, WallsFarFromTheWaterTakeNoPartAndChangeNothing) {
  const AtRest near = water_at_rest(0.3, 4);
  const AtRest far = water_at_rest(1.0, 4);
  ASSERT_GT(far.n_walls, near.n_walls + 50);
  EXPECT_EQ(near.n_rows, near.n_fluid + near.n_walls);  // the short box: every wall has its row
  EXPECT_EQ(far.n_rows, near.n_rows);
  ASSERT_EQ(far.n_fluid, near.n_fluid);
  Real dp_max = 0, dx_max = 0, p_max = 0;
  for (std::size_t k = 0; k < near.n_fluid; ++k) {
    dp_max = std::max(dp_max, std::abs(far.pressure[k] - near.pressure[k]));
    dx_max = std::max(dx_max, (far.position[k] - near.position[k]).norm());
    p_max = std::max(p_max, near.pressure[k]);
  }
  EXPECT_GT(p_max, 1500.0);  // the hydrostatic pressure at the floor, 1.96 kPa
  EXPECT_LT(dp_max, 1e-8 * p_max);
  EXPECT_LT(dx_max, 1e-12);
}

// The partition's weights after a fluid step (fluid_work_weights): each of the kinds fluid, wall and dummy keeps
// its total (the kind weight times the particles that take part), and within the fluid a particle at the free
// surface, with fewer pairs than one in the interior, weighs less; before any step the kind weights alone.
TEST(FluidWorkWeights, PairsMoveWeightWithinAKindAndKeepItsTotal) {
  const std::string file = dim == 2 ? "/cases/hydrostatic.yaml" : "/cases/3d/hydrostatic.yaml";
  const CaseSpec spec = load_case(std::string(MPSFSI_SOURCE_DIR) + file, {"dp=0.01"});
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  Distribution dist{MPI_COMM_SELF, {}};
  FluidSolver fluid{fluid_setup(spec), p, dist};
  const std::vector<Real> before = fluid_work_weights(p, p.n_owned(), MPI_COMM_SELF);
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    ASSERT_EQ(before[i], fluid_work_weight(p.kind[i])) << i;
    ASSERT_TRUE(fluid_takes_part(p, i)) << i;
  }
  fluid.advance(0, fluid.stable_dt());
  const std::vector<Real> w = fluid_work_weights(p, p.n_owned(), MPI_COMM_SELF);
  const std::vector<Real> kind_only = [&] {  // the kind weights with the step's marks of the walls left out
    std::vector<Real> k(p.n_owned());
    for (std::size_t i = 0; i < k.size(); ++i) k[i] = fluid_work_weight(p.kind[i], fluid_takes_part(p, i));
    return k;
  }();
  Real total[3] = {}, expected[3] = {};
  Real surface_max = 0, interior_max = 0;
  const auto& surface = p.scalar_field(fluid_fields::free_surface);
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    const auto k = static_cast<std::size_t>(p.kind[i]);
    ASSERT_LT(k, 3u);
    total[k] += w[i];
    expected[k] += kind_only[i];
    if (p.kind[i] != ParticleKind::fluid) continue;
    Real& largest = surface[i] != 0 ? surface_max : interior_max;
    largest = std::max(largest, w[i]);
  }
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(total[k], expected[k], 1e-9 * expected[k]) << "kind " << k;
  EXPECT_GT(interior_max, 1.0);
  EXPECT_LT(surface_max, interior_max);
}
