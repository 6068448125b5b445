// Bodies and walls given by closed surfaces (io/surface.hpp; in 2D polygons, in 3D STL and OBJ files): a box given
// as a surface gives the built-in rectangle's, box tank's and block's particles; a tessellated cylinder the built-in
// cylinder's; a body with an obstacle subtracted fills every lattice point outside it, up to the obstacle's wall
// points; bad surfaces are refused with the key, the value and what is wrong.
#include "core/geometry.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"
#include "io/surface.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

using namespace mpsfsi;
using ::testing::HasSubstr;

namespace {

namespace fs = std::filesystem;

/// A folder of this test process for the surface files.
fs::path work_dir() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / ("mpsfsi_test_surface_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

std::string write_file(const std::string& name, const std::string& text) {
  const fs::path path = work_dir() / name;
  std::ofstream(path) << text;
  return path.string();
}

/// `text` with the first occurrence of `from` (which must occur) replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << "test bug: '" << from << "' is not in the text";
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

/// The CaseError message of parsing `text` (relative files from the work folder), or "(no error)".
std::string error_of(const std::string& text) {
  try {
    parse_case(text, "cases/x.yaml", {}, work_dir().string());
  } catch (const CaseError& e) {
    return e.what();
  }
  return "(no error)";
}

/// Two scenes have the same particles: positions (to `tolerance`), kinds and wall offsets, in the same order.
void expect_same_particles(const Scene& a, const Scene& b, const Real tolerance) {
  const auto& p = a.particles;
  const auto& q = b.particles;
  ASSERT_EQ(p.size(), q.size());
  const auto& sa = p.vector_field(wall_surface_field);
  const auto& sb = q.vector_field(wall_surface_field);
  for (std::size_t i = 0; i < p.size(); ++i) {
    ASSERT_EQ(p.kind[i], q.kind[i]) << i;
    ASSERT_LE((p.position[i] - q.position[i]).norm(), tolerance) << i << ": " << p.position[i].transpose();
    if (p.kind[i] == ParticleKind::wall || p.kind[i] == ParticleKind::dummy) {
      ASSERT_LE((sa[i] - sb[i]).norm(), 1e-12) << i << ": " << p.position[i].transpose();
    }
  }
}

/// The counts of count_particles are those of the built scene.
void expect_counts_of(const CaseSpec& spec, const Scene& scene) {
  const ParticleCounts n = count_particles(spec);
  const auto& p = scene.particles;
  EXPECT_EQ(n.fluid, p.n_of_kind(ParticleKind::fluid));
  EXPECT_EQ(n.solid, p.n_of_kind(ParticleKind::solid));
  EXPECT_EQ(n.wall, p.n_of_kind(ParticleKind::wall));
  EXPECT_EQ(n.dummy, p.n_of_kind(ParticleKind::dummy));
}

/// Every lattice point of `rect` (a body's rectangle on the case's lattice, origin at its corner) next to an
/// obstacle subtracted from the body holds one particle: the body's where `distance` (the obstacle's, positive
/// outside) is above `on_surface`, the obstacle's wall or dummy particle where the point lies less than the wall and
/// dummy layers (3 dp) deep, closer to the surface than on_surface either (`surface_points_are_walls`); so the body
/// leaves no empty points along the obstacle's surface, whether the surface lies on the lattice or not.
void expect_no_gap_at(const Scene& scene, const Rect& rect, const Real dp, const SignedDistance& distance,
                      const bool surface_points_are_walls) {
  const auto key = [&](const Vec& x) {
    std::array<long long, dim> k{};
    for (int a = 0; a < dim; ++a) k[a] = std::llround((x[a] - rect.lo[a]) / dp - 0.5);
    return k;
  };
  std::map<std::array<long long, dim>, std::vector<ParticleKind>> at;
  const auto& p = scene.particles;
  for (std::size_t i = 0; i < p.size(); ++i) at[key(p.position[i])].push_back(p.kind[i]);
  const Real on_surface = surface_tolerance * dp;
  std::size_t n_near = 0;
  Vec nearest;
  for (const Vec& x : fill_rectangle(rect.lo, rect.hi, dp)) {
    const Real d = distance(x, nearest);
    if (d <= -3 * dp || d > 3 * dp) continue;  // deep inside the obstacle, or far from it
    ++n_near;
    const auto it = at.find(key(x));
    ASSERT_TRUE(it != at.end() && it->second.size() == 1) << "no particle, or more than one, at " << x.transpose();
    const bool wall_side = surface_points_are_walls ? d <= on_surface : d < -on_surface;
    EXPECT_EQ(it->second[0] == ParticleKind::fluid, !wall_side) << x.transpose() << " at distance " << d;
  }
  EXPECT_GT(n_near, 0u);
}

}  // namespace

#if MPSFSI_DIM == 2

namespace {

/// Water in an open box tank and a pile (a disc obstacle) in the water's way, on the lattice of dp 0.01.
const char* const tank_case = R"(name: polygons
description: a water column in a tank
source: tests
dp: 0.01
domain: {min: [-0.1, -0.1], max: [1.1, 1.1]}
time: {end: 0.5, dt: 1.0e-4}
materials:
  water: {type: fluid, rho: 1000, nu: 1.0e-6}
bodies:
  - {name: column, kind: fluid, material: water, rectangle: {min: [0, 0], max: [0.3, 0.4]}}
walls:
  - {name: tank, type: box, rectangle: {min: [0, 0], max: [1, 0.8]}}
)";


}  // namespace

