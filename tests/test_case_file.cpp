// Tests of the case-file parser (io/case_file.cpp): a valid case gives the expected numbers, every
// kind of bad input gives a CaseError naming file, line, key and expected form, --set overrides,
// and a fuzz test (mutated case files either parse or throw CaseError, nothing else).
#include "core/geometry.hpp"
#include "core/neighbours.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <sys/stat.h>

using namespace mpsfsi;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

namespace {

const std::string valid_path = std::string(MPSFSI_TEST_DATA_DIR) + "/valid_case.yaml";
const std::string file_name = "cases/x.yaml";

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::string& valid_text() {
  static const std::string text = read_text(valid_path);
  return text;
}

/// `text` with the first occurrence of `from` (which must occur) replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "test bug: '" << from << "' is not in the text";
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

/// The valid case with one replacement.
std::string valid_with(const std::string& from, const std::string& to) { return replaced(valid_text(), from, to); }

/// The 1-based number of the line of `text` where `needle` first occurs.
long line_of(const std::string& text, const std::string& needle) {
  const auto pos = text.find(needle);
  EXPECT_NE(pos, std::string::npos) << "test bug: '" << needle << "' not found";
  if (pos == std::string::npos) return 0;
  return 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(pos), '\n');
}

/// "cases/x.yaml:N:" with N = line_of(text, needle).
std::string at_line(const std::string& text, const std::string& needle) {
  return file_name + ":" + std::to_string(line_of(text, needle)) + ":";
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

constexpr double deg = pi / 180;

const char* const minimal_case = R"(name: minimal
description: one fluid block
source: tests
dp: 0.01
domain: {min: [0, 0], max: [1, 1]}
time: {end: 0.5, dt: 1.0e-4}
materials:
  water: {type: fluid, rho: 1000, nu: 1.0e-6}
bodies:
  - {name: block, kind: fluid, material: water, rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}}
)";

/// The smallest distance between two particles of different bodies, up to 1.5 dp (the neighbour list's reach).
Real closest_of_different_bodies(const ParticleSet& p, const Real dp) {
  NeighbourList nl;
  build_neighbour_list(p.position, 1.5 * dp, nl);
  Real closest = 1.5 * dp;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t k = nl.begin(i); k < nl.end(i); ++k)
      if (p.body[i] != p.body[nl.index[k]]) closest = std::min(closest, (p.position[nl.index[k]] - p.position[i]).norm());
  return closest;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Valid input.

TEST(CaseFile, ValidCaseGivesTheExpectedValues) {
  const CaseSpec c = load_case(valid_path);
  EXPECT_EQ(c.file, valid_path);
  EXPECT_EQ(c.name, "test_case");
  EXPECT_EQ(c.description, "Water column and an elastic plate in a rolling open tank");
  EXPECT_DOUBLE_EQ(c.dp, 0.004);
  EXPECT_DOUBLE_EQ(c.domain.lo[0], -0.1);
  EXPECT_DOUBLE_EQ(c.domain.hi[1], 0.8);
  EXPECT_DOUBLE_EQ(c.time.end, 1.0);
  EXPECT_FALSE(c.time.dt);
  ASSERT_TRUE(c.time.cfl);
  EXPECT_DOUBLE_EQ(*c.time.cfl, 0.2);
  EXPECT_DOUBLE_EQ(c.time.dt_max, 1e-3);
  EXPECT_DOUBLE_EQ(c.gravity[1], -9.81);

  ASSERT_EQ(c.fluid_materials.size(), 1u);
  ASSERT_EQ(c.solid_materials.size(), 1u);
  EXPECT_EQ(c.fluid_material_index("water"), 0);
  EXPECT_EQ(c.solid_material_index("rubber"), 0);
  EXPECT_EQ(c.fluid_material_index("rubber"), -1);
  EXPECT_EQ(c.solid_material_index("nothing"), -1);
  EXPECT_DOUBLE_EQ(c.solid_materials[0].E, 1.2e7);
  ASSERT_TRUE(c.solid_materials[0].fracture_strain);
  EXPECT_DOUBLE_EQ(*c.solid_materials[0].fracture_strain, 0.2);

  ASSERT_EQ(c.bodies.size(), 2u);
  EXPECT_EQ(c.bodies[0].kind, BodyKind::fluid);
  EXPECT_EQ(c.bodies[1].kind, BodyKind::solid);
  EXPECT_EQ(c.bodies[1].material, "rubber");
  EXPECT_DOUBLE_EQ(c.bodies[1].rect.hi[0], 0.412);
  ASSERT_TRUE(c.bodies[1].clamp);
  EXPECT_DOUBLE_EQ(c.bodies[1].clamp->hi[1], 0.032);
  EXPECT_FALSE(c.bodies[0].clamp);

  ASSERT_EQ(c.walls.size(), 2u);
  EXPECT_EQ(c.walls[0].type, WallType::box);
  EXPECT_TRUE(c.walls[0].open_top);
  EXPECT_EQ(c.walls[1].type, WallType::block);

  EXPECT_EQ(c.tank_motion.type, TankMotionType::sine_roll);
  EXPECT_NEAR(c.tank_motion.amplitude, 4 * deg, 1e-15);
  EXPECT_DOUBLE_EQ(c.tank_motion.period, 1.2);
  EXPECT_DOUBLE_EQ(c.tank_motion.pivot[0], 0.3);

  EXPECT_EQ(c.coupling.subcycles, 0);  // auto
  EXPECT_EQ(c.fluid.scheme, FluidScheme::standard);
  EXPECT_EQ(c.fluid.gradient, PressureGradient::corrected);
  EXPECT_EQ(c.fluid.solver, KrylovSolver::gmres);
  EXPECT_EQ(c.fluid.preconditioner, Preconditioner::ilu);
  EXPECT_EQ(c.fluid.max_iterations, 300);
  EXPECT_DOUBLE_EQ(c.fluid.beta2, 0.85);  // default
  EXPECT_DOUBLE_EQ(c.solid.re, 2.1);
  EXPECT_FALSE(c.solid.dt);
  EXPECT_TRUE(c.solid.plane_stress);
  EXPECT_DOUBLE_EQ(c.solid.dt_factor, 0.3);
  EXPECT_DOUBLE_EQ(c.solid.contact_stiffness, 0.5);
  EXPECT_EQ(c.solid.normalisation, SolidNormalisation::lattice);
  EXPECT_EQ(c.solid.volumetric_strain, VolumetricStrain::corrected);
  ASSERT_EQ(c.solid_loads.size(), 1u);
  EXPECT_EQ(c.solid_loads[0].body, "plate");
  EXPECT_DOUBLE_EQ(c.solid_loads[0].region.lo[1], 0.1);
  EXPECT_DOUBLE_EQ(c.solid_loads[0].peak, 1000);
  EXPECT_DOUBLE_EQ(c.solid_loads[0].width, 0.005);
  EXPECT_FALSE(c.solid_materials[0].vp);
  ASSERT_EQ(c.sources.size(), 2u);
  EXPECT_EQ(c.sources[0].name, "tap");
  EXPECT_EQ(c.sources[0].type, SourceType::force);
  EXPECT_DOUBLE_EQ(c.sources[0].direction[0], 0.6);  // normalised
  EXPECT_DOUBLE_EQ(c.sources[0].direction[1], 0.8);
  EXPECT_DOUBLE_EQ(c.sources[0].amplitude, 10);
  EXPECT_DOUBLE_EQ(c.sources[0].radius, 0.01);
  EXPECT_EQ(c.sources[0].wavelet.type, WaveletType::ricker);
  EXPECT_DOUBLE_EQ(c.sources[0].wavelet.frequency, 50);
  EXPECT_DOUBLE_EQ(c.sources[0].wavelet.delay, 0.03);
  EXPECT_EQ(c.sources[1].type, SourceType::explosion);
  EXPECT_DOUBLE_EQ(c.sources[1].position[1], 0.1);
  EXPECT_DOUBLE_EQ(c.sources[1].radius, 2 * 0.004);          // default 2 dp
  EXPECT_DOUBLE_EQ(c.sources[1].wavelet.delay, 1.5 / 100);   // default 1.5 / f0
  EXPECT_EQ(c.sources[1].wavelet.type, WaveletType::gaussian_derivative);
  ASSERT_TRUE(c.receivers.interval);
  EXPECT_DOUBLE_EQ(*c.receivers.interval, 1e-3);
  EXPECT_DOUBLE_EQ(c.receivers.radius, 0.01);
  ASSERT_EQ(c.receivers.points.size(), 2u);
  EXPECT_EQ(c.receivers.points[1].name, "top");
  EXPECT_EQ(c.receivers.points[1].body, "plate");
  EXPECT_DOUBLE_EQ(c.receivers.points[1].position[1], 0.2);

  ASSERT_EQ(c.probes.size(), 4u);
  EXPECT_EQ(c.probes[1].type, ProbeType::displacement);
  EXPECT_EQ(c.probes[1].body, "plate");
  EXPECT_EQ(c.probes[2].type, ProbeType::surge_front);
  EXPECT_EQ(c.probes[3].type, ProbeType::column_height);
  EXPECT_DOUBLE_EQ(c.output.interval, 0.02);
  EXPECT_EQ(c.output.fields, (std::vector<std::string>{"pressure", "velocity"}));

  // The resolved YAML is itself a valid case with the same values.
  const CaseSpec again = parse_case(c.resolved_yaml, "resolved.yaml");
  EXPECT_DOUBLE_EQ(again.dp, c.dp);
  EXPECT_EQ(again.bodies.size(), c.bodies.size());
  EXPECT_EQ(again.coupling.subcycles, 0);
}

TEST(CaseFile, MinimalCaseGetsTheDefaults) {
  const CaseSpec c = parse_case(minimal_case, "minimal.yaml");
  EXPECT_EQ(c.file, "minimal.yaml");
  EXPECT_TRUE(c.gravity.isZero());
  EXPECT_EQ(c.gravity_ramp, 0.0);
  ASSERT_TRUE(c.time.dt);
  EXPECT_DOUBLE_EQ(*c.time.dt, 1e-4);
  EXPECT_FALSE(c.time.cfl);
  EXPECT_DOUBLE_EQ(c.fluid_materials[0].c, FluidMaterial{}.c);
  EXPECT_DOUBLE_EQ(c.fluid_materials[0].kappa, FluidMaterial{}.kappa);
  EXPECT_TRUE(c.walls.empty());
  EXPECT_TRUE(c.probes.empty());
  EXPECT_EQ(c.tank_motion.type, TankMotionType::none);
  EXPECT_EQ(c.coupling.subcycles, 1);
  EXPECT_DOUBLE_EQ(c.coupling.solid_damping, 0.5);
  EXPECT_DOUBLE_EQ(c.coupling.load_relaxation, 1.0);
  EXPECT_EQ(c.coupling.scheme, CouplingSchemeKind::explicit_scheme);
  EXPECT_EQ(c.coupling.implicit.acceleration.kind, AccelerationKind::iqn_ils);
  EXPECT_DOUBLE_EQ(c.coupling.implicit.tolerance, 1e-3);
  EXPECT_EQ(c.coupling.implicit.max_iterations, 20);
  EXPECT_EQ(c.fluid.scheme, FluidScheme::projection);
  EXPECT_DOUBLE_EQ(c.fluid.projection_stabilisation, 1.0);
  EXPECT_DOUBLE_EQ(c.fluid.projection_radius, 2.0);
  EXPECT_EQ(c.fluid.solver, KrylovSolver::cg);
  EXPECT_EQ(c.fluid.preconditioner, Preconditioner::ssor);
  EXPECT_EQ(c.fluid.preconditioner_rebuild_every, 1);
  EXPECT_DOUBLE_EQ(c.fluid.density_tolerance, 1e-6);
  EXPECT_DOUBLE_EQ(c.fluid.re_laplacian, 4.0);
  EXPECT_DOUBLE_EQ(c.output.interval, 0.01);
  EXPECT_TRUE(c.output.fields.empty());
  EXPECT_TRUE(c.bodies[0].velocity.isZero());
  EXPECT_FALSE(c.solid.plane_stress);
  EXPECT_EQ(c.solid.normalisation, SolidNormalisation::mean);
  EXPECT_EQ(c.solid.volumetric_strain, VolumetricStrain::n0);
  EXPECT_DOUBLE_EQ(c.solid.dt_factor, SolidParameters{}.dt_factor);
  EXPECT_TRUE(c.solid_loads.empty());
  EXPECT_TRUE(c.sources.empty());
  EXPECT_TRUE(c.receivers.points.empty());
  EXPECT_FALSE(c.receivers.interval);
}

TEST(CaseFile, SolidFromWaveSpeeds) {
  const CaseSpec c = parse_case(valid_with("E: 1.2e7, nu: 0.4", "vp: 100, vs: 50"), file_name);
  const SolidMaterial& m = c.solid_materials[0];
  ASSERT_TRUE(m.vp && m.vs);
  EXPECT_DOUBLE_EQ(*m.vp, 100);
  // E and nu are the equivalents: mu = rho vs^2 and lambda + 2 mu = rho vp^2.
  const double mu = m.E / (2 * (1 + m.nu));
  const double lambda = m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu));
  EXPECT_NEAR(mu, 1100 * 50.0 * 50.0, 1e-6 * mu);
  EXPECT_NEAR(lambda + 2 * mu, 1100 * 100.0 * 100.0, 1e-6 * mu);

  EXPECT_THAT(error_of(valid_with("E: 1.2e7, nu: 0.4", "vp: 100")), HasSubstr("missing key 'vs' in materials.rubber"));
  EXPECT_THAT(error_of(valid_with("E: 1.2e7, nu: 0.4", "E: 1.2e7, vp: 100, vs: 50")),
              HasSubstr("materials.rubber: expected either E and nu or vp and vs, not both"));
  EXPECT_THAT(error_of(valid_with("E: 1.2e7, nu: 0.4", "vp: 50, vs: 50")),
              HasSubstr("materials.rubber.vp = 50: expected vp > sqrt(4/3) vs"));
}

