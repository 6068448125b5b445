// Tests of the case format in the 3D build (io/case_file.cpp, io/scene.cpp, io/probes.cpp with
// MPSFSI_DIM=3): a 3D case's vectors and boxes are read with three components; the dimension key must say 3;
// the quasi-2D options are refused; the roll axis is read and normalised; 2-component vectors are refused
// with the 3D expected forms; the shipped 3D cases build the particles they were counted for; the probes
// measure along z.
#include "core/tank_motion.hpp"
#include "fluid/fluid_parameters.hpp"
#include "io/case.hpp"
#include "io/probes.hpp"
#include "io/scene.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

using namespace mpsfsi;
using ::testing::HasSubstr;
using ::testing::StartsWith;

namespace {

const std::string file_name = "cases/x.yaml";

/// A 3D case that uses every kind of vector and box: a water column, a clamped plate on a block in a
/// rolling box tank, loads, sources, probes and receivers.
const char* const case_3d = R"(name: case_3d
description: "A 3D test case"
source: "tests"
dimension: 3
dp: 0.01
domain: {min: [-0.1, -0.1, -0.1], max: [0.7, 0.3, 0.8]}
time: {end: 0.5, cfl: 0.2}
gravity: [0, 0, -9.81]
materials:
  water: {type: fluid, rho: 1000, nu: 1.0e-6}
  rubber: {type: solid, rho: 1100, E: 1.2e7, nu: 0.4}
bodies:
  - {name: column, kind: fluid, material: water, rectangle: {min: [0, 0, 0], max: [0.2, 0.2, 0.4]}}
  - name: plate
    kind: solid
    material: rubber
    rectangle: {min: [0.4, 0, 0.02], max: [0.42, 0.2, 0.2]}
    clamp: {min: [0.4, 0, 0.02], max: [0.42, 0.2, 0.04]}
    velocity: [1, 2, 3]
    angular_velocity: [0, 0, 0.5]
walls:
  - {name: tank, type: box, rectangle: {min: [0, 0, 0], max: [0.6, 0.2, 0.6]}, open_top: true}
  - {name: step, type: block, rectangle: {min: [0.38, 0, 0], max: [0.44, 0.2, 0.02]}}
tank_motion: {type: sine_roll, pivot: [0.3, 0.1, 0], axis: [0, -2, 0], amplitude_deg: 4, period: 1.2}
solid_loads:
  - {name: push, body: plate, region: {min: [0.4, 0, 0.1], max: [0.41, 0.2, 0.2]}, direction: [1, 0, 0],
     peak: 1000, time: 0.01, width: 0.005}
sources:
  - {name: tap, body: plate, type: force, position: [0.41, 0.1, 0.15], amplitude: 10, direction: [0, 3, 4],
     wavelet: {type: ricker, frequency: 50}}
probes:
  - {name: p1, type: pressure, position: [0.1, 0.1, 0.02]}
  - {name: tip, type: displacement, position: [0.41, 0.1, 0.195], body: plate}
  - {name: front, type: surge_front, position: [0, 0.1, 0]}
  - {name: h1, type: column_height, position: [0, 0.1, 0]}
receivers:
  points:
    - {name: mid, body: plate, position: [0.41, 0.1, 0.1]}
)";

/// `text` with the first occurrence of `from` (which must occur) replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "test bug: '" << from << "' is not in the text";
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

std::string case_with(const std::string& from, const std::string& to) { return replaced(case_3d, from, to); }

/// "cases/x.yaml:N:" for the line of `text` where `needle` first occurs.
std::string at_line(const std::string& text, const std::string& needle) {
  const auto pos = text.find(needle);
  EXPECT_NE(pos, std::string::npos) << "test bug: '" << needle << "' not found";
  return file_name + ":" + std::to_string(1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(pos), '\n')) + ":";
}

/// The CaseError message of parsing `text`, or "(no error)".
std::string error_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    parse_case(text, file_name, overrides);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "(no error)";
}

void expect_vec(const Vec& v, const Real x, const Real y, const Real z) {
  EXPECT_DOUBLE_EQ(v[0], x);
  EXPECT_DOUBLE_EQ(v[1], y);
  EXPECT_DOUBLE_EQ(v[2], z);
}

}  // namespace