// A polygon square is the rectangle, a polygon tank with an open top is the box tank, point for point; the points
// may come from a file, and be scaled, rotated and translated.
TEST(Surface, PolygonsAreTheRectangleAndTheBox) {
  const CaseSpec boxes = parse_case(tank_case, "cases/x.yaml");
  const Scene reference = build_scene(boxes);
  const std::string polygons =
      replaced(replaced(tank_case, "rectangle: {min: [0, 0], max: [0.3, 0.4]}",
                        "polygon: {points: [[0, 0], [0.3, 0], [0.3, 0.4], [0, 0.4]]}"),
               "type: box, rectangle: {min: [0, 0], max: [1, 0.8]}",
               "type: polygon, polygon: {points: [[0, 0], [0, 0.8], [1, 0.8], [1, 0]]}, fluid: inside, open_top: true");
  const CaseSpec spec = parse_case(polygons, "cases/x.yaml");
  ASSERT_TRUE(spec.bodies[0].surface);
  EXPECT_NEAR(spec.bodies[0].surface->volume(), 0.12, 1e-15);
  EXPECT_EQ(spec.walls[0].type, WallType::surface);
  EXPECT_TRUE(spec.walls[0].is_container());
  const Scene scene = build_scene(spec);
  expect_same_particles(scene, reference, 0);
  expect_counts_of(spec, scene);
  ASSERT_TRUE(scene.counts[0].shape_volume);
  EXPECT_EQ(scene.counts[0].shape, "polygon");
  EXPECT_EQ(scene.counts[0].shape_source, "a polygon of 4 points, 4 edges");
  // The tank's points in a file ("x y" or "x, y", comments), the column as a unit square scaled, rotated by 90
  // degrees about the origin and translated: the same particles to round-off.
  write_file("tank.txt", "# the tank\n0 0\n0, 0.8\n\n1 0.8  # top right\n1 0\n");
  const std::string from_file =
      replaced(replaced(tank_case, "rectangle: {min: [0, 0], max: [0.3, 0.4]}",
                        "polygon: {points: [[0, 0], [1, 0], [1, 1], [0, 1]], scale: [0.4, 0.3], rotate: 90, "
                        "translate: [0.3, 0]}"),
               "type: box, rectangle: {min: [0, 0], max: [1, 0.8]}",
               "type: polygon, polygon: {file: tank.txt}, fluid: inside, open_top: true");
  const CaseSpec spec2 = parse_case(from_file, "cases/x.yaml", {}, work_dir().string());
  expect_same_particles(build_scene(spec2), reference, 1e-12);
}