TEST(CaseFile, TableMotionFileIsResolvedRelativeToTheCaseFile) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "mpsfsi_test_case_file_table";
  fs::create_directories(dir);
  std::ofstream(dir / "roll.csv") << "0,0\n1,4\n";
  const std::string text = valid_with("  type: sine_roll\n  pivot: [0.3, 0]\n  amplitude_deg: 4\n  period: 1.2\n",
                                      "  type: table\n  pivot: [0.3, 0]\n  file: roll.csv\n");
  std::ofstream(dir / "case.yaml") << text;
  const CaseSpec c = load_case((dir / "case.yaml").string());
  EXPECT_EQ(c.tank_motion.type, TankMotionType::table);
  EXPECT_TRUE(fs::equivalent(c.tank_motion.file, dir / "roll.csv"));

  // parse_case resolves relative to the current directory, where there is no roll.csv.
  const std::string msg = error_of(text);
  EXPECT_THAT(msg, HasSubstr(at_line(text, "file: roll.csv")));
  EXPECT_THAT(msg, HasSubstr("tank_motion.file = roll.csv: no such file"));
  EXPECT_THAT(msg, HasSubstr("expected a CSV file"));
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Bad input: each message names the file, the line, the key and the expected form.

TEST(CaseFileErrors, MissingFile) {
  try {
    load_case("/nonexistent/dir/case.yaml");
    FAIL() << "no error";
  } catch (const CaseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent/dir/case.yaml"));
    EXPECT_THAT(e.what(), HasSubstr("no such file"));
  }
}

TEST(CaseFileErrors, UnknownKeyAtTopLevel) {
  const std::string text = valid_with("gravity:", "colour: red\ngravity:");
  const std::string msg = error_of(text);
  EXPECT_THAT(msg, StartsWith(at_line(text, "colour:")));
  EXPECT_THAT(msg, HasSubstr("unknown key 'colour' in (top level); expected one of: name, description, source, dp"));
  EXPECT_THAT(msg, HasSubstr("probes, receivers, output"));
}

TEST(CaseFileErrors, TypoOfARequiredKey) {
  const std::string text = valid_with("time:", "tme:");
  const std::string msg = error_of(text);
  EXPECT_THAT(msg, StartsWith(at_line(text, "tme:")));
  EXPECT_THAT(msg, HasSubstr("unknown key 'tme' in (top level); did you mean 'time'?"));
}

TEST(CaseFileErrors, UnknownKeyNested) {
  const std::string text = valid_with("    angular_velocity: 0", "    angular_velocity: 0\n    colour: red");
  const std::string msg = error_of(text);
  EXPECT_THAT(msg, StartsWith(at_line(text, "colour:")));
  EXPECT_THAT(msg, HasSubstr("unknown key 'colour' in bodies[1]; expected one of: name, kind, material, rectangle"));

  const std::string text2 = valid_with("  beta1: 0.97", "  beta3: 0.97");
  const std::string msg2 = error_of(text2);
  EXPECT_THAT(msg2, StartsWith(at_line(text2, "beta3")));
  EXPECT_THAT(msg2, HasSubstr("unknown key 'beta3' in fluid; expected one of: re_gradient"));
  EXPECT_THAT(msg2, HasSubstr("(did you mean 'beta"));

  // A key of the other material type.
  const std::string text3 = valid_with("c: 20,", "E: 20,");
  EXPECT_THAT(error_of(text3), HasSubstr("unknown key 'E' in materials.water; expected one of: type, rho, nu, c, kappa"));
}

TEST(CaseFileErrors, MissingKey) {
  const std::string text = valid_with("  end: 1.0\n", "");
  const std::string msg = error_of(text);
  EXPECT_THAT(msg, StartsWith(at_line(text, "time:")));
  EXPECT_THAT(msg, HasSubstr("missing key 'end' in time; expected: time.end, a positive number [s]"));

  const std::string text2 = valid_with("    material: rubber\n", "");
  EXPECT_THAT(error_of(text2), HasSubstr("missing key 'material' in bodies[1]; expected: bodies[1].material"));

  const std::string msg3 = error_of(valid_with("dp: 0.004\n", ""));
  EXPECT_THAT(msg3, HasSubstr("missing key 'dp' in (top level); expected: dp, a positive number (particle spacing in metres)"));
}

TEST(CaseFileErrors, StringWhereANumberIsExpected) {
  const std::string text = valid_with("dp: 0.004", "dp: abc");
  EXPECT_EQ(error_of(text), at_line(text, "dp:") + " dp = abc: expected a positive number (particle spacing in metres)");
  // A quoted number is a string.
  EXPECT_THAT(error_of(valid_with("dp: 0.004", "dp: \"0.004\"")), HasSubstr("dp = \"0.004\": expected a positive number"));
  const std::string text2 = valid_with("period: 1.2", "period: soon");
  EXPECT_THAT(error_of(text2), StartsWith(at_line(text2, "period:")));
  EXPECT_THAT(error_of(text2), HasSubstr("tank_motion.period = soon: expected a positive number"));
}

TEST(CaseFileErrors, ScalarWhereAListIsExpected) {
  const std::string text = valid_with("gravity: [0, -9.81]", "gravity: 5");
  EXPECT_EQ(error_of(text), at_line(text, "gravity:") + " gravity = 5: expected a vector [gx, gy] in m/s2");
  const std::string text2 = replaced(minimal_case, "bodies:\n", "bodies: 3\nold_bodies:\n");
  EXPECT_THAT(error_of(text2), HasSubstr(at_line(text2, "bodies:") + " bodies = 3: expected a list of bodies"));
  const std::string text3 = valid_with("time:\n", "time: 1\ntimex:\n");
  EXPECT_THAT(error_of(text3), HasSubstr("time = 1: expected a map {end, dt or cfl, dt_max}"));
}

TEST(CaseFileErrors, GravityRamp) {
  EXPECT_DOUBLE_EQ(parse_case(valid_with("gravity: [0, -9.81]", "gravity: [0, -9.81]\ngravity_ramp: 0.25"), "c.yaml").gravity_ramp,
                   0.25);
  const std::string text = valid_with("gravity: [0, -9.81]", "gravity: [0, -9.81]\ngravity_ramp: -1");
  EXPECT_EQ(error_of(text), at_line(text, "gravity_ramp:") +
                                " gravity_ramp = -1: expected a non-negative time [s] over which gravity rises from 0 (0: at once)");
}

TEST(CaseFileErrors, VectorWithThreeComponents) {
  const std::string text = valid_with("gravity: [0, -9.81]", "gravity: [0, -9.81, 0]");
  EXPECT_EQ(error_of(text), at_line(text, "gravity:") + " gravity = [0, -9.81, 0]: expected a vector [gx, gy] in m/s2");
  const std::string text2 = valid_with("pivot: [0.3, 0]", "pivot: [0.3, 0, 1]");
  EXPECT_THAT(error_of(text2), HasSubstr("tank_motion.pivot = [0.3, 0, 1]: expected a point [x, y] in metres"));
}

// The dimension alone, as the program reads it to choose its 2D or 3D build (app/dimension_launch.cpp).
TEST(CaseFile, PeekDimension) {
  EXPECT_EQ(peek_case_dimension(minimal_case, false), 2);
  EXPECT_EQ(peek_case_dimension(std::string(minimal_case) + "dimension: 3\n", false), 3);
  EXPECT_EQ(peek_case_dimension("dimension: 2\n", false), 2);
  EXPECT_EQ(peek_case_dimension("dimension: 4\n", false), 0);
  EXPECT_EQ(peek_case_dimension("dimension: [3]\n", false), 0);
  EXPECT_EQ(peek_case_dimension("dimension: 3\n  bad: [", false), 0);
  EXPECT_EQ(peek_case_dimension("- a list\n", false), 2);
  EXPECT_EQ(peek_case_dimension(std::string(MPSFSI_SOURCE_DIR) + "/cases/3d/dam_break.yaml", true), 3);
  EXPECT_EQ(peek_case_dimension(std::string(MPSFSI_SOURCE_DIR) + "/cases/dam_break.yaml", true), 2);
  EXPECT_EQ(peek_case_dimension("/nonexistent/case.yaml", true), 0);
}

TEST(CaseFileErrors, DimensionThreeIsRefusedByThe2DBuild) {
  const std::string expected = "dimension = 3: this mpsfsi is built for 2D (MPSFSI_DIM=2); expected a 2D case (dimension: 2, "
                               "the default); 3D cases run in the 3D program, which mpsfsi starts when it was built "
                               "beside it (<build>/3d/mpsfsi, CMake option MPSFSI_WITH_3D)";
  const std::string text = std::string(minimal_case) + "dimension: 3\n";
  EXPECT_EQ(error_of(text), at_line(text, "dimension:") + " " + expected);
  // Checked before anything else: the 3D vectors of a 3D case do not give their own error.
  const std::string text3d =
      "dimension: 3\n" + replaced(minimal_case, "{min: [0, 0], max: [1, 1]}", "{min: [0, 0, 0], max: [1, 1, 1]}");
  EXPECT_EQ(error_of(text3d), file_name + ":1: " + expected);
  EXPECT_EQ(error_of(minimal_case, {"dimension=3"}), file_name + " (--set dimension=3): " + expected);
  EXPECT_EQ(error_of(std::string(minimal_case) + "dimension: 4\n"),
            at_line(std::string(minimal_case) + "dimension: 4\n", "dimension:") +
                " dimension = 4: expected 2 or 3 (the spatial dimension of the case; default 2)");
  EXPECT_THAT(error_of(std::string(minimal_case) + "dimension: 2.0\n"), HasSubstr("dimension = 2.0: expected 2 or 3"));
  // dimension: 2 is the default, said explicitly; the key is listed among the known ones.
  const CaseSpec c = parse_case(std::string(minimal_case) + "dimension: 2\n", file_name);
  EXPECT_EQ(c.bodies.size(), 1u);
  EXPECT_THAT(error_of(std::string(minimal_case) + "colour: red\n"), HasSubstr("receivers, output, dimension"));
}

TEST(CaseFileErrors, RollAxisIsA3DKey) {
  EXPECT_THAT(error_of(valid_with("period: 1.2", "period: 1.2\n  axis: [0, 0, 1]")),
              HasSubstr("unknown key 'axis' in tank_motion; expected one of: type, pivot, amplitude_deg, period"));
}