TEST(CaseFile3d, ReadsThreeComponents) {
  const CaseSpec c = parse_case(case_3d, file_name);
  expect_vec(c.domain.lo, -0.1, -0.1, -0.1);
  expect_vec(c.domain.hi, 0.7, 0.3, 0.8);
  expect_vec(c.gravity, 0, 0, -9.81);
  ASSERT_EQ(c.bodies.size(), 2u);
  expect_vec(c.bodies[0].rect.hi, 0.2, 0.2, 0.4);
  expect_vec(c.bodies[1].velocity, 1, 2, 3);
  expect_vec(c.bodies[1].angular_velocity, 0, 0, 0.5);
  ASSERT_TRUE(c.bodies[1].clamp);
  expect_vec(c.bodies[1].clamp->hi, 0.42, 0.2, 0.04);
  // The clamp spans the plate's x and y: it cuts along z, the free part starts above it.
  expect_vec(free_part(c.bodies[1]).lo, 0.4, 0, 0.04);
  ASSERT_EQ(c.walls.size(), 2u);
  expect_vec(c.walls[0].rect.hi, 0.6, 0.2, 0.6);
  expect_vec(c.tank_motion.pivot, 0.3, 0.1, 0);
  expect_vec(c.solid_loads.at(0).direction, 1, 0, 0);
  expect_vec(c.sources.at(0).direction, 0, 0.6, 0.8);
  expect_vec(c.sources.at(0).position, 0.41, 0.1, 0.15);
  ASSERT_EQ(c.probes.size(), 4u);
  expect_vec(c.probes[1].position, 0.41, 0.1, 0.195);
  expect_vec(c.receivers.points.at(0).position, 0.41, 0.1, 0.1);
}

TEST(CaseFile3d, RollAxisIsReadAndNormalised) {
  const CaseSpec c = parse_case(case_3d, file_name);
  expect_vec(c.tank_motion.axis, 0, -1, 0);
  const TankMotion motion = make_tank_motion(c.tank_motion);
  expect_vec(motion.params().axis, 0, -1, 0);
  // About -e_y a positive angle lifts +x: the x-z section rolls as the 2D tank in the x-y plane.
  const Vec x = motion.place(Vec(0.4, 0.1, 0), 0.1);
  EXPECT_NEAR(x[0], 0.3 + 0.1 * std::cos(0.1), 1e-15);
  EXPECT_NEAR(x[2], 0.1 * std::sin(0.1), 1e-15);

  const CaseSpec d = parse_case(case_with("axis: [0, -2, 0], ", ""), file_name);  // default e_z
  expect_vec(d.tank_motion.axis, 0, 0, 1);
  // A table's roll axis too.
  const auto table = std::filesystem::temp_directory_path() / ("mpsfsi_test_roll_" + std::to_string(::getpid()) + ".csv");
  std::ofstream(table) << "0, 0\n1, 2\n";
  const CaseSpec t = parse_case(case_3d, file_name, {"tank_motion={type: table, pivot: [0.3, 0.1, 0], axis: [3, 0, 4], file: " + table.string() + "}"});
  std::filesystem::remove(table);
  EXPECT_EQ(t.tank_motion.type, TankMotionType::table);
  expect_vec(t.tank_motion.axis, 0.6, 0, 0.8);

  const std::string zero = case_with("axis: [0, -2, 0]", "axis: [0, 0, 0]");
  EXPECT_EQ(error_of(zero), at_line(zero, "tank_motion:") +
                                " tank_motion.axis = [0, 0, 0]: expected a non-zero roll axis [x, y, z] through the "
                                "pivot (default [0, 0, 1]; normalised)");
  EXPECT_THAT(error_of(case_with("axis: [0, -2, 0]", "axis: [0, 1]")),
              HasSubstr("tank_motion.axis = [0, 1]: expected a non-zero roll axis [x, y, z]"));
  EXPECT_THAT(error_of(case_with("axis: [0, -2, 0]", "axis: [1e300, 1e300, 1e300]")),
              HasSubstr("expected a non-zero roll axis"));
  // Not a key of `none`.
  EXPECT_THAT(error_of(case_3d, {"tank_motion={type: none, axis: [0, 0, 1]}"}), HasSubstr("unknown key 'axis' in tank_motion"));
}