// An L-shaped tank (a step in the floor): a concave corner and a convex one. Its wall layer is every lattice point
// outside the polygon next to (in the 3 x 3 stencil) a point inside, its dummies the next two layers; no wall point
// is inside.
TEST(Surface, ConcavePolygonTankHasThreeLayersEverywhere) {
  const std::string text = replaced(
      replaced(tank_case, "rectangle: {min: [0, 0], max: [0.3, 0.4]}", "rectangle: {min: [0, 0.2], max: [0.3, 0.4]}"),
      "type: box, rectangle: {min: [0, 0], max: [1, 0.8]}",
      "type: polygon, polygon: {points: [[0, 0.2], [0.5, 0.2], [0.5, 0], [1, 0], [1, 0.8], [0, 0.8]]}, fluid: inside");
  const CaseSpec spec = parse_case(text, "cases/x.yaml");
  const Scene scene = build_scene(spec);
  expect_counts_of(spec, scene);
  const auto& p = scene.particles;
  const Real dp = spec.dp;
  Vec nearest;
  const auto inside = [&](const Vec& x) { return spec.walls[0].surface->signed_distance(x, nearest) < 0; };
  std::size_t n_wall = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.kind[i] != ParticleKind::wall && p.kind[i] != ParticleKind::dummy) continue;
    EXPECT_FALSE(inside(p.position[i])) << p.position[i].transpose();
    bool next_to_fluid = false;
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b) next_to_fluid = next_to_fluid || inside(p.position[i] + dp * Vec(Real(a), Real(b)));
    EXPECT_EQ(next_to_fluid, p.kind[i] == ParticleKind::wall) << p.position[i].transpose();
    n_wall += p.kind[i] == ParticleKind::wall;
  }
  // The wall layer of the closed polygon: a cell along each dp of its outline of 3.6 m, one more at each of its 5
  // convex corners and one less at its concave corner.
  EXPECT_EQ(n_wall, 360u + 5u - 1u);
}

// A body with obstacles subtracted: the water fills the tank around a disc and a ramp (a polygon whose slope lies
// off the lattice). No water particle is inside either, and every lattice point next to their surfaces is the
// water's or the obstacle's: the body leaves no empty points along a face off the lattice. The scene has no overlap
// (build_scene checks it).
TEST(Surface, SubtractCutsAnObstacleOutOfABody) {
  const std::string text =
      replaced(tank_case, "rectangle: {min: [0, 0], max: [0.3, 0.4]}}",
               "rectangle: {min: [0, 0], max: [0.3, 0.4]}, subtract: [pile, ramp]}") +
      "  - {name: pile, type: sphere, sphere: {centre: [0.15, 0.2], radius: 0.0537}}\n"
      "  - {name: ramp, type: polygon, polygon: {points: [[0.05, 0.03], [0.25, 0.03], [0.25, 0.1]]}}\n";
  const CaseSpec spec = parse_case(text, "cases/x.yaml");
  ASSERT_EQ(spec.bodies[0].subtract, (std::vector<std::string>{"pile", "ramp"}));
  const Scene scene = build_scene(spec);
  expect_counts_of(spec, scene);
  const auto& p = scene.particles;
  const SignedDistance pile = sphere_distance(Vec(0.15, 0.2), 0.0537);
  const SignedDistance ramp = ClosedSurface::distance_function(spec.walls[2].surface);
  std::size_t n_fluid = 0;
  Vec nearest;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.kind[i] != ParticleKind::fluid) continue;
    ++n_fluid;
    EXPECT_GT(pile(p.position[i], nearest), 0.0);
    EXPECT_GE(ramp(p.position[i], nearest), 0.0);
  }
  const Rect body{Vec(0, 0), Vec(0.3, 0.4)};
  std::size_t n_cut = 0;
  for (const Vec& x : fill_rectangle(body.lo, body.hi, spec.dp))
    n_cut += pile(x, nearest) <= surface_tolerance * spec.dp || ramp(x, nearest) < -surface_tolerance * spec.dp;
  EXPECT_EQ(n_fluid, 30 * 40 - n_cut);
  EXPECT_GT(n_cut, 0u);
  expect_no_gap_at(scene, body, spec.dp, pile, true);
  expect_no_gap_at(scene, body, spec.dp, ramp, false);
  // Without the pile in subtract the body overlaps it.
  const std::string overlapping = replaced(text, "subtract: [pile, ramp]", "subtract: [ramp]");
  EXPECT_THAT(error_of(overlapping), HasSubstr("bodies must not overlap walls (or list the wall in the body's subtract)"));
  EXPECT_THAT(error_of(replaced(text, "subtract: [pile, ramp]", "subtract: [rock]")),
              HasSubstr("bodies[0].subtract: 'rock' is not a wall of the case; expected names of walls"));
  EXPECT_THAT(error_of(replaced(text, "subtract: [pile, ramp]", "subtract: [tank]")),
              HasSubstr("'tank' is a tank (the fluid is inside it); expected obstacles"));
}