TEST(CaseFileErrors, OutOfRangeValues) {
  const std::string text = valid_with("dp: 0.004", "dp: -0.004");
  EXPECT_EQ(error_of(text), at_line(text, "dp:") + " dp = -0.004: expected a positive number (particle spacing in metres)");
  EXPECT_THAT(error_of(valid_with("dp: 0.004", "dp: 0")), HasSubstr("dp = 0: expected a positive number"));
  EXPECT_THAT(error_of(valid_with("dp: 0.004", "dp: 1e400")), HasSubstr("dp = 1e400: expected a positive number"));
  EXPECT_THAT(error_of(valid_with("dp: 0.004", "dp: .nan")), HasSubstr("dp = .nan: expected a positive number"));
  EXPECT_THAT(error_of(valid_with("cfl: 0.2", "cfl: 1.5")), HasSubstr("time.cfl = 1.5: expected a Courant number C with 0 < C <= 1"));
  EXPECT_THAT(error_of(valid_with("nu: 0.4", "nu: 0.5")), HasSubstr("materials.rubber.nu = 0.5: expected a number in (-1, 0.5)"));
  EXPECT_THAT(error_of(valid_with("amplitude_deg: 4", "amplitude_deg: 95")),
              HasSubstr("tank_motion.amplitude_deg = 95: expected a number of degrees in (0, 90)"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: 0")),
              HasSubstr("coupling.subcycles = 0: expected a positive integer up to 100000 or auto"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: 2.5")),
              HasSubstr("coupling.subcycles = 2.5: expected a positive integer up to 100000 or auto"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, solid_damping: -1")),
              HasSubstr("coupling.solid_damping = -1: expected a number >= 0"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, load_relaxation: 0")),
              HasSubstr("coupling.load_relaxation = 0: expected a number in (0, 1]"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, scheme: strong")),
              HasSubstr("coupling.scheme = strong: expected one of: explicit, implicit"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, implicit: {acceleration: broyden}")),
              HasSubstr("coupling.implicit.acceleration = broyden: expected one of: constant, aitken, iqn-ils"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, implicit: {tolerance: 1}")),
              HasSubstr("coupling.implicit.tolerance = 1: expected a number in (0, 1)"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, implicit: {max_iterations: 0}")),
              HasSubstr("coupling.implicit.max_iterations = 0: expected an integer from 1 to 1000"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, implicit: {on_max_iterations: abort}")),
              HasSubstr("coupling.implicit.on_max_iterations = abort: expected one of: continue, stop"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, implicit: {reuse: -1}")),
              HasSubstr("coupling.implicit.reuse = -1: expected an integer from 0 to 1000"));
  EXPECT_THAT(error_of(valid_with("subcycles: auto", "subcycles: auto, implicit: 3")),
              HasSubstr("coupling.implicit"));
  EXPECT_THAT(error_of(valid_with("solver: gmres", "solver: bicgstab")),
              HasSubstr("fluid.solver = bicgstab: expected one of: cg, gmres"));
  EXPECT_THAT(error_of(valid_with("  solver: gmres", "  solver: gmres\n  density_tolerance: -1e-6")),
              HasSubstr("fluid.density_tolerance = -1e-6: expected a number in [0, 1)"));
  EXPECT_THAT(error_of(valid_with("  solver: gmres", "  solver: gmres\n  lateral_walls: {gap: 0}")),
              HasSubstr("fluid.lateral_walls.gap = 0: expected a positive number"));
  EXPECT_THAT(error_of(valid_with("  solver: gmres", "  solver: gmres\n  lateral_walls: {gap: 0.04, model: turbulent}")),
              HasSubstr("fluid.lateral_walls.model = turbulent: expected one of: stokes, poiseuille"));
  EXPECT_THAT(error_of(valid_with("  solver: gmres", "  solver: gmres\n  lateral_walls: {gap: 0.04, width: 1}")),
              HasSubstr("unknown key 'width' in fluid.lateral_walls"));
  EXPECT_THAT(error_of(valid_with("open_top: true", "open_top: maybe")),
              HasSubstr("walls[0].open_top = maybe: expected true or false"));
  EXPECT_THAT(error_of(valid_with("max: [0.2, 0.4]", "max: [0.2, -0.4]")),
              HasSubstr("bodies[0].rectangle = {min: [0, 0], max: [0.2, -0.4]}: expected max > min in both components"));
}

TEST(CaseFileErrors, TimeStepChoice) {
  const std::string both = valid_with("  cfl: 0.2\n", "  cfl: 0.2\n  dt: 1.0e-4\n");
  EXPECT_THAT(error_of(both), HasSubstr("both dt and cfl are given; expected exactly one of time.dt"));
  const std::string neither = valid_with("  cfl: 0.2\n", "");
  EXPECT_THAT(error_of(neither), StartsWith(at_line(neither, "time:")));
  EXPECT_THAT(error_of(neither), HasSubstr("missing key 'dt' or 'cfl' in time"));
  // A solid-only case needs neither.
  const std::string solid_only = replaced(replaced(minimal_case, "time: {end: 0.5, dt: 1.0e-4}", "time: {end: 0.5}"),
                                          "water: {type: fluid, rho: 1000, nu: 1.0e-6}",
                                          "steel: {type: solid, rho: 7800, E: 2.0e11, nu: 0.3}");
  EXPECT_EQ(error_of(replaced(solid_only, "kind: fluid, material: water", "kind: solid, material: steel")), "(no error)");
  EXPECT_THAT(error_of(replaced(minimal_case, "time: {end: 0.5, dt: 1.0e-4}", "time: {end: 0.5}")),
              HasSubstr("missing key 'dt' or 'cfl' in time"));
}

TEST(CaseFileErrors, OverlappingBodies) {
  const std::string text = valid_with("min: [0.4, 0.02], max: [0.412, 0.2]", "min: [0.15, 0.02], max: [0.162, 0.2]");
  const std::string msg = error_of(text);
  EXPECT_EQ(msg, at_line(text, "min: [0.15, 0.02]") +
                     " bodies[1].rectangle overlaps bodies[0].rectangle ('column'): bodies must not overlap");
  // Touching edges do not overlap.
  const std::string touching = std::string(minimal_case) +
                               "  - {name: b2, kind: fluid, material: water, rectangle: {min: [0.3, 0.1], max: [0.5, 0.3]}}\n";
  EXPECT_EQ(error_of(touching), "(no error)");
  EXPECT_EQ(error_of(valid_with("max: [0.2, 0.4]", "max: [0.38, 0.4]")), "(no error)");  // touches the block
}

TEST(CaseFileErrors, BodyOverlapsABlock) {
  const std::string text = valid_with("min: [0.4, 0.02], max: [0.412, 0.2]", "min: [0.4, 0.01], max: [0.412, 0.2]");
  EXPECT_THAT(error_of(text), HasSubstr(at_line(text, "min: [0.4, 0.01]") +
                                        " bodies[1].rectangle overlaps walls[1].rectangle ('step'): bodies must not overlap walls"));
}

TEST(CaseFileErrors, BodyOutsideItsTank) {
  const std::string text = valid_with("min: [0, 0], max: [0.2, 0.4]", "min: [-0.05, 0], max: [0.2, 0.4]");
  const std::string msg = error_of(text);
  EXPECT_THAT(msg, StartsWith(at_line(text, "min: [-0.05, 0]")));
  EXPECT_THAT(msg, HasSubstr("bodies[0].rectangle = {min: [-0.05, 0], max: [0.2, 0.4]} lies outside walls[0].rectangle ('tank')"));
  EXPECT_THAT(msg, HasSubstr("expected bodies inside the tank"));
  // Above an open tank is fine, above a closed one is not.
  const std::string high = valid_with("max: [0.2, 0.4]", "max: [0.2, 0.7]");
  EXPECT_EQ(error_of(high), "(no error)");
  EXPECT_THAT(error_of(replaced(high, "open_top: true", "open_top: false")), HasSubstr("lies outside walls[0].rectangle"));
}

TEST(CaseFileErrors, BodyOutsideTheDomain) {
  const std::string text = valid_with("domain: {min: [-0.1, -0.1], max: [0.7, 0.8]}", "domain: {min: [0.1, -0.1], max: [0.7, 0.8]}");
  EXPECT_THAT(error_of(text), HasSubstr("bodies[0].rectangle = {min: [0, 0], max: [0.2, 0.4]} lies outside the domain"));
}

TEST(CaseFileErrors, UnknownMaterial) {
  const std::string text = valid_with("material: water", "material: oil");
  EXPECT_EQ(error_of(text),
            at_line(text, "material: oil") + " bodies[0].material = oil: unknown material; expected a fluid material (one of: water)");
}

TEST(CaseFileErrors, MaterialOfTheWrongType) {
  const std::string text = valid_with("material: rubber", "material: water");
  const std::string msg = error_of(text);
  EXPECT_THAT(msg, StartsWith(at_line(text, "material: water\n    rectangle: {min: [0.4")));
  EXPECT_THAT(msg, HasSubstr("bodies[1].material = water: 'water' is a fluid material but the body is solid; expected a "
                             "solid material (one of: rubber)"));
}

TEST(CaseFileErrors, ClampOnAFluidBody) {
  const std::string text =
      valid_with("max: [0.2, 0.4]}\n", "max: [0.2, 0.4]}\n    clamp: {min: [0, 0], max: [0.2, 0.01]}\n");
  EXPECT_THAT(error_of(text), HasSubstr(at_line(text, "clamp: {min: [0, 0]") +
                                        " bodies[0].clamp: a fluid body cannot be clamped; expected clamp only on solid bodies"));
}

TEST(CaseFileErrors, ProbeOfAnUnknownBody) {
  const std::string probe = "position: [0.406, 0.198], body: plate";
  const std::string text = valid_with(probe, "position: [0.406, 0.198], body: plank");
  EXPECT_THAT(error_of(text), HasSubstr(at_line(text, "body: plank") +
                                        " probes[1].body = plank: unknown body; expected the name of a solid body (one of: plate)"));
  EXPECT_THAT(error_of(valid_with(probe, "position: [0.406, 0.198], body: column")), HasSubstr("'column' is a fluid body"));
  EXPECT_THAT(error_of(valid_with(probe, "position: [0.406, 0.198]")), HasSubstr("missing key 'body' in probes[1]"));
  EXPECT_THAT(error_of(valid_with(probe, "position: [0.3, 0.198], body: plate")),
              HasSubstr("probes[1].position = [0.3, 0.198]: expected a point on body 'plate'"));
}

TEST(CaseFile, DisplacementProbeFrame) {
  const std::string probe = "position: [0.406, 0.198], body: plate";
  EXPECT_EQ(parse_case(valid_text(), file_name).probes[1].frame, ProbeFrame::global);
  const CaseSpec c = parse_case(valid_with(probe, probe + ", frame: tank"), file_name);
  EXPECT_EQ(c.probes[1].frame, ProbeFrame::tank);
  EXPECT_THAT(error_of(valid_with(probe, probe + ", frame: plate")), HasSubstr("probes[1].frame = plate: expected one of: global, tank"));
  EXPECT_THAT(error_of(valid_with("position: [0.59, 0.01]}", "position: [0.59, 0.01], frame: tank}")),
              HasSubstr("unknown key 'frame' in probes[0]"));  // only displacement probes have a frame
}

TEST(CaseFileErrors, SolidLoads) {
  const std::string text = valid_with("body: plate, region", "body: column, region");
  EXPECT_THAT(error_of(text), HasSubstr(at_line(text, "body: column, region") +
                                        " solid_loads[0].body = column: 'column' is a fluid body; expected a solid body "
                                        "(one of: plate)"));
  EXPECT_THAT(error_of(valid_with("region: {min: [0.4, 0.1]", "region: {min: [0.5, 0.1]")),
              HasSubstr("solid_loads[0].region = {min: [0.5, 0.1], max: [0.404, 0.2]}: expected max > min"));
  EXPECT_THAT(error_of(valid_with("region: {min: [0.4, 0.1], max: [0.404, 0.2]}", "region: {min: [0.5, 0.1], max: [0.504, 0.2]}")),
              HasSubstr("solid_loads[0].region = {min: [0.5, 0.1], max: [0.504, 0.2]} does not overlap body 'plate'"));
  EXPECT_THAT(error_of(valid_with("direction: [1, 0]", "direction: [0, 0]")),
              HasSubstr("solid_loads[0].direction = [0, 0]: expected a non-zero direction"));
  EXPECT_THAT(error_of(valid_with("width: 0.005", "width: 0")), HasSubstr("solid_loads[0].width = 0: expected a positive number"));
  EXPECT_THAT(error_of(valid_with("normalisation: lattice", "normalisation: grid")),
              HasSubstr("solid.normalisation = grid: expected one of: particle, lattice, mean"));
  EXPECT_THAT(error_of(valid_with("volumetric_strain: corrected", "volumetric_strain: exact")),
              HasSubstr("solid.volumetric_strain = exact: expected one of: n0, corrected"));
  // The corrected gradient belongs to the standard scheme; the default scheme, the projection, refuses it.
  EXPECT_THAT(error_of(valid_with("  scheme: standard\n", "")),
              HasSubstr("fluid.gradient = corrected: expected min_pressure (the default) with fluid.scheme = projection "
                        "(the default)"));
}

TEST(CaseFile, WaveletTableIsReadRelativeToTheCaseFile) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "mpsfsi_test_case_file_wavelet";
  fs::create_directories(dir);
  const std::string wavelet = "wavelet: {type: ricker, frequency: 50, delay: 0.03}";
  const std::string text = valid_with(wavelet, "wavelet: {type: table, file: stf.csv}");
  std::ofstream(dir / "case.yaml") << text;
  const auto table_error = [&](const std::string& csv) {
    std::ofstream(dir / "stf.csv") << csv;
    try {
      load_case((dir / "case.yaml").string());
    } catch (const CaseError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  std::ofstream(dir / "stf.csv") << "# a source time function\ntime,value\n0, 0\n0.001 1\n\n0.002,0.5\n";
  const CaseSpec c = load_case((dir / "case.yaml").string());
  const WaveletSpec& w = c.sources[0].wavelet;
  EXPECT_EQ(w.type, WaveletType::table);
  EXPECT_EQ(w.time, (std::vector<Real>{0, 0.001, 0.002}));
  EXPECT_EQ(w.value, (std::vector<Real>{0, 1, 0.5}));
  EXPECT_TRUE(fs::equivalent(w.file, dir / "stf.csv"));

  EXPECT_THAT(table_error("0,0\n0.001,1\n0.001,2\n"),
              HasSubstr("sources[0].wavelet.file = stf.csv: " + (dir / "stf.csv").string() +
                        ":3: time 0.001 s: expected times that increase strictly"));
  EXPECT_THAT(table_error("0,0\n0.001,x\n"), HasSubstr(":2: '0.001,x': expected a row of two numbers: time [s], value"));
  EXPECT_THAT(table_error("0,0,1\n"), HasSubstr(":1: '0,0,1': expected a row of two numbers"));
  EXPECT_THAT(table_error("0,0\n"), HasSubstr("has 1 row(s); expected at least two rows"));
  fs::remove_all(dir);
  // parse_case resolves relative to the current directory, where there is no stf.csv.
  EXPECT_THAT(error_of(text), HasSubstr(at_line(text, "wavelet: {type: table") +
                                        " sources[0].wavelet.file = stf.csv: no such file './stf.csv'; expected a CSV file"));
}

TEST(CaseFileErrors, Sources) {
  const std::string src = "position: [0.406, 0.15]";
  EXPECT_THAT(error_of(valid_with("name: tap\n    body: plate", "name: tap\n    body: column")),
              HasSubstr("sources[0].body = column: 'column' is a fluid body; expected a solid body (one of: plate)"));
  EXPECT_THAT(error_of(valid_with("type: force\n", "type: push\n")),
              HasSubstr("sources[0].type = push: expected one of: explosion, force"));
  EXPECT_THAT(error_of(valid_with(src, "position: [0.3, 0.15]")),
              HasSubstr("sources[0].position = [0.3, 0.15]: expected a point on body 'plate' {min: [0.4, 0.02], max: "
                        "[0.412, 0.2]}"));
  EXPECT_THAT(error_of(valid_with("direction: [3, 4]", "direction: [0, 0]")),
              HasSubstr("sources[0].direction = [0, 0]: expected a non-zero direction"));
  EXPECT_THAT(error_of(valid_with("    direction: [3, 4]\n", "")), HasSubstr("missing key 'direction' in sources[0]"));
  EXPECT_THAT(error_of(valid_with("amplitude: 2.5,", "amplitude: 2.5, direction: [1, 0],")),
              HasSubstr("sources[1].direction: expected only with type: force"));
  EXPECT_THAT(error_of(valid_with("radius: 0.01\n    wavelet", "radius: 0\n    wavelet")),
              HasSubstr("sources[0].radius = 0: expected a positive number (radius of the particle stencil"));
  EXPECT_THAT(error_of(valid_with("type: ricker", "type: sinc")),
              HasSubstr("sources[0].wavelet.type = sinc: expected one of: gaussian_derivative, ricker, gaussian, table"));
  EXPECT_THAT(error_of(valid_with("frequency: 50,", "frequency: -50,")),
              HasSubstr("sources[0].wavelet.frequency = -50: expected a positive number (central frequency f0) [Hz]"));
  EXPECT_THAT(error_of(valid_with("frequency: 50,", "")), HasSubstr("missing key 'frequency' in sources[0].wavelet"));
  EXPECT_THAT(error_of(valid_with("delay: 0.03", "delay: -1")),
              HasSubstr("sources[0].wavelet.delay = -1: expected a non-negative number"));
  EXPECT_THAT(error_of(valid_with("delay: 0.03", "delay: 0.03, width: 1")),
              HasSubstr("unknown key 'width' in sources[0].wavelet"));
  EXPECT_THAT(error_of(valid_with("    wavelet: {type: ricker, frequency: 50, delay: 0.03}\n", "")),
              HasSubstr("missing key 'wavelet' in sources[0]"));
  EXPECT_THAT(error_of(valid_with("name: blast", "name: tap")),
              HasSubstr("sources[1].name = tap: duplicate name (also sources[0].name); expected a name unique among sources"));
}

TEST(CaseFileErrors, Receivers) {
  EXPECT_THAT(error_of(valid_with("{name: top, body: plate, position: [0.406, 0.2]}",
                                  "{name: top, body: plate, position: [0.406, 0.21]}")),
              HasSubstr("receivers.points[1].position = [0.406, 0.21]: expected a point on body 'plate'"));
  EXPECT_THAT(error_of(valid_with("{name: top, body: plate", "{name: top, body: tank")),
              HasSubstr("receivers.points[1].body = tank: unknown body; expected a solid body (one of: plate)"));
  EXPECT_THAT(error_of(valid_with("{name: top, body: plate", "{name: mid, body: plate")),
              HasSubstr("receivers.points[1].name = mid: duplicate name (also receivers.points[0].name)"));
  EXPECT_THAT(error_of(valid_with("  interval: 1.0e-3\n", "  interval: 0\n")),
              HasSubstr("receivers.interval = 0: expected a positive number (simulated time between rows"));
  EXPECT_THAT(error_of(valid_with("  radius: 0.01\n  points:", "  radius: 0.01\n  spacing: 1\n  points:")),
              HasSubstr("unknown key 'spacing' in receivers"));
  const std::string points = "  points:\n    - {name: mid, body: plate, position: [0.406, 0.1]}\n"
                             "    - {name: top, body: plate, position: [0.406, 0.2]}\n";
  EXPECT_THAT(error_of(valid_with(points, "")), HasSubstr("missing key 'points' in receivers"));
  EXPECT_THAT(error_of(valid_with(points, "  points: []\n")),
              HasSubstr("receivers.points = []: expected a list of receivers, each {name, body, position}"));
  // Receivers can be dropped or replaced with --set.
  EXPECT_TRUE(parse_case(valid_text(), file_name, {"receivers=~"}).receivers.points.empty());
  const CaseSpec c =
      parse_case(valid_text(), file_name, {"receivers.points=[{name: a, body: plate, position: [0.41, 0.05]}]"});
  ASSERT_EQ(c.receivers.points.size(), 1u);
  EXPECT_DOUBLE_EQ(c.receivers.points[0].position[0], 0.41);
}

TEST(CaseFileErrors, DuplicateNames) {
  const std::string text = valid_with("name: plate", "name: column");
  EXPECT_THAT(error_of(text), HasSubstr(at_line(text, "name: column\n    kind: solid") +
                                        " bodies[1].name = column: duplicate name (also bodies[0].name); expected a name "
                                        "unique among bodies and walls"));
  EXPECT_THAT(error_of(valid_with("name: step", "name: plate")), HasSubstr("walls[1].name = plate: duplicate name"));
  EXPECT_THAT(error_of(valid_with("name: h1", "name: p1")), HasSubstr("probes[3].name = p1: duplicate name"));
  const std::string dup_key = valid_with("dp: 0.004\n", "dp: 0.004\ndp: 0.005\n");
  EXPECT_THAT(error_of(dup_key), HasSubstr(at_line(dup_key, "dp: 0.005") + " duplicate key 'dp' in (top level) (first given at line"));
}

TEST(CaseFileErrors, YamlSyntaxError) {
  const std::string text = valid_with("gravity: [0, -9.81]", "gravity: [0, -9.81");
  const std::string msg = error_of(text);
  EXPECT_THAT(msg, StartsWith(file_name + ":"));
  EXPECT_THAT(msg, HasSubstr("YAML syntax error"));
  EXPECT_THAT(msg, HasSubstr("expected valid YAML"));
  const std::string tab = valid_with("  end: 1.0", "\tend: 1.0");
  EXPECT_THAT(error_of(tab), StartsWith(at_line(tab, "\tend")));
  EXPECT_THAT(error_of(tab), HasSubstr("this line has a tab: indent with spaces"));
  EXPECT_THAT(error_of("a: b: c\n"), StartsWith(file_name + ":1: YAML syntax error"));
}

TEST(CaseFileErrors, NotAMapOrEmpty) {
  EXPECT_THAT(error_of("- 1\n- 2\n"), HasSubstr("(top level) = [1, 2]: expected a map of case keys"));
  EXPECT_THAT(error_of(""), HasSubstr("missing key 'name' in (top level)"));
  EXPECT_THAT(error_of("# only a comment\n"), HasSubstr("missing key 'name'"));
}

// ---------------------------------------------------------------------------------------------
// --set overrides.

TEST(CaseFileOverrides, ValuesListsIndexesNames) {
  const CaseSpec c = parse_case(valid_text(), file_name,
                                {"time.end=0.5", "gravity=[0,0]", "bodies.0.velocity=[1, 0]",
                                 "bodies.plate.angular_velocity=2", "coupling.subcycles=4", "materials.water.rho=998",
                                 "fluid.solver=cg", "walls.tank.open_top=false", "probes.p1.position=[0.5, 0.02]"});
  EXPECT_DOUBLE_EQ(c.time.end, 0.5);
  EXPECT_TRUE(c.gravity.isZero());
  EXPECT_DOUBLE_EQ(c.bodies[0].velocity[0], 1.0);
  EXPECT_DOUBLE_EQ(c.bodies[1].angular_velocity, 2.0);
  EXPECT_EQ(c.coupling.subcycles, 4);
  EXPECT_DOUBLE_EQ(c.fluid_materials[0].rho, 998);
  EXPECT_EQ(c.fluid.solver, KrylovSolver::cg);
  EXPECT_FALSE(c.walls[0].open_top);
  EXPECT_DOUBLE_EQ(c.probes[0].position[0], 0.5);
  EXPECT_THAT(c.resolved_yaml, HasSubstr("end: 0.5"));
  EXPECT_THAT(c.resolved_yaml, HasSubstr("rho: 998"));

  EXPECT_EQ(parse_case(minimal_case, file_name, {"coupling.subcycles=auto"}).coupling.subcycles, 0);
  EXPECT_DOUBLE_EQ(parse_case(minimal_case, file_name, {"coupling.solid_damping=2"}).coupling.solid_damping, 2.0);
  EXPECT_EQ(parse_case(valid_text(), file_name, {"coupling.subcycles=7"}).coupling.subcycles, 7);
  const CaseSpec implicit = parse_case(valid_text(), file_name,
                                       {"coupling.scheme=implicit", "coupling.implicit.acceleration=aitken",
                                        "coupling.implicit.relaxation=0.3", "coupling.implicit.on_max_iterations=stop"});
  EXPECT_EQ(implicit.coupling.scheme, CouplingSchemeKind::implicit_scheme);
  EXPECT_EQ(implicit.coupling.implicit.acceleration.kind, AccelerationKind::aitken);
  EXPECT_DOUBLE_EQ(implicit.coupling.implicit.acceleration.relaxation, 0.3);
  EXPECT_EQ(implicit.coupling.implicit.on_max_iterations, NonConvergence::stop);
  // A later override wins; ~ removes an optional key.
  const CaseSpec d = parse_case(valid_text(), file_name, {"dp=0.01", "dp=0.002", "time.cfl=~", "time.dt_max=~", "time.dt=1e-4"});
  EXPECT_DOUBLE_EQ(d.dp, 0.002);
  EXPECT_FALSE(d.time.cfl);
  EXPECT_DOUBLE_EQ(*d.time.dt, 1e-4);
  // A whole new section.
  EXPECT_DOUBLE_EQ(parse_case(minimal_case, file_name, {"solid.dt=1e-6"}).solid.dt.value(), 1e-6);
}

TEST(CaseFileOverrides, BadValueNamesTheOverride) {
  const std::string msg = error_of(valid_text(), {"time.end=-1"});
  EXPECT_EQ(msg, file_name + " (--set time.end=-1): time.end = -1: expected a positive number [s]");
  EXPECT_THAT(error_of(valid_text(), {"bodies.plate.velocity=[1,2,3]"}),
              HasSubstr("(--set bodies.plate.velocity=[1,2,3]): bodies[1].velocity = [1, 2, 3]: expected an initial velocity"));
  // An override that moves a body into another: the line of the body plus the override.
  const std::string overlap = error_of(valid_text(), {"bodies.plate.rectangle.min=[0.1, 0.02]"});
  EXPECT_THAT(overlap, StartsWith(file_name + ":" + std::to_string(line_of(valid_text(), "min: [0.4, 0.02]")) +
                                  " (after --set bodies.plate.rectangle.min=[0.1, 0.02])"));
  EXPECT_THAT(overlap, HasSubstr("bodies[1].rectangle overlaps bodies[0].rectangle"));
}

TEST(CaseFileOverrides, TypoKeyMentionsTheOverride) {
  const std::string msg = error_of(valid_text(), {"time.ned=0.5"});
  EXPECT_THAT(msg, StartsWith(file_name + " (--set time.ned=0.5): unknown key 'ned' in time; expected one of: end, dt, cfl, dt_max"));
  const std::string msg2 = error_of(valid_text(), {"tmie.end=0.5"});
  EXPECT_THAT(msg2, StartsWith(file_name + " (--set tmie.end=0.5): unknown key 'tmie' in (top level)"));
  EXPECT_THAT(msg2, HasSubstr("did you mean 'time'?"));
}

TEST(CaseFileOverrides, BadPaths) {
  EXPECT_EQ(error_of(valid_text(), {"bodies.5.velocity=[0,0]"}),
            file_name + " (--set bodies.5.velocity=[0,0]): index 5 is out of range: bodies has 2 element(s)");
  EXPECT_THAT(error_of(valid_text(), {"bodies.gate.velocity=[0,0]"}),
              HasSubstr("(--set bodies.gate.velocity=[0,0]): bodies has no element named 'gate'; expected an index (0 to 1) "
                        "or one of the names: column, plate"));
  EXPECT_THAT(error_of(valid_text(), {"dp.x=1"}),
              HasSubstr("(--set dp.x=1): dp is a single value (0.004), so it has no key 'x'"));
  EXPECT_THAT(error_of(valid_text(), {"time.end"}), HasSubstr("(--set time.end): expected dotted.key=value"));
  EXPECT_THAT(error_of(valid_text(), {"time..end=1"}), HasSubstr("'time..end' is not a dotted key"));
  EXPECT_THAT(error_of(valid_text(), {"gravity=[0,"}), HasSubstr("(--set gravity=[0,): the value '[0,' is not valid YAML"));
}

// ---------------------------------------------------------------------------------------------
// Fuzz: mutated copies of the valid case either parse or throw CaseError; nothing else, no crash.

namespace {

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  return text;
}

std::string mutate(const std::string& text, std::mt19937& rng) {
  static const std::vector<std::string> garbage = {"-1", "abc", "[1,2,3]", "{}", "\"\"", "1e400", "nan", "0", "~",
                                                   "[", "}", ":", "- x", "&a", "*a", "!!int x", "0x10", "-0", ".inf"};
  const auto pick = [&](const std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  std::vector<std::string> lines = split_lines(text);
  if (lines.empty()) return text;
  switch (pick(8)) {
    case 0:  // delete a line
      lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(pick(lines.size())));
      break;
    case 1: {  // duplicate a line
      const auto i = pick(lines.size());
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(i), lines[i]);
      break;
    }
    case 2:  // swap two lines
      std::swap(lines[pick(lines.size())], lines[pick(lines.size())]);
      break;
    case 3: {  // replace a token (a run of letters, digits, '.', '-', '_') by garbage
      std::string& line = lines[pick(lines.size())];
      std::vector<std::pair<std::size_t, std::size_t>> tokens;
      for (std::size_t i = 0; i < line.size();) {
        const auto is_token = [](const char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_'; };
        if (!is_token(line[i])) {
          ++i;
          continue;
        }
        std::size_t j = i;
        while (j < line.size() && is_token(line[j])) ++j;
        tokens.emplace_back(i, j - i);
        i = j;
      }
      if (!tokens.empty()) {
        const auto [pos, len] = tokens[pick(tokens.size())];
        line.replace(pos, len, garbage[pick(garbage.size())]);
      }
      break;
    }
    case 4: {  // truncate at a random byte
      const std::string joined = join_lines(lines);
      return joined.substr(0, pick(joined.size() + 1));
    }
    case 5: {  // insert random characters, tabs included
      static const std::string chars = "\t :-[]{},#&*!|>'\"%@`?\\x9.";
      std::string& line = lines[pick(lines.size())];
      const auto n = 1 + pick(3);
      for (std::size_t k = 0; k < n; ++k) line.insert(pick(line.size() + 1), 1, chars[pick(chars.size())]);
      break;
    }
    case 6: {  // change the indentation of a line
      std::string& line = lines[pick(lines.size())];
      const auto indent = line.find_first_not_of(' ');
      line = std::string(pick(7), ' ') + (indent == std::string::npos ? std::string() : line.substr(indent));
      break;
    }
    default: {  // replace a number by another number, sometimes out of range
      std::string& line = lines[pick(lines.size())];
      const auto pos = line.find_first_of("0123456789");
      if (pos != std::string::npos) {
        static const std::vector<std::string> numbers = {"0", "-0.5", "1e-30", "1e30", "2", "0.3", "100000"};
        line.replace(pos, 1, numbers[pick(numbers.size())]);
      }
      break;
    }
  }
  return join_lines(lines);
}

}  // namespace

TEST(CaseFileFuzz, MutatedFilesParseOrThrowCaseError) {
  std::mt19937 rng(20240611);
  const bool verbose = std::getenv("MPSFSI_FUZZ_VERBOSE") != nullptr;  // print every message
  int accepted = 0;
  int rejected = 0;
  for (int iteration = 0; iteration < 200; ++iteration) {
    std::string text = valid_text();
    const int n_mutations = 1 + static_cast<int>(rng() % 3);
    for (int m = 0; m < n_mutations; ++m) text = mutate(text, rng);
    try {
      const CaseSpec c = parse_case(text, "fuzz.yaml");
      ++accepted;
      // Whatever is accepted is consistent.
      EXPECT_GT(c.dp, 0);
      EXPECT_FALSE(c.bodies.empty());
      for (const auto& b : c.bodies) EXPECT_TRUE((b.rect.hi.array() > b.rect.lo.array()).all());
      EXPECT_FALSE(c.time.dt && c.time.cfl);
    } catch (const CaseError& e) {
      ++rejected;
      if (verbose) std::printf("  %s\n", e.what());
      EXPECT_THAT(e.what(), StartsWith("fuzz.yaml")) << "mutated case:\n" << text;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "not a CaseError: " << e.what() << "\nmutated case:\n" << text;
    } catch (...) {
      ADD_FAILURE() << "unknown exception\nmutated case:\n" << text;
    }
  }
  std::printf("fuzz: %d mutated cases accepted, %d rejected with CaseError\n", accepted, rejected);
  EXPECT_GT(accepted, 0);
  EXPECT_GT(rejected, 0);
}

// solid.wide_plate needs plane stress and materials given by E and nu.
TEST(CaseFile, WidePlate) {
  EXPECT_FALSE(parse_case(valid_text(), file_name).solid.wide_plate);
  EXPECT_THAT(error_of(minimal_case + std::string("solid: {wide_plate: true}\n")),
              HasSubstr("solid.wide_plate = true: expected solid.plane_stress: true as well"));
  EXPECT_THAT(error_of(minimal_case + std::string("solid: {plane_stress: true, wide_plate: maybe}\n")),
              HasSubstr("solid.wide_plate = maybe: expected true (plane stress with the wide-plate bending modulus"));
  EXPECT_TRUE(parse_case(minimal_case + std::string("solid: {plane_stress: true, wide_plate: true}\n"), file_name).solid.wide_plate);
}

// fluid.lateral_walls: the stokes frequency defaults to the sine roll's; without a sine roll it is required.
TEST(CaseFile, LateralWallFriction) {
  const CaseSpec off = parse_case(valid_text(), file_name);
  EXPECT_EQ(off.fluid.lateral_walls.gap, 0.0);
  const CaseSpec c = parse_case(valid_with("  solver: gmres", "  solver: gmres\n  lateral_walls: {gap: 0.039}"), file_name);
  EXPECT_DOUBLE_EQ(c.fluid.lateral_walls.gap, 0.039);
  EXPECT_EQ(c.fluid.lateral_walls.model, LateralWallModel::stokes);
  EXPECT_DOUBLE_EQ(c.fluid.lateral_walls.frequency, 1 / 1.2);  // the valid case rolls with period 1.2 s
  const CaseSpec f = parse_case(valid_with("  solver: gmres", "  solver: gmres\n  lateral_walls: {gap: 0.039, frequency: 2}"),
                                file_name);
  EXPECT_DOUBLE_EQ(f.fluid.lateral_walls.frequency, 2.0);
  const CaseSpec h = parse_case(minimal_case + std::string("fluid: {lateral_walls: {gap: 0.01, model: poiseuille}}\n"), file_name);
  EXPECT_EQ(h.fluid.lateral_walls.model, LateralWallModel::poiseuille);
  EXPECT_THAT(error_of(minimal_case + std::string("fluid: {lateral_walls: {gap: 0.01}}\n")),
              HasSubstr("missing key 'frequency' in fluid.lateral_walls; expected: fluid.lateral_walls.frequency, a "
                        "positive number [Hz]"));
}

// ---------------------------------------------------------------------------------------------
// Tables, sizes and bounds (issue 13): input that used to block, run out of memory, take minutes or reach
// the run before it failed is refused when the case is read, with the key and the expected form.

namespace {

namespace fs = std::filesystem;

/// A folder of its own under the system's temporary folder, removed at the end of the test.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) : path(fs::temp_directory_path() / name) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

/// The valid case with a wavelet table `file`, written to dir/case.yaml.
std::string wavelet_case(const fs::path& dir, const std::string& file) {
  const std::string text = valid_with("wavelet: {type: ricker, frequency: 50, delay: 0.03}", "wavelet: {type: table, file: " + file + "}");
  std::ofstream(dir / "case.yaml") << text;
  return (dir / "case.yaml").string();
}

/// The valid case with a tank-motion table `file`, written to dir/case.yaml.
std::string table_motion_case(const fs::path& dir, const std::string& file) {
  const std::string text = valid_with("  type: sine_roll\n  pivot: [0.3, 0]\n  amplitude_deg: 4\n  period: 1.2\n",
                                      "  type: table\n  pivot: [0.3, 0]\n  file: " + file + "\n");
  std::ofstream(dir / "case.yaml") << text;
  return (dir / "case.yaml").string();
}

std::string load_error(const std::string& path, const std::vector<std::string>& overrides = {}) {
  try {
    load_case(path, overrides);
  } catch (const CaseError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

// A FIFO used to block `check` forever and /dev/zero to read until memory ran out; a huge file was read whole.
TEST(CaseFileTables, OnlyRegularFilesOfBoundedSize) {
  const TempDir dir("mpsfsi_test_case_file_special");
  const fs::path fifo = dir.path / "stf.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  for (const auto& make : {wavelet_case, table_motion_case}) {
    const std::string key = make == wavelet_case ? "sources[0].wavelet.file" : "tank_motion.file";
    EXPECT_THAT(load_error(make(dir.path, fifo.string())),
                HasSubstr(key + " = " + fifo.string() + ": '" + fifo.string() + "' is not a regular file (a FIFO); expected a CSV file of time [s]"));
    EXPECT_THAT(load_error(make(dir.path, "/dev/zero")),
                HasSubstr(key + " = /dev/zero: '/dev/zero' is not a regular file (a device, socket or other special file)"));
    EXPECT_THAT(load_error(make(dir.path, dir.path.string())), HasSubstr("is not a regular file (a directory)"));
  }
  // Over 16 MiB (a sparse file: nothing is written).
  std::ofstream(dir.path / "big.csv") << "0,0\n1,1\n";
  fs::resize_file(dir.path / "big.csv", (16u << 20) + 1);
  EXPECT_THAT(load_error(wavelet_case(dir.path, "big.csv")),
              HasSubstr("sources[0].wavelet.file = big.csv: '" + (dir.path / "big.csv").string() + "' has 16777217 bytes; expected a table file of at most 16 MiB"));
  // More than a million rows (within 16 MiB).
  {
    std::ofstream many(dir.path / "many.csv");
    for (int k = 0; k <= 1000000; ++k) many << k << ",0\n";
  }
  EXPECT_THAT(load_error(table_motion_case(dir.path, "many.csv")),
              HasSubstr((dir.path / "many.csv").string() + ":1000001: more than 1000000 rows; expected at most 1000000 rows of time [s], angle [deg]"));
  // The case file itself.
  std::ofstream(dir.path / "huge.yaml") << "name: x\n";
  fs::resize_file(dir.path / "huge.yaml", (16u << 20) + 1);
  EXPECT_THAT(load_error((dir.path / "huge.yaml").string()), HasSubstr("cannot read the case file: it has 16777217 bytes; expected a case file of at most 16 MiB"));
  EXPECT_THAT(load_error(fifo.string()), HasSubstr("cannot read the case file: not a regular file"));
}

// The tank-motion table was read only by the run, which skipped rows it could not read and then said "needs
// at least two rows" of a three-row file (exit 1). Now the case reader reads it, with the wavelets' reader.
TEST(CaseFileTables, TankMotionTableIsCheckedWhenTheCaseIsRead) {
  const TempDir dir("mpsfsi_test_case_file_motion");
  const std::string case_path = table_motion_case(dir.path, "roll.csv");
  const std::string csv = (dir.path / "roll.csv").string();
  const auto error = [&](const std::string& rows) {
    std::ofstream(dir.path / "roll.csv") << rows;
    return load_error(case_path);
  };
  const std::string key = "tank_motion.file = roll.csv: ";
  EXPECT_THAT(error("0;0\n0.5;1\n1;0\n"), HasSubstr(key + csv + ":2: '0.5;1': expected a row of two numbers: time [s], angle [deg]"));
  EXPECT_THAT(error("0,0\n1,nan\n2,0\n"), HasSubstr(key + csv + ":2: '1,nan': expected a row of two numbers"));
  EXPECT_THAT(error("0,0\n1,1\n0.5,2\n"), HasSubstr(key + csv + ":3: time 0.5 s: expected times that increase strictly"));
  EXPECT_THAT(error("0,0\n"), HasSubstr(key + "'" + csv + "' has 1 row(s); expected at least two rows of time [s], angle [deg]"));
  EXPECT_THAT(error("0,0\n1,95\n"), HasSubstr(key + csv + ":2: angle [deg] = 95: expected an angle in (-90, 90) degrees"));
  EXPECT_THAT(error("0,0\n1,2,3\n"), HasSubstr(csv + ":2: '1,2,3': expected a row of two numbers"));
  std::ofstream(dir.path / "passwd") << "root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n";
  EXPECT_THAT(load_error(table_motion_case(dir.path, "passwd")),
              HasSubstr("tank_motion.file = passwd: " + (dir.path / "passwd").string() + ":2: 'daemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin': expected a row of two numbers"));

  // A good table is kept in the case (angles in radians): the run uses it and does not read the file again.
  std::ofstream(dir.path / "roll.csv") << "# roll\ntime, angle\n0, 0\n0.5, 2\n1.0 -4\n";
  const CaseSpec c = load_case(table_motion_case(dir.path, "roll.csv"));
  EXPECT_EQ(c.tank_motion.time, (std::vector<Real>{0, 0.5, 1.0}));
  ASSERT_EQ(c.tank_motion.angle.size(), 3u);
  EXPECT_NEAR(c.tank_motion.angle[1], 2 * deg, 1e-15);
  EXPECT_NEAR(c.tank_motion.angle[2], -4 * deg, 1e-15);
}

// --set fluid.re_laplacian=1e6 made `check` run for minutes (about 3e12 neighbours per particle).
TEST(CaseFileErrors, RadiiAreBounded) {
  EXPECT_THAT(error_of(valid_text(), {"fluid.re_laplacian=1e6"}),
              HasSubstr("fluid.re_laplacian = 1e6: about pi re^2 = 3.1e+12 neighbours per particle; expected a number in "
                        "(1, 10] (effective radius of the Laplacian, in units of dp)"));
  EXPECT_THAT(error_of(valid_text(), {"fluid.re_gradient=10.5"}), HasSubstr("fluid.re_gradient = 10.5: about pi re^2 = 3.5e+02 neighbours"));
  EXPECT_THAT(error_of(valid_text(), {"fluid.re_gradient=1"}), HasSubstr("fluid.re_gradient = 1: expected a number in (1, 10]"));
  EXPECT_THAT(error_of(valid_text(), {"solid.re=40"}), HasSubstr("solid.re = 40: about pi re^2 = 5e+03 neighbours per particle; expected a number in (1, 10] (effective radius of the bonds"));
  EXPECT_THAT(error_of(valid_text(), {"sources.tap.radius=1"}),
              HasSubstr("sources[0].radius = 1: 250 dp, about 2e+05 particles in the stencil; expected a radius of at most 10 dp = 0.04 m (dp = 0.004 m)"));
  EXPECT_THAT(error_of(valid_text(), {"receivers.radius=0.041"}), HasSubstr("receivers.radius = 0.041: 10.2 dp"));
  EXPECT_EQ(error_of(valid_text(), {"fluid.re_laplacian=10", "solid.re=10", "receivers.radius=0.04"}), "(no error)");
}

// output.interval = 1e-300 hung a run; so would the same receivers.interval; time steps are bounded too.
TEST(CaseFileErrors, IntervalsAndTimeStepsAreBounded) {
  EXPECT_THAT(error_of(valid_text(), {"output.interval=1e-300"}),
              HasSubstr("output.interval = 1e-300: expected an interval of at least 1e-06 s (at least 1e-09 s, and at most "
                        "1e+06 frames up to time.end = 1 s) [s]"));
  EXPECT_THAT(error_of(valid_text(), {"output.interval=1e-25"}), HasSubstr("output.interval = 1e-25: expected an interval of at least 1e-06 s"));
  EXPECT_THAT(error_of(valid_text(), {"time.end=1e-6", "output.interval=1e-10"}),
              HasSubstr("output.interval = 1e-10: expected an interval of at least 1e-09 s"));
  // The default interval (0.01 s) is too short for a very long end time.
  EXPECT_THAT(error_of(minimal_case, {"time.end=1e5"}),
              HasSubstr("output.interval = 0.01 (default): expected an interval of at least 0.1 s"));
  EXPECT_THAT(error_of(valid_text(), {"receivers.interval=1e-300"}),
              HasSubstr("receivers.interval = 1e-300: expected an interval of at least 1e-06 s (at least 1e-09 s, and at "
                        "most 1e+06 rows up to time.end = 1 s) [s]"));
  EXPECT_THAT(error_of(minimal_case, {"time.dt=1e-13"}),
              HasSubstr("time.dt = 1e-13: expected a time step of at least 5e-10 s (at least 1e-12 s, and at most 1e+09 "
                        "steps up to time.end = 0.5 s) [s]"));
  EXPECT_THAT(error_of(valid_text(), {"time.dt_max=1e-300"}), HasSubstr("time.dt_max = 1e-300: expected a time step of at least 1e-12 s"));
  EXPECT_THAT(error_of(valid_text(), {"solid.dt=1e-15"}), HasSubstr("solid.dt = 1e-15: expected a time step of at least 1e-09 s"));
  EXPECT_THAT(error_of(valid_text(), {"coupling.subcycles=100001"}),
              HasSubstr("coupling.subcycles = 100001: expected a positive integer up to 100000 or auto"));
  EXPECT_EQ(error_of(valid_text(), {"coupling.subcycles=100000", "output.interval=1e-6", "receivers.interval=1e-6"}), "(no error)");
}

// gravity: [1e300, 1e300] and other huge numbers overflowed in the run.
TEST(CaseFileErrors, MagnitudesAreBounded) {
  EXPECT_THAT(error_of(valid_text(), {"gravity=[1e300, 1e300]"}),
              HasSubstr("gravity = [1e300, 1e300]: expected a vector [gx, gy] in m/s2 of magnitude at most 10000 m/s2 (1000 g)"));
  EXPECT_THAT(error_of(valid_text(), {"bodies.column.velocity=[0, -2e4]"}),
              HasSubstr("bodies[0].velocity = [0, -2e4]: expected an initial velocity [vx, vy] in m/s of magnitude at most 10000 m/s"));
  EXPECT_THAT(error_of(valid_text(), {"bodies.plate.angular_velocity=1e300"}),
              HasSubstr("bodies[1].angular_velocity = 1e300: expected a number in [-10000, 10000] (initial angular velocity) [rad/s]"));
  EXPECT_THAT(error_of(valid_text(), {"materials.water.rho=1e300"}), HasSubstr("materials.water.rho = 1e300: expected a number in [0.001, 100000] (density) [kg/m3]"));
  EXPECT_THAT(error_of(valid_text(), {"materials.water.c=1e-300"}), HasSubstr("materials.water.c = 1e-300: expected a number in [0.001, 100000] (sound speed"));
  EXPECT_THAT(error_of(valid_text(), {"materials.water.nu=1e300"}), HasSubstr("materials.water.nu = 1e300: expected a number in [0, 10000] (kinematic viscosity)"));
  EXPECT_THAT(error_of(valid_text(), {"materials.rubber.E=1e300"}), HasSubstr("materials.rubber.E = 1e300: expected a number in [0.001, 1e+13] (Young's modulus) [Pa]"));
  EXPECT_THAT(error_of(valid_text(), {"materials.rubber.rho=1e-300"}), HasSubstr("materials.rubber.rho = 1e-300: expected a number in [0.001, 100000]"));
  EXPECT_THAT(error_of(valid_with("E: 1.2e7, nu: 0.4", "vp: 1e300, vs: 50")), HasSubstr("materials.rubber.vp = 1e300: expected a number in [0.001, 100000] (P-wave speed"));
  EXPECT_THAT(error_of(valid_text(), {"tank_motion.period=1e-300"}), HasSubstr("tank_motion.period = 1e-300: expected a roll period of at least 0.001 s"));
  EXPECT_THAT(error_of(valid_text(), {"solid_loads.push.peak=1e300"}), HasSubstr("solid_loads[0].peak = 1e300: expected a number in [-1e+13, 1e+13] (peak pressure) [Pa]"));
  EXPECT_THAT(error_of(valid_text(), {"sources.tap.amplitude=-1e300"}), HasSubstr("sources[0].amplitude = -1e300: expected a number in [-1e+13, 1e+13] (line force F0) [N/m]"));
  EXPECT_THAT(error_of(valid_with("  solver: gmres", "  solver: gmres\n  lateral_walls: {gap: 1e-300}")),
              HasSubstr("fluid.lateral_walls.gap = 1e-300: expected a gap of at least 1e-06 m"));
}

// An invalid UTF-8 description went into case.resolved.yaml, which YAML readers then refused; a 300-character
// name made creating the output folder fail with a raw filesystem error.
TEST(CaseFileErrors, TextIsUtf8AndNamesAreShort) {
  EXPECT_THAT(error_of(valid_with("Water column", "Water \xff column")),
              HasSubstr("description: the text is not valid UTF-8 (byte 0xff at position 7); expected a one-line description "
                        "of the case, as UTF-8 text"));
  EXPECT_THAT(error_of(valid_with("Made-up", "Made\xc3-up")), HasSubstr("source: the text is not valid UTF-8 (byte 0xc3 at position 5)"));
  EXPECT_THAT(error_of(valid_with("Made-up", "Made\xed\xa0\x80-up")), HasSubstr("source: the text is not valid UTF-8"));  // a surrogate
  EXPECT_THAT(error_of(valid_with("Made-up", "Made\xc0\xaf-up")), HasSubstr("source: the text is not valid UTF-8"));  // overlong '/'
  EXPECT_THAT(error_of(valid_text(), {"description=caf\xe9"}), HasSubstr("(--set description=caf\xe9): description: the text is not valid UTF-8"));
  EXPECT_EQ(error_of(valid_with("Water column", "Wasser \xc3\xa4 \xe2\x82\xac \xf0\x9f\x8c\x8a column")), "(no error)");

  const std::string long_name(65, 'a');
  EXPECT_THAT(error_of(valid_with("name: test_case", "name: " + long_name)),
              HasSubstr("name = " + long_name.substr(0, 57) + "...: expected the case name: a name of at most 64 letters"));
  EXPECT_THAT(error_of(valid_with("name: plate", "name: " + long_name)), HasSubstr("bodies[1].name = aaaa"));
  EXPECT_THAT(error_of(valid_with("water:", long_name + ":")), HasSubstr("material name '" + long_name + "': expected a name of at most 64"));
  EXPECT_EQ(error_of(valid_with("name: test_case", "name: " + std::string(64, 'a'))), "(no error)");
}

TEST(CaseFile, MaxLoss) {
  EXPECT_DOUBLE_EQ(parse_case(minimal_case, file_name).fluid.max_loss, 0.05);
  EXPECT_DOUBLE_EQ(parse_case(minimal_case, file_name, {"fluid.max_loss=0.2"}).fluid.max_loss, 0.2);
  EXPECT_DOUBLE_EQ(parse_case(minimal_case, file_name, {"fluid.max_loss=0"}).fluid.max_loss, 0.0);
  EXPECT_THAT(error_of(minimal_case, {"fluid.max_loss=1.5"}),
              HasSubstr("fluid.max_loss = 1.5: expected a number in [0, 1] (largest share of a fluid body's particles that "
                        "may leave the domain before the run stops)"));
  EXPECT_THAT(error_of(minimal_case, {"fluid.max_loss=-0.1"}), HasSubstr("fluid.max_loss = -0.1: expected a number in [0, 1]"));
  EXPECT_TRUE(key_under("fluid.max_loss", restart_tunable_keys()));
}

// dp 1e-5 for the dam break ended in std::bad_alloc (exit 1): the particle count and the memory are
// estimated from the rectangles and checked before build_scene allocates.
TEST(Scene, ParticleCountFromTheRectanglesMatchesTheScene) {
  const std::string cases = std::string(MPSFSI_TEST_DATA_DIR) + "/../../cases/";
  for (const std::string name : {"dam_break", "dam_break_obstacle", "hydrostatic", "cantilever", "collision_fracture",
                                 "sloshing_high", "dam_break_elastic_plate"}) {
    const CaseSpec spec = load_case(cases + name + ".yaml");
    const ParticleCounts n = count_particles(spec);
    const Scene scene = build_scene(spec);
    const auto& p = scene.particles;
    EXPECT_EQ(n.fluid, p.n_of_kind(ParticleKind::fluid)) << name;
    EXPECT_EQ(n.solid, p.n_of_kind(ParticleKind::solid)) << name;
    // Wall points next to clamped particles embedded in a wall give way (io/scene.cpp), in the count too.
    EXPECT_EQ(n.wall, p.n_of_kind(ParticleKind::wall)) << name;
    EXPECT_EQ(n.dummy, p.n_of_kind(ParticleKind::dummy)) << name;
    EXPECT_EQ(estimate_memory_bytes(spec, n), estimate_memory_bytes(spec, scene)) << name;
  }
}

// Bodies on one lattice: at dp that do not divide the geometry (sloshing_high_measured's 0.302 m of oil, 4 mm of
// plate and 0.609 m of tank at dp 4 and 3 mm; the elastic gate's lintel at 2 mm) no two particles of different
// bodies are closer than dp. Before, each body was filled from its own corner, and particles of two bodies sat
// dp/2 apart: the first steps stopped (exit 3).
TEST(Scene, BodiesThatTouchAreDpApartAtAnyDp) {
  const std::string cases = std::string(MPSFSI_TEST_DATA_DIR) + "/../../cases/";
  for (const auto& [name, dp] : std::vector<std::pair<std::string, std::string>>{
           {"sloshing_high_measured", "0.004"}, {"sloshing_high_measured", "0.003"}, {"sloshing_low", "0.004"},
           {"elastic_gate", "0.002"}, {"dam_break_elastic_plate", "0.006"}}) {
    const CaseSpec spec = load_case(cases + name + ".yaml", {"dp=" + dp});
    const Scene scene = build_scene(spec);
    EXPECT_NEAR(closest_of_different_bodies(scene.particles, spec.dp), spec.dp, 1e-9 * spec.dp) << name << " at dp " << dp;
  }
}

// Discs, cylinders and polygons whose bounding boxes are off the case's lattice are filled on it, like the
// rectangles: every particle sits at a cell centre of the tank's lattice, so no two particles of different bodies
// come closer than dp, and count_particles counts the shapes on that lattice.
TEST(Scene, RoundAndPolygonBodiesAreOnTheCaseLattice) {
  const std::string text =
      replaced(minimal_case, "rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}", "rectangle: {min: [0, 0], max: [0.4, 0.3]}") +
      "  - {name: drop, kind: fluid, material: water, sphere: {centre: [0.4513, 0.8529], radius: 0.0407}}\n"
      "walls:\n  - {name: tank, type: box, rectangle: {min: [0, 0], max: [1, 1]}}\n"
      "  - {name: pile, type: cylinder, cylinder: {base: [0.5137, 0], axis: [0, 0.3], radius: 0.0211}}\n"
      "  - {name: ball, type: sphere, sphere: {centre: [0.7123, 0.6049], radius: 0.0507}}\n"
      "  - {name: ramp, type: polygon, polygon: {points: [[0.6033, 0.0], [0.9977, 0.0], [0.9977, 0.2051]]}}\n";
  const CaseSpec spec = parse_case(text, file_name);
  const Scene scene = build_scene(spec);
  const auto& p = scene.particles;
  Real off = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (int a = 0; a < dim; ++a) {
      const Real f = p.position[i][a] / spec.dp - 0.5;
      off = std::max(off, std::abs(f - std::round(f)));
    }
  EXPECT_LT(off, 1e-9);
  EXPECT_NEAR(closest_of_different_bodies(p, spec.dp), spec.dp, 1e-9 * spec.dp);
  const ParticleCounts n = count_particles(spec);
  EXPECT_EQ(n.fluid, p.n_of_kind(ParticleKind::fluid));
  EXPECT_EQ(n.wall, p.n_of_kind(ParticleKind::wall));
  EXPECT_EQ(n.dummy, p.n_of_kind(ParticleKind::dummy));
}

TEST(Scene, TooLargeForTheMachineIsRefusedBeforeAllocating) {
  const std::string dam_break = std::string(MPSFSI_TEST_DATA_DIR) + "/../../cases/dam_break.yaml";
  const CaseSpec spec = load_case(dam_break, {"dp=1e-5"});
  try {
    build_scene(spec);  // would need about 780 GiB
    FAIL() << "no error";
  } catch (const CaseError& e) {
    EXPECT_THAT(e.what(), HasSubstr(dam_break + ": dp = 1e-05: the case would have 427020836 particles (426320000 fluid, 0 "
                                    "solid, 233604 wall, 467232 dummy) and need about "));
    EXPECT_THAT(e.what(), HasSubstr("available (MemAvailable in /proc/meminfo, or less under ulimit -v); expected a case that fits: a larger dp"));
  }
  // The same check with a given available memory: the case at its own dp needs about 90 MiB.
  const CaseSpec normal = load_case(dam_break);
  EXPECT_NO_THROW(check_scene_size(normal, std::size_t{1} << 30));
  EXPECT_NO_THROW(check_scene_size(normal, std::nullopt));
  EXPECT_THROW(check_scene_size(normal, std::size_t{64} << 20), CaseError);
  // Above the hard bound whatever the memory.
  CaseSpec huge = normal;
  huge.dp = 1e-6;
  EXPECT_THAT([&] {
    try {
      check_scene_size(huge, std::nullopt);
    } catch (const CaseError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  }(), HasSubstr("dp = 1e-06: the case would have about 4.26e+10 particles; expected at most 1e+09 (a larger dp)"));
  EXPECT_TRUE(available_memory_bytes().has_value());
  // A polygon body is refused by its area ("about" N particles), before it is filled point by point.
  const std::string standing_wave = std::string(MPSFSI_TEST_DATA_DIR) + "/../../cases/standing_wave.yaml";
  const CaseSpec polygon = load_case(standing_wave, {"dp=3e-5"});
  try {
    check_scene_size(polygon, std::size_t{8} << 30);
    ADD_FAILURE() << "no error";
  } catch (const CaseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("dp = 3e-05: the case would have about 1.34e+08 particles and need about "));
  }
  EXPECT_NO_THROW(check_scene_size(load_case(standing_wave), std::size_t{1} << 30));
}

// A 0.16 m body came out 0.16025 m: build_scene gives the extent the particles represent, and for clamped
// solids the free length, which `check` prints (and warns about beyond dp/4).
TEST(Scene, ExtentsAndFreeLength) {
  const CaseSpec spec = parse_case(valid_text(), file_name, {"bodies.column.rectangle={min: [0, 0], max: [0.1625, 0.4]}"});
  const Scene scene = build_scene(spec);
  const BodyCount& column = scene.counts[0];
  EXPECT_NEAR(column.extent.lo[0], 0, 1e-12);
  EXPECT_NEAR(column.extent.hi[0], 0.164, 1e-12);  // round(0.1625 / 0.004) = 41 particles
  EXPECT_NEAR(column.extent.hi[1], 0.4, 1e-12);
  EXPECT_NEAR(column.extent_difference, 0.0015, 1e-12);
  EXPECT_FALSE(column.free_length);
  // The plate: 0.012 x 0.18 m, clamped over its lowest 0.012 m: free length 0.168 m along y.
  const BodyCount& plate = scene.counts[1];
  EXPECT_NEAR(plate.extent_difference, 0, 1e-12);
  ASSERT_TRUE(plate.free_length);
  EXPECT_EQ(plate.free_axis, 1);
  EXPECT_NEAR(*plate.free_length, 0.168, 1e-12);
  EXPECT_NEAR(plate.file_free_length, 0.168, 1e-12);
  EXPECT_EQ(scene.counts[2].kind, "wall");
}

// Walls may overlap in their rectangles, but two walls whose particles coincide (the same block twice) put two
// particles at one point, which the kernel cannot see (r = 0): the scene refuses them like overlapping bodies.
// Thousands of such walls are refused in about a second (the clamped particles are listed once, not per wall).
TEST(Scene, CoincidentWallParticlesAreRefused) {
  std::string walls = "walls:\n";
  for (int k = 0; k < 2000; ++k)
    walls += "  - {name: w" + std::to_string(k) + ", type: block, rectangle: {min: [0.5, 0.5], max: [0.6, 0.6]}}\n";
  const CaseSpec spec = parse_case(std::string(minimal_case) + walls, file_name);
  try {
    build_scene(spec, std::nullopt);
    ADD_FAILURE() << "no error";
  } catch (const CaseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bodies 'w0' and 'w1' overlap: particles at (0.505, 0.505) and (0.505, 0.505)"));
  }
  // One of them is fine.
  const CaseSpec one = parse_case(std::string(minimal_case) + "walls:\n  - {name: w0, type: block, rectangle: {min: [0.5, 0.5], max: [0.6, 0.6]}}\n", file_name);
  EXPECT_NO_THROW(build_scene(one, std::nullopt));
}

// Every body is on the case's lattice, so bodies that touch sit dp apart and a closer pair is refused: here a body
// thinner than dp (0.2995-0.3048 m at dp 0.01 m holds no cell centre, so it keeps one cell from its low side, off the
// lattice) beside water that ends at 0.2995 m puts two particles 0.95 dp apart.
TEST(Scene, BodyThinnerThanDpBesideAnotherIsRefused) {
  const std::string text = replaced(minimal_case, "max: [0.3, 0.3]", "max: [0.2995, 0.3]") +
                           "  - {name: film, kind: fluid, material: water, rectangle: {min: [0.2995, 0.1], max: [0.3048, 0.3]}}\n";
  try {
    build_scene(parse_case(text, file_name), std::nullopt);
    ADD_FAILURE() << "no error";
  } catch (const CaseError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bodies 'block' and 'film' overlap: particles at (0.295, 0.105) and (0.3045, 0.105) "
                                    "are closer than dp = 0.01 m; expected bodies that at most touch (bodies thinner "
                                    "than dp need a smaller dp)"));
  }
  // Thicker than dp, it starts on the lattice, dp from the water.
  const std::string thick = replaced(text, "max: [0.3048, 0.3]", "max: [0.3105, 0.3]");
  EXPECT_NO_THROW(build_scene(parse_case(thick, file_name), std::nullopt));
}

// A block standing on the tank's floor: its two lower corner particles point at their side faces, not at the
// corner on the floor (a fluid particle put back out of the corner cell would land in the seam between block and
// floor); its upper corners and a free block's corners keep their diagonal offsets, its other particles theirs.
TEST(Scene, CornersOnAnotherWallPointAtTheirOpenFaces) {
  const std::string text = std::string(minimal_case) +
                           "walls:\n  - {name: tank, type: box, rectangle: {min: [0, 0], max: [1, 1]}}\n"
                           "  - {name: piston, type: block, rectangle: {min: [0.5, 0], max: [0.54, 0.4]}}\n"
                           "  - {name: free, type: block, rectangle: {min: [0.7, 0.5], max: [0.74, 0.6]}}\n";
  const Scene scene = build_scene(parse_case(text, file_name));
  const ParticleSet& p = scene.particles;
  const auto& s = p.vector_field(wall_surface_field);
  const auto at = [&](const double x, const double y) {
    for (std::size_t i = 0; i < p.size(); ++i)
      if ((p.position[i] - Vec(x, y)).norm() < 1e-9) return i;
    ADD_FAILURE() << "no particle at " << x << ", " << y;
    return std::size_t{0};
  };
  const double h = 0.005;
  EXPECT_LT((s[at(0.505, 0.005)] - Vec(-h, 0)).norm(), 1e-12);  // lower corners: the side faces
  EXPECT_LT((s[at(0.535, 0.005)] - Vec(h, 0)).norm(), 1e-12);
  EXPECT_LT((s[at(0.505, 0.395)] - Vec(-h, h)).norm(), 1e-12);  // upper corners: the corner
  EXPECT_LT((s[at(0.535, 0.395)] - Vec(h, h)).norm(), 1e-12);
  EXPECT_LT((s[at(0.515, 0.005)] - Vec(0, -h)).norm(), 1e-12);  // the bottom row between them: the floor face, as built
  EXPECT_LT((s[at(0.705, 0.505)] - Vec(-h, -h)).norm(), 1e-12);  // a free block's corner
  EXPECT_LT((s[at(0.005, -0.005)] - Vec(0, h)).norm(), 1e-12);  // the tank's floor
}

// A wall given by its surface that rests on another (a 1:10 beach on the tank's floor, its end against the tank's
// right wall): the particles whose nearest surface point lies on a covered face (the foot on the floor, the end at
// the wall) point at the foot of the perpendicular onto the wetted slope's plane instead; the others keep their
// offsets to the slope. So every particle of the beach points at the slope: x + s on its line, s along its normal.
TEST(Scene, ShapedWallOnAnotherPointsAtItsWettedFace) {
  const std::string text = std::string(minimal_case) +
                           "walls:\n  - {name: tank, type: box, rectangle: {min: [0, 0], max: [1, 1]}}\n"
                           "  - {name: beach, type: polygon, polygon: {points: [[0.4, 0], [1.0, 0.06], [1.0, 0]]}}\n";
  const Scene scene = build_scene(parse_case(text, file_name));
  const ParticleSet& p = scene.particles;
  const auto& s = p.vector_field(wall_surface_field);
  const Vec normal = Vec(-0.06, 0.6).normalized();  // the slope's, towards the water
  const Vec toe(0.4, 0);
  std::size_t n_near = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.bodies[static_cast<std::size_t>(p.body[i])].name != "beach") continue;
    const Real depth = (toe - p.position[i]).dot(normal);  // below the slope's line
    if (depth > 3 * 0.01) continue;  // deeper than the wall layer and two dummy layers below the slope
    ++n_near;
    EXPECT_NEAR((p.position[i] + s[i] - toe).dot(normal), 0.0, 1e-12) << p.position[i].transpose();
    EXPECT_NEAR(s[i].dot(normal), depth, 1e-12) << p.position[i].transpose();
  }
  EXPECT_GT(n_near, 100u);
  // The floor under the beach's toe (0.4 < x < 0.45, where the slope is less than dp/2 high and the beach has no
  // particles) points at the slope's plane, not at its own face that the beach's foot covers.
  std::size_t n_sliver = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.bodies[static_cast<std::size_t>(p.body[i])].name != "tank" || p.position[i][1] > 0) continue;
    const Real x = p.position[i][0];
    if (x < 0.4 + 1e-9 || x > 0.45 - 1e-9) continue;
    ++n_sliver;
    EXPECT_NEAR((p.position[i] + s[i] - toe).dot(normal), 0.0, 1e-9) << p.position[i].transpose();
    EXPECT_NEAR(s[i].normalized().dot(normal), 1.0, 1e-9) << p.position[i].transpose();
  }
  EXPECT_EQ(n_sliver, 5u * 3u);  // five columns of the wall layer and its two dummy layers
}

// A body may be a disc (`sphere`) or a cylinder's section instead of a rectangle, a wall a solid disc or cylinder;
// the scene fills them on the lattice (core/geometry.hpp), `rect` holds their bounds, and count_particles
// counts them exactly.
TEST(CaseFile, RoundBodiesAndWalls) {
  const std::string text = replaced(minimal_case, "rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}",
                                    "sphere: {centre: [0.2, 0.2], radius: 0.05}") +
                           "walls:\n  - {name: pile, type: cylinder, cylinder: {base: [0.6, 0.1], axis: [0, 0.3], "
                           "radius: 0.04}}\n  - {name: ball, type: sphere, sphere: {centre: [0.8, 0.8], radius: 0.1}}\n";
  const CaseSpec spec = parse_case(text, file_name);
  ASSERT_TRUE(spec.bodies[0].round);
  EXPECT_EQ(spec.bodies[0].round->kind, RoundShape::Kind::sphere);
  EXPECT_DOUBLE_EQ(spec.bodies[0].round->radius, 0.05);
  EXPECT_NEAR(spec.bodies[0].rect.lo[0], 0.15, 1e-15);
  EXPECT_NEAR(spec.bodies[0].rect.hi[1], 0.25, 1e-15);
  ASSERT_EQ(spec.walls.size(), 2u);
  EXPECT_EQ(spec.walls[0].type, WallType::cylinder);
  EXPECT_NEAR(spec.walls[0].rect.lo[0], 0.56, 1e-15);
  EXPECT_NEAR(spec.walls[0].rect.hi[1], 0.4, 1e-15);
  EXPECT_EQ(spec.walls[1].type, WallType::sphere);
  const Scene scene = build_scene(spec);
  const auto& p = scene.particles;
  EXPECT_EQ(p.n_of_kind(ParticleKind::fluid), fill_sphere(Vec(0.2, 0.2), 0.05, 0.01).size());
  const std::size_t walls = cylinder_walls(Vec(0.6, 0.1), Vec(0, 0.3), 0.04, 0.01).size() +
                            sphere_walls(Vec(0.8, 0.8), 0.1, 0.01).size();
  EXPECT_EQ(p.n_of_kind(ParticleKind::wall) + p.n_of_kind(ParticleKind::dummy), walls);
  const ParticleCounts n = count_particles(spec);
  EXPECT_EQ(n.fluid, p.n_of_kind(ParticleKind::fluid));
  EXPECT_EQ(n.wall, p.n_of_kind(ParticleKind::wall));
  EXPECT_EQ(n.dummy, p.n_of_kind(ParticleKind::dummy));
  ASSERT_TRUE(scene.counts[0].shape_volume);
  EXPECT_NEAR(*scene.counts[0].shape_volume, pi * 0.05 * 0.05, 1e-15);
}

TEST(CaseFileErrors, RoundShapes) {
  const std::string two = replaced(minimal_case, "rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}",
                                   "rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}, sphere: {centre: [0.5, 0.5], radius: 0.1}");
  EXPECT_THAT(error_of(two), HasSubstr("'rectangle' and 'sphere' given; expected one shape: rectangle, sphere, cylinder or polygon"));
  const std::string bad_radius = replaced(minimal_case, "rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}",
                                          "sphere: {centre: [0.2, 0.2], radius: -0.1}");
  EXPECT_THAT(error_of(bad_radius), HasSubstr("radius = -0.1: expected a positive radius in metres"));
  const std::string no_axis = replaced(minimal_case, "rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}",
                                       "cylinder: {base: [0.2, 0.2], axis: [0, 0], radius: 0.1}");
  EXPECT_THAT(error_of(no_axis), HasSubstr("axis = [0, 0]: expected a non-zero axis [x, y] in metres"));
  const std::string outside = replaced(minimal_case, "rectangle: {min: [0.1, 0.1], max: [0.3, 0.3]}",
                                       "sphere: {centre: [0.95, 0.5], radius: 0.1}");
  EXPECT_THAT(error_of(outside), HasSubstr("lies outside the domain"));
  const std::string wall_shape = std::string(minimal_case) +
                                 "walls:\n  - {name: w, type: sphere, rectangle: {min: [0.5, 0.5], max: [0.6, 0.6]}}\n";
  EXPECT_THAT(error_of(wall_shape), HasSubstr("missing key 'sphere'"));
  const std::string box_with_sphere = std::string(minimal_case) +
      "walls:\n  - {name: w, type: box, rectangle: {min: [0, 0], max: [1, 1]}, sphere: {centre: [0.5, 0.5], radius: 0.1}}\n";
  EXPECT_THAT(error_of(box_with_sphere), HasSubstr("unknown key 'sphere'"));
  // A body in the way of a round wall, by the wall's bounds.
  const std::string overlap = std::string(minimal_case) +
      "walls:\n  - {name: ball, type: sphere, sphere: {centre: [0.35, 0.2], radius: 0.1}}\n";
  EXPECT_THAT(error_of(overlap), HasSubstr("bodies must not overlap walls"));
}

// A wall's own motion: a translation and a rotation with start, ramp and stop, read into WallMotionSpec and passed
// to the fluid by the wall's name.
TEST(CaseFile, WallMotion) {
  const std::string text = std::string(minimal_case) +
                           "walls:\n  - name: piston\n    type: block\n    rectangle: {min: [0.5, 0], max: [0.52, 0.2]}\n"
                           "    motion: {translation: {type: sine, amplitude: [0.05, 0], period: 1.2}, rotation: {type: "
                           "sine, pivot: [0.5, 0], amplitude_deg: 10, period: 2}, start: 0.1, ramp: 0.5, stop: 4}\n";
  const CaseSpec spec = parse_case(text, file_name);
  const WallMotionSpec& m = spec.walls[0].motion;
  EXPECT_EQ(m.translation, WallMotionSpec::Translation::sine);
  EXPECT_DOUBLE_EQ(m.amplitude[0], 0.05);
  EXPECT_DOUBLE_EQ(m.period, 1.2);
  EXPECT_EQ(m.rotation, WallMotionSpec::Rotation::sine);
  EXPECT_DOUBLE_EQ(m.angle_amplitude, 10 * deg);
  EXPECT_DOUBLE_EQ(m.angle_period, 2);
  EXPECT_DOUBLE_EQ(m.start, 0.1);
  EXPECT_DOUBLE_EQ(m.ramp, 0.5);
  EXPECT_DOUBLE_EQ(m.stop, 4);
  const FluidSetup setup = fluid_setup(spec);
  ASSERT_EQ(setup.wall_motions.size(), 1u);
  EXPECT_EQ(setup.wall_motions[0].first, "piston");
  EXPECT_EQ(parse_case(replaced(text, ", start: 0.1, ramp: 0.5, stop: 4", ""), file_name).walls[0].motion.stop,
            std::numeric_limits<Real>::infinity());
}

TEST(CaseFileErrors, WallMotion) {
  const std::string wall = std::string(minimal_case) +
                           "walls:\n  - {name: gate, type: block, rectangle: {min: [0.5, 0], max: [0.52, 0.2]}, motion: MOTION}\n";
  const auto with = [&](const std::string& motion) { return replaced(wall, "MOTION", motion); };
  EXPECT_THAT(error_of(with("{start: 1}")), HasSubstr("walls[0].motion: no translation and no rotation; expected a motion"));
  EXPECT_THAT(error_of(with("{translation: {type: velocity, velocity: [0, 1]}, start: 1, stop: 0.5}")),
              HasSubstr("stop = 0.5: expected a time > start [s]"));
  EXPECT_THAT(error_of(with("{translation: {type: spin}}")), HasSubstr("type = spin"));
  EXPECT_THAT(error_of(with("{translation: {type: sine, amplitude: [0.1, 0], period: 0}}")),
              HasSubstr("period = 0: expected a positive period [s]"));
  EXPECT_THAT(error_of(with("{rotation: {type: sine, pivot: [0, 0], amplitude_deg: 95, period: 1}}")),
              HasSubstr("amplitude_deg = 95: expected a number of degrees in (-90, 90)"));
  EXPECT_THAT(error_of(with("{translation: {type: velocity, velocity: [0, 1]}, ramp: -1}")), HasSubstr("ramp = -1"));
  EXPECT_THAT(error_of(with("{translation: {type: velocity, velocity: [0, 1]}, speed: 2}")), HasSubstr("unknown key 'speed'"));
  // The tank moves or its walls on their own, not both.
  const std::string both = with("{translation: {type: velocity, velocity: [0, 1]}}") +
                           "tank_motion: {type: sine_roll, pivot: [0.5, 0], amplitude_deg: 4, period: 1.2}\n";
  EXPECT_THAT(error_of(both), HasSubstr("tank_motion.type = sine_roll and wall 'gate' has a motion of its own"));
}

// Wave makers by stroke and period: a piston translates by S/2 along the direction; a flap turns about its hinge by
// atan(S / 2d), d the still water level above the hinge, its top moving along the direction first.
TEST(CaseFile, WaveMaker) {
  const std::string wall = std::string(minimal_case) +
                           "walls:\n  - {name: paddle, type: block, rectangle: {min: [0.5, 0], max: [0.52, 0.2]}, motion: MOTION}\n";
  const auto motion = [&](const std::string& m) { return parse_case(replaced(wall, "MOTION", m), file_name).walls[0].motion; };
  const WallMotionSpec piston = motion("{wave_maker: {type: piston, stroke: 0.04, period: 1.5}, ramp: 3}");
  EXPECT_EQ(piston.translation, WallMotionSpec::Translation::sine);
  EXPECT_EQ(piston.rotation, WallMotionSpec::Rotation::none);
  EXPECT_DOUBLE_EQ(piston.amplitude[0], 0.02);
  EXPECT_DOUBLE_EQ(piston.amplitude[1], 0);
  EXPECT_DOUBLE_EQ(piston.period, 1.5);
  EXPECT_DOUBLE_EQ(piston.ramp, 3);
  EXPECT_DOUBLE_EQ(motion("{wave_maker: {type: piston, stroke: 0.04, period: 1.5, direction: [-2, 0]}}").amplitude[0], -0.02);
  const WallMotionSpec flap =
      motion("{wave_maker: {type: flap, stroke: 0.1, period: 2, hinge: [0.5, -0.1], water_level: 0.15}}");
  EXPECT_EQ(flap.translation, WallMotionSpec::Translation::none);
  EXPECT_EQ(flap.rotation, WallMotionSpec::Rotation::sine);
  EXPECT_DOUBLE_EQ(flap.pivot[0], 0.5);
  EXPECT_DOUBLE_EQ(flap.pivot[1], -0.1);
  EXPECT_DOUBLE_EQ(flap.angle_amplitude, -std::atan(0.05 / 0.25));
  EXPECT_DOUBLE_EQ(flap.angle_period, 2);
  // At the quarter period the flap crosses the still water level S/2 along the direction: its point at
  // sqrt(d^2 + (S/2)^2) above the hinge is there.
  const Vec x0(0.5, -0.1 + std::hypot(0.25, 0.05));
  const Vec top = WallMotion(flap).place(x0, 0.5);
  EXPECT_NEAR(top[0], 0.55, 1e-15);
  EXPECT_NEAR(top[1], 0.15, 1e-15);
  const WallMotionSpec back =
      motion("{wave_maker: {type: flap, stroke: 0.1, period: 2, hinge: [0.5, -0.1], water_level: 0.15, direction: [-1, 0]}}");
  EXPECT_NEAR(WallMotion(back).place(x0, 0.5)[0], 0.45, 1e-15);
}

TEST(CaseFileErrors, WaveMaker) {
  const std::string wall = std::string(minimal_case) +
                           "walls:\n  - {name: paddle, type: block, rectangle: {min: [0.5, 0], max: [0.52, 0.2]}, motion: MOTION}\n";
  const auto with = [&](const std::string& motion) { return replaced(wall, "MOTION", motion); };
  EXPECT_THAT(error_of(with("{wave_maker: {type: piston, stroke: 0.04, period: 1}, translation: {type: velocity, velocity: [0, 1]}}")),
              HasSubstr("walls[0].motion.translation: a wall's motion is a wave_maker or a translation and rotation"));
  EXPECT_THAT(error_of(with("{wave_maker: {type: wedge, stroke: 0.04, period: 1}}")), HasSubstr("type = wedge"));
  EXPECT_THAT(error_of(with("{wave_maker: {type: piston, stroke: 0, period: 1}}")),
              HasSubstr("stroke = 0: expected the paddle's stroke S > 0 [m]"));
  EXPECT_THAT(error_of(with("{wave_maker: {type: piston, stroke: 0.04}}")), HasSubstr("missing key 'period'"));
  EXPECT_THAT(error_of(with("{wave_maker: {type: piston, stroke: 0.04, period: 1, direction: [0, 1]}}")),
              HasSubstr("direction = [0, 1]: expected a horizontal direction"));
  EXPECT_THAT(error_of(with("{wave_maker: {type: flap, stroke: 0.04, period: 1, hinge: [0.5, 0.2], water_level: 0.1}}")),
              HasSubstr("water_level = 0.1: expected a still water level above the hinge (height 0.2 m)"));
  EXPECT_THAT(error_of(with("{wave_maker: {type: flap, stroke: 0.04, period: 1, water_level: 0.1}}")), HasSubstr("missing key 'hinge'"));
  EXPECT_THAT(error_of(with("{wave_maker: {type: piston, stroke: 0.04, period: 1, hinge: [0, 0]}}")), HasSubstr("unknown key 'hinge'"));
}

/// The error of load_case on dir/case.yaml holding `text`.
std::string load_error_of(const fs::path& dir, const std::string& text) {
  std::ofstream(dir / "case.yaml") << text;
  try {
    load_case((dir / "case.yaml").string());
  } catch (const CaseError& e) {
    return e.what();
  }
  return "(no error)";
}

// Motion tables: a translation along a direction and a rotation about a pivot, each from a CSV file relative to
// the case file (time from start, displacement in m or angle in degrees); case.resolved.yaml names the files by
// their absolute paths, so that it runs from any folder.
TEST(CaseFile, WallMotionTables) {
  const TempDir dir("mpsfsi_test_case_file_wall_tables");
  std::ofstream(dir.path / "paddle.csv") << "# time [s], displacement [m]\n0, 0\n0.5, 0.01\n1.0, 0\n";
  std::ofstream(dir.path / "flap.csv") << "0, 0\n1, 5\n";
  const std::string text = std::string(minimal_case) +
                           "walls:\n  - {name: paddle, type: block, rectangle: {min: [0.5, 0], max: [0.52, 0.2]}, motion: "
                           "{translation: {type: table, file: paddle.csv, direction: [2, 0]}, rotation: {type: table, file: "
                           "flap.csv, pivot: [0.5, 0], half_window: 0.01}, start: 0.2}}\n";
  std::ofstream(dir.path / "case.yaml") << text;
  const CaseSpec spec = load_case((dir.path / "case.yaml").string());
  const WallMotionSpec& m = spec.walls[0].motion;
  EXPECT_EQ(m.translation, WallMotionSpec::Translation::table);
  EXPECT_EQ(m.direction, Vec::UnitX());
  EXPECT_EQ(m.table_time, (std::vector<Real>{0, 0.5, 1.0}));
  EXPECT_EQ(m.table_value, (std::vector<Real>{0, 0.01, 0}));
  EXPECT_DOUBLE_EQ(m.table_half_window, 0.025);
  EXPECT_EQ(m.rotation, WallMotionSpec::Rotation::table);
  EXPECT_EQ(m.angle_time, (std::vector<Real>{0, 1}));
  EXPECT_DOUBLE_EQ(m.angle_value[1], 5 * deg);
  EXPECT_DOUBLE_EQ(m.angle_half_window, 0.01);
  EXPECT_DOUBLE_EQ(m.start, 0.2);
  EXPECT_NEAR(WallMotion(m).displacement(0.45)[0], 0.005, 1e-15);
  // The resolved case names both files by absolute paths and reads back to the same motion from elsewhere.
  const std::string paddle = fs::absolute(dir.path / "paddle.csv").lexically_normal().string();
  EXPECT_THAT(spec.resolved_yaml, HasSubstr(paddle));
  EXPECT_THAT(spec.resolved_yaml, HasSubstr(fs::absolute(dir.path / "flap.csv").lexically_normal().string()));
  EXPECT_THAT(spec.resolved_yaml, Not(HasSubstr("file: paddle.csv")));
  const CaseSpec again = parse_case(spec.resolved_yaml, "case.resolved.yaml", {}, "/nonexistent");
  EXPECT_EQ(again.walls[0].motion.table_value, m.table_value);
  EXPECT_EQ(again.resolved_yaml, spec.resolved_yaml);
}

TEST(CaseFileErrors, WallMotionTables) {
  const TempDir dir("mpsfsi_test_case_file_wall_table_errors");
  std::ofstream(dir.path / "paddle.csv") << "0, 0\n0.5, 0.01\n";
  std::ofstream(dir.path / "jump.csv") << "0, 0\n1e-6, 0.1\n";
  std::ofstream(dir.path / "flap.csv") << "0, 0\n1, 95\n";
  const std::string wall = std::string(minimal_case) +
                           "walls:\n  - {name: paddle, type: block, rectangle: {min: [0.5, 0], max: [0.52, 0.2]}, motion: MOTION}\n";
  const auto error = [&](const std::string& motion) { return load_error_of(dir.path, replaced(wall, "MOTION", motion)); };
  EXPECT_THAT(error("{translation: {type: table, file: missing.csv, direction: [1, 0]}}"),
              HasSubstr("walls[0].motion.translation.file = missing.csv: no such file"));
  EXPECT_THAT(error("{translation: {type: table, file: paddle.csv}}"), HasSubstr("missing key 'direction'"));
  EXPECT_THAT(error("{translation: {type: table, file: paddle.csv, direction: [0, 0]}}"),
              HasSubstr("direction = [0, 0]: expected a non-zero direction"));
  EXPECT_THAT(error("{translation: {type: table, file: jump.csv, direction: [1, 0]}}"),
              HasSubstr("file = jump.csv: expected a table whose displacement changes at most 10000 m/s (it changes at 1e+05 m/s)"));
  EXPECT_THAT(error("{translation: {type: table, file: paddle.csv, direction: [1, 0], half_window: 0}}"),
              HasSubstr("half_window = 0: expected a positive time [s]"));
  EXPECT_THAT(error("{translation: {type: table, file: paddle.csv, direction: [1, 0], period: 1}}"), HasSubstr("unknown key 'period'"));
  EXPECT_THAT(error("{rotation: {type: table, file: flap.csv, pivot: [0.5, 0]}}"),
              HasSubstr("rotation.file = flap.csv: " + (dir.path / "flap.csv").string() + ":2"));
  EXPECT_THAT(error("{rotation: {type: table, file: flap.csv, pivot: [0.5, 0]}}"), HasSubstr("an angle in (-90, 90) degrees"));
  EXPECT_THAT(error("{rotation: {type: table, file: paddle.csv}}"), HasSubstr("missing key 'pivot'"));
}

// A solid's clamp that reaches into a wall with a motion of its own moves with that wall (the solid's setup gets the
// motion by the body's name); a clamp in two moving walls is refused.
TEST(CaseFile, ClampInAMovingWallMovesWithIt) {
  const std::string text = std::string(minimal_case) +
                           "  - {name: plate, kind: solid, material: rubber, rectangle: {min: [0.55, 0.19], max: [0.56, 0.3]}, "
                           "clamp: {min: [0.545, 0.185], max: [0.565, 0.2]}}\n"
                           "walls:\n  - {name: paddle, type: block, rectangle: {min: [0.5, 0], max: [0.6, 0.2]}, motion: "
                           "{translation: {type: sine, amplitude: [0.02, 0], period: 1}}}\n"
                           "  - {name: step, type: block, rectangle: {min: [0.7, 0], max: [0.8, 0.2]}}\n";
  const std::string with_rubber = replaced(text, "materials:\n", "materials:\n  rubber: {type: solid, rho: 1100, E: 2.0e6, nu: 0.0}\n");
  const CaseSpec spec = parse_case(with_rubber, file_name);
  ASSERT_EQ(spec.bodies.size(), 2u);
  EXPECT_EQ(spec.bodies[1].clamp_wall, "paddle");
  const SolidSetup setup = solid_setup(spec);
  ASSERT_EQ(setup.clamp_motions.size(), 1u);
  EXPECT_EQ(setup.clamp_motions[0].first, "plate");
  EXPECT_EQ(setup.clamp_motions[0].second.translation, WallMotionSpec::Translation::sine);
  // Without the paddle's motion the clamp stays (a wall at rest holds it as the floor does).
  EXPECT_EQ(parse_case(replaced(with_rubber, ", motion: {translation: {type: sine, amplitude: [0.02, 0], period: 1}}", ""),
                       file_name).bodies[1].clamp_wall, "");
  // A clamp that reaches two moving walls.
  const std::string two = replaced(with_rubber, "max: [0.8, 0.2]}}", "max: [0.8, 0.2]}, motion: {translation: {type: velocity, velocity: [0, 0.1]}}}");
  const std::string wide = replaced(two, "clamp: {min: [0.545, 0.185], max: [0.565, 0.2]}", "clamp: {min: [0.545, 0.185], max: [0.70, 0.2]}");
  EXPECT_THAT(error_of(wide), HasSubstr("bodies[1].clamp = "));
  EXPECT_THAT(error_of(wide), HasSubstr("reaches into two walls that move, 'paddle' and 'step'; expected a clamp in one moving wall at most"));
}