TEST(CaseFile3d, DimensionMustBeThree) {
  const std::string expected = "this mpsfsi is built for 3D (MPSFSI_DIM=3); expected a 3D case (dimension: 3); 2D cases run in "
                               "the 2D program (<build>/mpsfsi, which starts this one for 3D cases)";
  // Without the key the case is 2D (the default): refused before its 3D vectors are read, naming the key.
  const std::string none = case_with("dimension: 3\n", "");
  EXPECT_EQ(error_of(none), file_name + ":1: dimension = 2 (the default): " + expected);
  const std::string two = case_with("dimension: 3", "dimension: 2");
  EXPECT_EQ(error_of(two), at_line(two, "dimension:") + " dimension = 2: " + expected);
  // A 2D case: the dimension, not its first 2-component vector.
  const std::string case_2d = R"(name: flat
description: a 2D case
source: tests
dp: 0.01
domain: {min: [0, 0], max: [1, 1]}
time: {end: 0.5, dt: 1.0e-4}
gravity: [0, -9.81]
materials:
  water: {type: fluid, rho: 1000, nu: 1.0e-6}
bodies:
  - {name: block, kind: fluid, material: water, rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}}
)";
  EXPECT_THAT(error_of(case_2d), HasSubstr("dimension = 2 (the default): " + expected));
  EXPECT_EQ(error_of(case_3d, {"dimension=2"}), file_name + " (--set dimension=2): dimension = 2: " + expected);
  EXPECT_THAT(error_of(case_with("dimension: 3", "dimension: three")),
              HasSubstr("dimension = three: expected 2 or 3 (the spatial dimension of the case; default 2)"));
}

TEST(CaseFile3d, QuasiTwoDimensionalOptionsAreRefused) {
  const std::string plane_stress = std::string(case_3d) + "solid: {plane_stress: true}\n";
  EXPECT_EQ(error_of(plane_stress), at_line(plane_stress, "solid: {") +
                                        " solid.plane_stress = true: a 3D body has its real thickness; plane stress is "
                                        "a 2D model (a section of a body free in the third direction); expected false, "
                                        "or leave the key out");
  const std::string wide_plate = std::string(case_3d) + "solid: {wide_plate: true}\n";
  EXPECT_THAT(error_of(wide_plate), StartsWith(at_line(wide_plate, "solid: {") +
                                               " solid.wide_plate = true: a 3D plate has its real width and bends as a "
                                               "plate by itself; the wide-plate modulus E / (1 - nu^2) is a 2D model"));
  // Both: the first is named.
  EXPECT_THAT(error_of(std::string(case_3d) + "solid: {plane_stress: true, wide_plate: true}\n"),
              HasSubstr("solid.plane_stress = true: a 3D body has its real thickness"));
  // false is fine.
  EXPECT_EQ(error_of(std::string(case_3d) + "solid: {plane_stress: false, wide_plate: false}\n"), "(no error)");
  const std::string lateral = std::string(case_3d) + "fluid:\n  lateral_walls: {gap: 0.039, model: poiseuille}\n";
  EXPECT_EQ(error_of(lateral), at_line(lateral, "lateral_walls:") +
                                   " fluid.lateral_walls.gap = 0.039: a 3D tank has its real front and back walls (give "
                                   "them as walls, at their real distance); the lateral-wall friction is a quasi-2D "
                                   "model of them; expected no fluid.lateral_walls in a 3D case");
}