// Bad polygons: each message names the key and says what is wrong.
TEST(SurfaceErrors, Polygons) {
  const auto with_polygon = [](const std::string& polygon) {
    return replaced(tank_case, "rectangle: {min: [0, 0], max: [0.3, 0.4]}", "polygon: " + polygon);
  };
  EXPECT_THAT(error_of(with_polygon("{points: [[0.1, 0.1], [0.3, 0.3], [0.3, 0.1], [0.1, 0.3]]}")),
              HasSubstr("bodies[0].polygon: the polygon crosses itself: its edges 1-2 and 3-4 meet; expected a simple polygon"));
  EXPECT_THAT(error_of(with_polygon("{points: [[0.1, 0.1], [0.3, 0.3]]}")),
              HasSubstr("bodies[0].polygon: a polygon of 2 points; expected at least 3 points"));
  EXPECT_THAT(error_of(with_polygon("{points: [[0.1, 0.1], [0.3, 0.1], [0.3, 0.1], [0.1, 0.3]]}")),
              HasSubstr("the polygon's points 2 and 3 are the same"));
  EXPECT_THAT(error_of(with_polygon("{points: [[0.1, 0.1], [0.2, 0.1], [0.3, 0.1]]}")),
              HasSubstr("the polygon encloses no area"));
  EXPECT_THAT(error_of(with_polygon("{points: [[0.1, 0.1], [0.3, 0.1], [0.3, 0.3]], file: a.txt}")),
              HasSubstr("bodies[0].polygon: both points and file given; expected a polygon {points"));
  EXPECT_THAT(error_of(with_polygon("{scale: 2}")), HasSubstr("neither points nor file given"));
  EXPECT_THAT(error_of(with_polygon("{file: missing.txt}")), HasSubstr("missing.txt': no such file"));
  write_file("bad.txt", "0 0\n1 x\n");
  EXPECT_THAT(error_of(with_polygon("{file: bad.txt}")), HasSubstr("bad.txt:2: '1 x': expected two finite numbers x y per line"));
  EXPECT_THAT(error_of(with_polygon("{points: [[0.1, 0.1], [0.3, 0.1], [0.3, 0.3]], scale: -1}")),
              HasSubstr("scale = -1: expected a positive scale factor s or [x, y] of positive factors"));
  EXPECT_THAT(error_of(with_polygon("{points: [[2, 2], [3, 2], [3, 3]]}")), HasSubstr("lies outside the domain"));
  EXPECT_THAT(error_of(with_polygon("{points: [[0.1, 0.1], [0.3, 0.1], [0.3, 0.3]], normals: out}")),
              HasSubstr("unknown key 'normals'"));
  // A 3D surface in 2D: the body has none of the 2D shapes.
  EXPECT_THAT(error_of(replaced(tank_case, "rectangle: {min: [0, 0], max: [0.3, 0.4]}", "surface: {file: a.stl}")),
              HasSubstr("missing key 'rectangle' in bodies[0]"));
  EXPECT_THAT(error_of(replaced(tank_case, "type: box, rectangle: {min: [0, 0], max: [1, 0.8]}",
                                "type: polygon, polygon: {points: [[0, 0], [1, 0], [1, 1]]}, fluid: below")),
              HasSubstr("fluid = below"));
}

#else  // MPSFSI_DIM == 3

namespace {

using Triangle = std::array<Vec, 3>;

/// The triangles of a convex solid turned so that their normals point away from `centre` (outward).
std::vector<Triangle> outward(std::vector<Triangle> triangles, const Vec& centre) {
  for (auto& t : triangles) {
    const Vec n = (t[1] - t[0]).cross(t[2] - t[0]);
    if (n.dot((t[0] + t[1] + t[2]) / 3 - centre) < 0) std::swap(t[1], t[2]);
  }
  return triangles;
}

/// The 12 triangles of the box [lo, hi], outward.
std::vector<Triangle> box_triangles(const Vec& lo, const Vec& hi) {
  const auto corner = [&](const int k) { return Vec(k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]); };
  // Each face: its four corners around it.
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  std::vector<Triangle> t;
  for (const auto& f : faces) {
    t.push_back({corner(f[0]), corner(f[1]), corner(f[2])});
    t.push_back({corner(f[0]), corner(f[2]), corner(f[3])});
  }
  return outward(t, (lo + hi) / 2);
}

/// A cylinder of n segments about the z axis through (cx, cy), from z0 to z1, its vertices on the circle of radius r.
std::vector<Triangle> cylinder_triangles(const Real cx, const Real cy, const Real r, const Real z0, const Real z1, const int n) {
  std::vector<Triangle> t;
  const auto at = [&](const int k, const Real z) {
    const Real a = 2 * pi * k / n;
    return Vec(cx + r * std::cos(a), cy + r * std::sin(a), z);
  };
  for (int k = 0; k < n; ++k) {
    t.push_back({at(k, z0), at(k + 1, z0), at(k + 1, z1)});
    t.push_back({at(k, z0), at(k + 1, z1), at(k, z1)});
    t.push_back({Vec(cx, cy, z0), at(k, z0), at(k + 1, z0)});
    t.push_back({Vec(cx, cy, z1), at(k, z1), at(k + 1, z1)});
  }
  return outward(t, Vec(cx, cy, (z0 + z1) / 2));
}

std::string stl_text(const std::vector<Triangle>& triangles) {
  std::string s = "solid test\n";
  char line[256];
  for (const auto& t : triangles) {
    s += " facet normal 0 0 0\n  outer loop\n";
    for (const Vec& v : t) {
      std::snprintf(line, sizeof line, "   vertex %.17g %.17g %.17g\n", v[0], v[1], v[2]);
      s += line;
    }
    s += "  endloop\n endfacet\n";
  }
  return s + "endsolid test\n";
}

std::string obj_text(const std::vector<Triangle>& triangles) {
  std::string s;
  char line[256];
  for (const auto& t : triangles)
    for (const Vec& v : t) {
      std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", v[0], v[1], v[2]);
      s += line;
    }
  for (std::size_t k = 0; k < triangles.size(); ++k) {
    std::snprintf(line, sizeof line, "f %zu %zu %zu\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
    s += line;
  }
  return s;
}

/// A 3D water column in an open box tank on the lattice of dp 0.01.
const char* const tank_case = R"(name: surfaces
description: a water column in a tank
source: tests
dimension: 3
dp: 0.01
domain: {min: [-0.1, -0.1, -0.1], max: [0.6, 0.3, 0.6]}
time: {end: 0.5, dt: 1.0e-4}
gravity: [0, 0, -9.81]
materials:
  water: {type: fluid, rho: 1000, nu: 1.0e-6}
bodies:
  - {name: column, kind: fluid, material: water, rectangle: {min: [0, 0, 0], max: [0.1, 0.2, 0.3]}}
walls:
  - {name: tank, type: box, rectangle: {min: [0, 0, 0], max: [0.5, 0.2, 0.4]}}
)";

}  // namespace