TEST(CaseFile3d, TwoComponentVectorsAreRefusedWithThe3dForm) {
  const std::string gravity = case_with("gravity: [0, 0, -9.81]", "gravity: [0, -9.81]");
  EXPECT_EQ(error_of(gravity), at_line(gravity, "gravity:") + " gravity = [0, -9.81]: expected a vector [gx, gy, gz] in m/s2");
  EXPECT_THAT(error_of(case_with("velocity: [1, 2, 3]", "velocity: [1, 2]")),
              HasSubstr("bodies[1].velocity = [1, 2]: expected an initial velocity [vx, vy, vz] in m/s"));
  EXPECT_THAT(error_of(case_with("angular_velocity: [0, 0, 0.5]", "angular_velocity: 0.5")),
              HasSubstr("bodies[1].angular_velocity = 0.5: expected an initial angular velocity [wx, wy, wz] in rad/s"));
  EXPECT_THAT(error_of(case_with("position: [0.1, 0.1, 0.02]", "position: [0.1, 0.02]")),
              HasSubstr("probes[0].position = [0.1, 0.02]: expected a point [x, y, z] in metres"));
  EXPECT_THAT(error_of(case_with("max: [0.7, 0.3, 0.8]", "max: [0.7, 0.8]")),
              HasSubstr("domain.max = [0.7, 0.8]: expected the highest corner [x, y, z] in metres"));
  EXPECT_THAT(error_of(case_with("domain: {min: [-0.1, -0.1, -0.1], max: [0.7, 0.3, 0.8]}", "domain: 1")),
              HasSubstr("domain = 1: expected a rectangle {min: [x, y, z], max: [x, y, z]} in metres"));
  EXPECT_THAT(error_of(case_with("max: [0.7, 0.3, 0.8]", "max: [0.7, -0.3, 0.8]")),
              HasSubstr("domain = {min: [-0.1, -0.1, -0.1], max: [0.7, -0.3, 0.8]}: expected max > min in all three "
                        "components"));
  EXPECT_THAT(error_of(case_with("direction: [1, 0, 0]", "direction: [0, 0, 0]")),
              HasSubstr("solid_loads[0].direction = [0, 0, 0]: expected a non-zero direction [x, y, z] of the force"));
  // A 3D body must be at least one particle deep too.
  EXPECT_THAT(error_of(case_with("max: [0.2, 0.2, 0.4]", "max: [0.2, 0.001, 0.4]")),
              HasSubstr("expected a rectangle at least dp/2 = 0.005 m wide, deep and high (one particle)"));
  EXPECT_THAT(error_of(case_3d, {"fluid.re_laplacian=11"}),
              HasSubstr("about 4/3 pi re^3 = 5.6e+03 neighbours per particle; expected a number in (1, 10]"));
}

TEST(CaseFile3d, OpenTopIsTheFaceAcrossZ) {
  // Above the top of an open box is inside it (the water column may stand higher than the walls) ...
  EXPECT_EQ(error_of(case_with("max: [0.2, 0.2, 0.4]}}", "max: [0.2, 0.2, 0.7]}}")), "(no error)");
  // ... but not beyond its side walls across y, nor above a lid.
  EXPECT_THAT(error_of(case_with("max: [0.2, 0.2, 0.4]}}", "max: [0.2, 0.25, 0.4]}}")),
              HasSubstr("lies outside walls[0].rectangle ('tank'), the inner rectangle of the tank (open top)"));
  EXPECT_THAT(error_of(case_with("max: [0.2, 0.2, 0.4]}}", "max: [0.2, 0.2, 0.7]}}"), {"walls.tank.open_top=false"}),
              HasSubstr("lies outside walls[0].rectangle ('tank')"));
}

TEST(Scene3d, CountsMatchTheBuiltScene) {
  const std::string dir = std::string(MPSFSI_SOURCE_DIR) + "/cases/3d";
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (entry.path().extension() == ".yaml") files.push_back(entry.path().string());
  ASSERT_GE(files.size(), 2u);
  std::vector<CaseSpec> specs;
  for (const auto& f : files) specs.push_back(load_case(f));
  CaseSpec closed = parse_case(case_3d, file_name);
  closed.walls[0].open_top = false;
  specs.push_back(closed);
  specs.push_back(parse_case(case_3d, file_name));
  for (const CaseSpec& spec : specs) {
    SCOPED_TRACE(spec.name);
    const Scene scene = build_scene(spec, std::nullopt);
    const ParticleCounts n = count_particles(spec);
    const auto& p = scene.particles;
    EXPECT_EQ(n.fluid, p.n_of_kind(ParticleKind::fluid));
    EXPECT_EQ(n.solid, p.n_of_kind(ParticleKind::solid));
    EXPECT_EQ(n.wall, p.n_of_kind(ParticleKind::wall));
    EXPECT_EQ(n.dummy, p.n_of_kind(ParticleKind::dummy));
  }
  // The open box has no particle above its side walls' top, the closed one a lid of 3 layers.
  const Scene open = build_scene(specs.back(), std::nullopt);
  const Scene lid = build_scene(closed, std::nullopt);
  Real top_open = -1, top_closed = -1;
  for (std::size_t i = 0; i < open.particles.size(); ++i)
    if (open.particles.bodies[open.particles.body[i]].name == "tank") top_open = std::max(top_open, open.particles.position[i][2]);
  for (std::size_t i = 0; i < lid.particles.size(); ++i)
    if (lid.particles.bodies[lid.particles.body[i]].name == "tank") top_closed = std::max(top_closed, lid.particles.position[i][2]);
  EXPECT_NEAR(top_open, 0.595, 1e-12);
  EXPECT_NEAR(top_closed, 0.625, 1e-12);
}