// A box given as an STL or OBJ surface is the rectangle (a body), the box tank (fluid inside, open top) and the block
// (fluid outside), point for point, with the wall offsets; scale, rotation and translation place a unit cube there.
TEST(Surface, StlAndObjBoxesAreTheBuiltInBoxes) {
  write_file("column.stl", stl_text(box_triangles(Vec(0, 0, 0), Vec(0.1, 0.2, 0.3))));
  write_file("tank.stl", stl_text(box_triangles(Vec(0, 0, 0), Vec(0.5, 0.2, 0.4))));
  write_file("cube.obj", obj_text(box_triangles(Vec(0, 0, 0), Vec(1, 1, 1))));
  const Scene reference = build_scene(parse_case(tank_case, "cases/x.yaml"));
  const std::string text =
      replaced(replaced(tank_case, "rectangle: {min: [0, 0, 0], max: [0.1, 0.2, 0.3]}", "surface: {file: column.stl}"),
               "type: box, rectangle: {min: [0, 0, 0], max: [0.5, 0.2, 0.4]}",
               "type: surface, surface: {file: tank.stl}, fluid: inside, open_top: true");
  const CaseSpec spec = parse_case(text, "cases/x.yaml", {}, work_dir().string());
  ASSERT_TRUE(spec.bodies[0].surface);
  EXPECT_NEAR(spec.bodies[0].surface->volume(), 0.006, 1e-15);
  EXPECT_EQ(spec.bodies[0].surface->n_facets(), 12u);
  const Scene scene = build_scene(spec);
  expect_same_particles(scene, reference, 0);
  expect_counts_of(spec, scene);
  // The column as a unit cube in OBJ: scaled to 0.2 x 0.1 x 0.3, turned by 90 degrees about z, moved into place.
  const std::string obj = replaced(text, "surface: {file: column.stl}",
                                   "surface: {file: cube.obj, scale: [0.2, 0.1, 0.3], rotate: [0, 0, 90], translate: [0.1, 0, 0]}");
  const Scene turned = build_scene(parse_case(obj, "cases/x.yaml", {}, work_dir().string()));
  expect_same_particles(turned, reference, 1e-12);
  // The block: a box obstacle given as a surface with the fluid outside.
  const std::string blocks = std::string(tank_case) +
                             "  - {name: step, type: block, rectangle: {min: [0.3, 0, 0], max: [0.4, 0.2, 0.05]}}\n";
  write_file("step.stl", stl_text(box_triangles(Vec(0.3, 0, 0), Vec(0.4, 0.2, 0.05))));
  const Scene block = build_scene(parse_case(blocks, "cases/x.yaml"));
  const Scene step = build_scene(parse_case(
      replaced(blocks, "type: block, rectangle: {min: [0.3, 0, 0], max: [0.4, 0.2, 0.05]}", "type: surface, surface: {file: step.stl}"),
      "cases/x.yaml", {}, work_dir().string()));
  ASSERT_EQ(step.particles.size(), block.particles.size());
  for (std::size_t i = 0; i < block.particles.size(); ++i) {
    ASSERT_EQ(step.particles.position[i], block.particles.position[i]);
    ASSERT_EQ(step.particles.kind[i], block.particles.kind[i]);
  }
}

// A cylinder of 256 triangles' segments fills the built-in cylinder's lattice points (none lies within the facets'
// 4e-6 m of the true surface here); as an obstacle, every point less than dp below its surface is a wall point.
TEST(Surface, StlCylinderIsTheBuiltInCylinder) {
  const Real r = 0.05, dp = 0.01;
  write_file("pile.stl", stl_text(cylinder_triangles(0.25, 0.1, r, 0, 0.2, 256)));
  const auto pile = ClosedSurface::from_file((work_dir() / "pile.stl").string(), {});
  const Real prism = 0.5 * 256 * r * r * std::sin(2 * pi / 256) * 0.2;  // the 256-gon's area times the height
  EXPECT_NEAR(pile->volume(), prism, 1e-6 * prism);  // the file's coordinates are floats
  const Rect& b = pile->bounds();
  const auto filled = fill_region(b.lo, b.hi, dp, ClosedSurface::distance_function(pile));
  const auto built = fill_cylinder(Vec(0.25, 0.1, 0), Vec(0, 0, 0.2), r, dp);
  ASSERT_EQ(filled.size(), built.size());
  for (std::size_t k = 0; k < built.size(); ++k) EXPECT_LT((filled[k] - built[k]).norm(), 1e-12);
  const auto walls = region_walls(b.lo, b.hi, dp, ClosedSurface::distance_function(pile), false, false);
  for (const Vec& x : built) {
    const Real depth = std::min({r - std::hypot(x[0] - 0.25, x[1] - 0.1), x[2], 0.2 - x[2]});
    if (depth >= dp) continue;
    const bool is_wall = std::any_of(walls.begin(), walls.end(),
                                     [&](const WallPoint& p) { return (p.x - x).norm() < 1e-12 && p.is_wall; });
    EXPECT_TRUE(is_wall) << x.transpose();
  }
}

// Water around a cylinder given as a surface: the body lists the pile in `subtract`; it leaves no empty points
// between the water and the pile.
TEST(Surface, SubtractCutsAnStlObstacleOutOfABody) {
  write_file("pile.stl", stl_text(cylinder_triangles(0.25, 0.1, 0.05, 0, 0.2, 64)));
  const std::string text = replaced(tank_case, "rectangle: {min: [0, 0, 0], max: [0.1, 0.2, 0.3]}",
                                    "rectangle: {min: [0, 0, 0], max: [0.5, 0.2, 0.1]}, subtract: [pile]") +
                           "  - {name: pile, type: surface, surface: {file: pile.stl}}\n";
  const CaseSpec spec = parse_case(text, "cases/x.yaml", {}, work_dir().string());
  const Scene scene = build_scene(spec);
  expect_counts_of(spec, scene);
  Vec nearest;
  for (std::size_t i = 0; i < scene.particles.size(); ++i) {
    if (scene.particles.kind[i] == ParticleKind::fluid) {
      EXPECT_GE(spec.walls[1].surface->signed_distance(scene.particles.position[i], nearest), 0.0);
    }
  }
  EXPECT_LT(scene.particles.n_of_kind(ParticleKind::fluid), 50u * 20u * 10u);
  // Every lattice point along the pile's curved surface is the water's or the pile's.
  expect_no_gap_at(scene, Rect{Vec(0, 0, 0), Vec(0.5, 0.2, 0.1)}, spec.dp,
                   ClosedSurface::distance_function(spec.walls[1].surface), false);
}

// Bad surfaces: not closed, inside out, inconsistently oriented, empty, unreadable, missing, of another format, far
// outside the domain. Each message names the key and says what is wrong.
TEST(SurfaceErrors, StlSurfaces) {
  auto open = box_triangles(Vec(0.1, 0.05, 0.1), Vec(0.2, 0.15, 0.2));
  open.pop_back();
  write_file("open.stl", stl_text(open));
  auto inverted = box_triangles(Vec(0.1, 0.05, 0.1), Vec(0.2, 0.15, 0.2));
  for (auto& t : inverted) std::swap(t[1], t[2]);
  write_file("inverted.stl", stl_text(inverted));
  auto mixed = box_triangles(Vec(0.1, 0.05, 0.1), Vec(0.2, 0.15, 0.2));
  std::swap(mixed[0][1], mixed[0][2]);
  write_file("mixed.stl", stl_text(mixed));
  write_file("empty.stl", "");
  write_file("far.stl", stl_text(box_triangles(Vec(5, 5, 5), Vec(6, 6, 6))));
  write_file("box.ply", "ply\n");
  const auto with_surface = [](const std::string& surface) {
    return replaced(tank_case, "rectangle: {min: [0, 0, 0], max: [0.1, 0.2, 0.3]}", "surface: " + surface);
  };
  EXPECT_THAT(error_of(with_surface("{file: open.stl}")),
              HasSubstr("bodies[0].surface: the surface in '" + (work_dir() / "open.stl").string() + "' is not closed"));
  EXPECT_THAT(error_of(with_surface("{file: inverted.stl}")), HasSubstr("its normals point inward; expected outward normals"));
  EXPECT_THAT(error_of(with_surface("{file: mixed.stl}")), HasSubstr("is not consistently oriented"));
  EXPECT_THAT(error_of(with_surface("{file: empty.stl}")), HasSubstr("bodies[0].surface: "));
  EXPECT_THAT(error_of(with_surface("{file: missing.stl}")), HasSubstr("missing.stl': no such file"));
  EXPECT_THAT(error_of(with_surface("{file: box.ply}")), HasSubstr("is not an .stl or .obj file"));
  EXPECT_THAT(error_of(with_surface("{file: far.stl}")), HasSubstr("lies outside the domain"));
  EXPECT_THAT(error_of(with_surface("{file: far.stl, scale: 0}")), HasSubstr("scale = 0: expected a positive scale factor"));
  EXPECT_THAT(error_of(with_surface("{points: [[0, 0], [1, 0], [1, 1]]}")), HasSubstr("unknown key 'points'"));
  EXPECT_THAT(error_of(with_surface("{}")), HasSubstr("no file given"));
  // A 2D polygon in 3D: the body has none of the 3D shapes.
  EXPECT_THAT(error_of(replaced(tank_case, "rectangle: {min: [0, 0, 0], max: [0.1, 0.2, 0.3]}", "polygon: {file: a.txt}")),
              HasSubstr("missing key 'rectangle' in bodies[0]"));
}

#endif