TEST(Scene3d, ClampedPlateIsMeasuredAlongZ) {
  const Scene scene = build_scene(parse_case(case_3d, file_name), std::nullopt);
  const BodyCount& plate = scene.counts.at(1);
  EXPECT_EQ(plate.n_particles, 2u * 20u * 18u);
  EXPECT_EQ(plate.n_clamped, 2u * 20u * 2u);
  EXPECT_EQ(plate.free_axis, 2);
  ASSERT_TRUE(plate.free_length);
  EXPECT_NEAR(*plate.free_length, 0.16, 1e-12);
  EXPECT_NEAR(plate.file_free_length, 0.16, 1e-12);
  // Particles of a body start with v0 + omega x (x - centroid).
  const auto& p = scene.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.body[i] != 1 || p.clamped[i]) continue;
    const Vec r = p.position[i] - Vec(0.41, 0.1, 0.11);
    const Vec v = Vec(1, 2, 3) + cross(Vec(0, 0, 0.5), r);
    EXPECT_NEAR((p.velocity[i] - v).norm(), 0, 1e-12);
  }
}

TEST(Scene3d, OverlapNamesThreeCoordinates) {
  const CaseSpec spec = parse_case(case_3d, file_name);
  CaseSpec overlapping = spec;
  overlapping.bodies[1].rect.lo[0] = 0.192;  // into the water column, past the parser's check
  overlapping.bodies[1].rect.hi[0] = 0.212;
  overlapping.bodies[1].clamp.reset();
  try {
    build_scene(overlapping, std::nullopt);
    ADD_FAILURE() << "no error";
  } catch (const CaseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bodies 'column' and 'plate' overlap: particles at (0.195, 0.005, 0.025) and (0.195, 0.005, 0.025)"));  // on one lattice
  }
}

TEST(Probes3d, MeasureAlongZ) {
  const CaseSpec spec = parse_case(case_3d, file_name);
  Scene scene = build_scene(spec, std::nullopt);
  ParticleSet& p = scene.particles;
  auto& pressure = p.add_scalar_field(fluid_fields::pressure);
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::fluid || p.kind[i] == ParticleKind::wall) pressure[i] = 1000 * 9.81 * (0.4 - p.position[i][2]);
  ProbeWriter probes(spec, p, "");
  EXPECT_EQ(probes.columns(), (std::vector<std::string>{"p1", "tip_dx", "tip_dy", "tip_dz", "front", "h1"}));
  // Move the tip particle by (1, 2, 3) mm.
  const Vec shift(0.001, 0.002, 0.003);
  Real best = 1e9;
  std::size_t tip = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Real d = (p.position[i] - Vec(0.41, 0.1, 0.195)).norm();
    if (p.bodies[p.body[i]].name == "plate" && d < best) best = d, tip = i;
  }
  p.position[tip] += shift;
  const std::vector<Real> v = probes.evaluate(p, 0);
  ASSERT_EQ(v.size(), 6u);
  // The kernel average of a linear field over neighbours placed symmetrically about the point.
  EXPECT_NEAR(v[0], 1000 * 9.81 * 0.38, 1e-9);
  EXPECT_NEAR(v[1], 0.001, 1e-12);
  EXPECT_NEAR(v[2], 0.002, 1e-12);
  EXPECT_NEAR(v[3], 0.003, 1e-12);
  EXPECT_NEAR(v[4], 0.2, 1e-12);  // the column's front face at x = 0.2 m
  EXPECT_NEAR(v[5], 0.4, 1e-12);  // its top at z = 0.4 m

  // A fluid particle ahead of the column near the floor moves the front; one high up does not.
  const std::size_t n = p.size();
  p.add(Vec(0.305, 0.1, 0.015), Vec::Zero(), ParticleKind::fluid, 0, 0);
  p.add(Vec(0.355, 0.1, 0.105), Vec::Zero(), ParticleKind::fluid, 0, 0);
  ASSERT_EQ(p.size(), n + 2);
  const std::vector<Real> w = probes.evaluate(p, 0);
  EXPECT_NEAR(w[4], 0.31, 1e-12);
  EXPECT_NEAR(w[5], 0.4, 1e-12);
}

// A flap wave maker in 3D turns about the horizontal hinge line across its direction (e_z x direction), its top
// moving along the direction first; a piston translates along it.
TEST(CaseFile3d, WaveMakerTurnsAboutItsHingeLine) {
  const std::string flap = "walls.step.motion={wave_maker: {type: flap, stroke: 0.1, period: 2, direction: [0, 1, 0], "
                           "hinge: [0.4, 0, -0.1], water_level: 0.15}}";
  const WallMotionSpec m = parse_case(case_3d, file_name, {"tank_motion={type: none}", flap}).walls[1].motion;
  expect_vec(m.axis, -1, 0, 0);  // e_z x e_y
  EXPECT_DOUBLE_EQ(m.angle_amplitude, std::atan(0.05 / 0.25));
  const Vec top = WallMotion(m).place(Vec(0.4, 0.0, -0.1 + std::hypot(0.25, 0.05)), 0.5);
  EXPECT_NEAR(top[1], 0.05, 1e-15);
  EXPECT_NEAR(top[2], 0.15, 1e-15);
  const std::string piston = "walls.step.motion={wave_maker: {type: piston, stroke: 0.1, period: 2, direction: [3, 4, 0]}}";
  expect_vec(parse_case(case_3d, file_name, {"tank_motion={type: none}", piston}).walls[1].motion.amplitude, 0.03, 0.04, 0);
  EXPECT_THAT(error_of(case_3d, {"tank_motion={type: none}", "walls.step.motion={wave_maker: {type: piston, stroke: 0.1, "
                                                             "period: 2, direction: [1, 0, 1]}}"}),
              HasSubstr("direction = [1, 0, 1]: expected a horizontal direction [x, y, z]"));
}

// A wave gauge in 3D reads the top of the water in a column 2 dp across around its (x, y), and its own height
// where there is no water.
TEST(Probes3d, WaveGaugeReadsTheTopAlongZ) {
  CaseSpec spec = parse_case(case_3d, file_name);
  ProbeSpec g;
  g.name = "g";
  g.type = ProbeType::wave_gauge;
  g.position = Vec(0.1, 0.1, 0);
  ProbeSpec dry = g;
  dry.name = "dry";
  dry.position = Vec(0.3, 0.1, 0.01);
  spec.probes = {g, dry};
  Scene scene = build_scene(spec, std::nullopt);
  const ProbeWriter probes(spec, scene.particles, "");
  const std::vector<Real> v = probes.evaluate(scene.particles, 0);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_NEAR(v[0], 0.4, 1e-12);  // the column's top
  EXPECT_DOUBLE_EQ(v[1], 0.01);
}

// A rotation table in 3D turns the wall about its axis through the pivot by the table's angle change since start,
// and a translation table moves it along a 3D direction.
TEST(CaseFile3d, WallMotionTablesTurnAboutTheAxis) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "mpsfsi_test_case_file3d_tables";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "turn.csv") << "0, 10\n1, 40\n";
  std::ofstream(dir / "shift.csv") << "0, 0\n1, 0.1\n";
  const std::string motion = "walls.step.motion={rotation: {type: table, file: " + (dir / "turn.csv").string() +
                             ", pivot: [0.4, 0, 0], axis: [0, 0, 2]}, translation: {type: table, file: " +
                             (dir / "shift.csv").string() + ", direction: [0, 0, 1]}}";
  const WallMotionSpec m = parse_case(case_3d, file_name, {"tank_motion={type: none}", motion}).walls[1].motion;
  expect_vec(m.axis, 0, 0, 1);
  const WallMotion w(m);
  // At tau = 0.5 s: turned by 15 degrees about e_z through the pivot, lifted by 0.05 m.
  const Vec x = w.place(Vec(0.5, 0, 0), 0.5);
  EXPECT_NEAR(x[0], 0.4 + 0.1 * std::cos(15 * pi / 180), 1e-15);
  EXPECT_NEAR(x[1], 0.1 * std::sin(15 * pi / 180), 1e-15);
  EXPECT_NEAR(x[2], 0.05, 1e-15);
  EXPECT_NEAR(w.angular_velocity(0.5), 30 * pi / 180, 1e-12);
  std::filesystem::remove_all(dir);
}
