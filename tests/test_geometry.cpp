// Unit tests of the lattice geometry: filled rectangles (boxes in 3D), box walls, wall blocks; the 2D
// tests count rows and columns, the 3D ones faces, edges and corners.
#include "core/geometry.hpp"
#include "core/neighbours.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace mpsfsi;

namespace {
/// Smallest distance between any two points (via the neighbour search).
Real min_spacing(const std::vector<Vec>& x, const Real probe) {
  NeighbourList nl;
  build_neighbour_list(x, probe, nl);
  Real d = probe;
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t k = nl.begin(i); k < nl.end(i); ++k) d = std::min(d, (x[nl.index[k]] - x[i]).norm());
  return d;
}
}  // namespace

#if MPSFSI_DIM == 2
TEST(Geometry, FillRectangleExactLattice) {
  const Real dp = 0.002;
  const auto x = fill_rectangle(Vec(0.1, 0.0), Vec(0.146, 0.292), dp);
  EXPECT_EQ(x.size(), 23u * 146u);
  EXPECT_DOUBLE_EQ(x.front()[0], 0.1 + 0.5 * dp);
  EXPECT_DOUBLE_EQ(x.front()[1], 0.5 * dp);
  EXPECT_DOUBLE_EQ(x.back()[0], 0.1 + 22.5 * dp);
  EXPECT_DOUBLE_EQ(x.back()[1], 145.5 * dp);
  EXPECT_NEAR(min_spacing(x, 2 * dp), dp, 1e-15);
}

#else
TEST(Geometry, FillBoxExactLattice) {
  const Real dp = 0.002;
  const auto x = fill_rectangle(Vec(0.1, 0.0, -0.01), Vec(0.146, 0.03, 0.0), dp);  // 23 x 15 x 5
  EXPECT_EQ(x.size(), 23u * 15u * 5u);
  EXPECT_DOUBLE_EQ(x.front()[0], 0.1 + 0.5 * dp);
  EXPECT_DOUBLE_EQ(x.front()[2], -0.01 + 0.5 * dp);
  EXPECT_DOUBLE_EQ(x[1][0], 0.1 + 1.5 * dp);  // x fastest
  EXPECT_DOUBLE_EQ(x[23][1], 1.5 * dp);       // then y
  EXPECT_DOUBLE_EQ(x[23 * 15][2], -0.01 + 1.5 * dp);
  EXPECT_DOUBLE_EQ(x.back()[0], 0.1 + 22.5 * dp);
  EXPECT_DOUBLE_EQ(x.back()[1], 14.5 * dp);
  EXPECT_NEAR(x.back()[2], -0.01 + 4.5 * dp, 1e-17);
  EXPECT_NEAR(min_spacing(x, 2 * dp), dp, 1e-15);
}
#endif

TEST(Geometry, LatticeCellsRoundsAndRejectsBadInput) {
  EXPECT_EQ(lattice_cells(0.146, 0.0016), 91);  // 91.25 -> 91
  EXPECT_EQ(lattice_cells(1e-9, 1.0), 1);
  EXPECT_THROW(lattice_cells(1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(lattice_cells(-1.0, 0.1), std::invalid_argument);
}

#if MPSFSI_DIM == 2
// Rectangles on one lattice: touching rectangles whose shared face is not on the lattice (0.302 = 75.5 dp at
// dp 4 mm, the sloshing cases' oil | plate | oil) get neighbouring cells, dp apart, none shared and none left out;
// a rectangle on the lattice keeps its corner bit for bit; a side shorter than dp keeps one cell from lo.
TEST(Geometry, LatticeRectPutsTouchingRectanglesOnOneLattice) {
  const Real dp = 0.004;
  const Vec origin = Vec::Zero();
  Vec lo = Vec::Zero(), hi = Vec::Constant(0.1148);
  hi[0] = 0.302;
  const Rect left = lattice_rect(lo, hi, origin, dp);
  lo[0] = 0.302, hi[0] = 0.306;
  const Rect plate = lattice_rect(lo, hi, origin, dp);
  lo[0] = 0.306, hi[0] = 0.609;
  const Rect right = lattice_rect(lo, hi, origin, dp);
  EXPECT_EQ(left.lo[0], 0.0);
  EXPECT_NEAR(left.hi[0], 0.304, 1e-12);  // centres up to 0.302, the one on the face
  EXPECT_NEAR(plate.lo[0], 0.304, 1e-12);
  EXPECT_NEAR(plate.hi[0], 0.308, 1e-12);  // one cell, centre 0.306
  EXPECT_NEAR(right.lo[0], 0.308, 1e-12);
  EXPECT_NEAR(right.hi[0], 0.608, 1e-12);  // centres up to 0.606 <= 0.609 < 0.610
  EXPECT_EQ(left.lo[1], 0.0);
  EXPECT_NEAR(left.hi[1], 29 * dp, 1e-12);  // 0.1148 = 28.7 dp
  std::vector<Vec> x;
  for (const Rect& r : {left, plate, right})
    for (const Vec& p : fill_rectangle(r.lo, r.hi, dp)) x.push_back(p);
  EXPECT_EQ(x.size(), static_cast<std::size_t>((76 + 1 + 75) * 29 * (dim == 3 ? 29 : 1)));
  EXPECT_NEAR(min_spacing(x, 1.5 * dp), dp, 1e-12);

  // On the lattice: lo kept exactly (0.306 = 153 cells of 2 mm), the count as fill_rectangle's round(side / dp).
  const Rect aligned = lattice_rect(Vec::Constant(0.306), Vec::Constant(0.609), origin, 0.002);
  EXPECT_EQ(aligned.lo[0], 0.306);
  EXPECT_NEAR(aligned.hi[0], 0.306 + lattice_cells(0.303, 0.002) * 0.002, 1e-12);
  // A side shorter than dp with no centre in it: one cell from lo.
  const Rect thin = lattice_rect(Vec::Constant(0.3005), Vec::Constant(0.3015), origin, dp);
  EXPECT_EQ(thin.lo[0], 0.3005);
  EXPECT_NEAR(thin.hi[0], 0.3045, 1e-12);
  EXPECT_THROW(lattice_rect(Vec::Zero(), Vec::Zero(), origin, dp), std::invalid_argument);
  EXPECT_THROW(lattice_rect(Vec::Zero(), Vec::Ones(), origin, 0.0), std::invalid_argument);
}

// The lattice corner below a point: the face at or below it on every axis, the point itself on a face (to round-off);
// a sphere and a cylinder given the origin are filled on that lattice, their own corner's when they are not.
TEST(Geometry, LatticeCornerPutsRoundShapesOnTheCaseLattice) {
  const Real dp = 0.004;
  const Vec origin(-0.01, 0.002);
  const Vec corner = lattice_corner(Vec(0.3137, 0.0211), origin, dp);
  EXPECT_NEAR(corner[0], -0.01 + 80 * dp, 1e-12);  // 0.3137 = origin + 80.925 dp
  EXPECT_NEAR(corner[1], 0.002 + 4 * dp, 1e-12);   // 0.0211 = origin + 4.775 dp
  const Vec on(-0.01 + 75 * dp, 0.002 - 3 * dp);
  EXPECT_EQ(lattice_corner(on, origin, dp), on);
  EXPECT_THROW(lattice_corner(on, origin, 0.0), std::invalid_argument);
  const auto on_lattice = [&](const std::vector<Vec>& points) {
    Real off = 0;
    for (const Vec& x : points)
      for (int a = 0; a < dim; ++a) {
        const Real f = (x[a] - origin[a]) / dp - 0.5;
        off = std::max(off, std::abs(f - std::round(f)));
      }
    return off;
  };
  const auto sphere = fill_sphere(Vec(0.3137, 0.0211), 0.0307, dp, origin);
  const auto cylinder = fill_cylinder(Vec(0.2013, 0.1007), Vec(0.05, 0.1), 0.0133, dp, origin);
  ASSERT_GT(sphere.size(), 150u);
  ASSERT_GT(cylinder.size(), 150u);
  EXPECT_LT(on_lattice(sphere), 1e-9);
  EXPECT_LT(on_lattice(cylinder), 1e-9);
  EXPECT_GT(on_lattice(fill_sphere(Vec(0.3137, 0.0211), 0.0307, dp)), 0.1);  // its own corner's lattice
  std::vector<Vec> walls;
  for (const WallPoint& w : cylinder_walls(Vec(0.2013, 0.1007), Vec(0.05, 0.1), 0.0133, dp, 2, origin)) walls.push_back(w.x);
  ASSERT_FALSE(walls.empty());
  EXPECT_LT(on_lattice(walls), 1e-9);
  // The same shape on either lattice: counts within the lattice's rounding, every point inside.
  for (const Vec& x : sphere) EXPECT_LE((x - Vec(0.3137, 0.0211)).norm(), 0.0307 + 1e-12);
  const RoundCount c = count_sphere(Vec(0.3137, 0.0211), 0.0307, dp, 2, origin);
  EXPECT_EQ(c.filled, sphere.size());
  EXPECT_EQ(c.layers, sphere_walls(Vec(0.3137, 0.0211), 0.0307, dp, 2, origin).size());
}

TEST(Geometry, OpenBoxWallsHaveOneWallAndTwoDummyLayers) {
  const Real dp = 0.01;
  const int nx = 20, ny = 10;
  const auto w = box_walls(Vec(0, 0), Vec(nx * dp, ny * dp), dp, true);
  std::size_t n_wall = 0, n_dummy = 0;
  for (const auto& p : w) {
    (p.is_wall ? n_wall : n_dummy) += 1;
    // Nothing inside the box.
    EXPECT_FALSE(p.x[0] > 0 && p.x[0] < nx * dp && p.x[1] > 0) << p.x.transpose();
  }
  // Wall layer: floor (nx + 2 corners) + two sides of height ny.
  EXPECT_EQ(n_wall, static_cast<std::size_t>(nx + 2 + 2 * ny));
  // Dummy layers 2 and 3: floor rows (nx + 4) + (nx + 6), side columns 2 * 2 * (ny + 1) + 2 * 2 * (ny + 2) ... counted directly:
  EXPECT_EQ(n_dummy, static_cast<std::size_t>((nx + 4) + (nx + 6) + 2 * (ny + 1) + 2 * (ny + 2)));
  // The fluid that fills the box sits exactly dp from the wall layer, never closer.
  auto all = fill_rectangle(Vec(0, 0), Vec(nx * dp, ny * dp), dp);
  for (const auto& p : w) all.push_back(p.x);
  EXPECT_NEAR(min_spacing(all, 2 * dp), dp, 1e-15);
}

TEST(Geometry, ClosedBoxHasALid) {
  const Real dp = 0.01;
  const auto open = box_walls(Vec(0, 0), Vec(0.1, 0.1), dp, true);
  const auto closed = box_walls(Vec(0, 0), Vec(0.1, 0.1), dp, false);
  // The lid adds 3 full rows of the widened box (16 particles each) minus the side columns already there.
  EXPECT_EQ(closed.size() - open.size(), 3u * 16u);
}

TEST(Geometry, BlockKeepsOuterWallAndTwoDummyLayers) {
  const Real dp = 0.001;
  const auto b = block_walls(Vec(0, 0), Vec(0.024, 0.048), dp);  // 24 x 48 cells
  std::size_t n_wall = 0;
  for (const auto& p : b) n_wall += p.is_wall;
  EXPECT_EQ(n_wall, static_cast<std::size_t>(2 * 24 + 2 * 48 - 4));
  EXPECT_EQ(b.size(), static_cast<std::size_t>(24 * 48 - 18 * 42));  // the core deeper than 3 layers is left out
}
#else
namespace {
/// Lattice points of the open (closed) box grown by L layers: (nx + 2L)(ny + 2L)(nz + L (2L)).
std::size_t grown(const int nx, const int ny, const int nz, const int layers, const bool open_top) {
  return static_cast<std::size_t>((nx + 2 * layers) * (ny + 2 * layers) * (nz + (open_top ? 1 : 2) * layers));
}
}  // namespace

TEST(Geometry, OpenBoxWallsHaveOneWallAndTwoDummyLayers) {
  const Real dp = 0.01;
  const int nx = 8, ny = 6, nz = 5;
  const auto w = box_walls(Vec::Zero(), Vec(nx * dp, ny * dp, nz * dp), dp, true);
  std::size_t n_wall = 0, n_dummy = 0;
  for (const auto& p : w) {
    (p.is_wall ? n_wall : n_dummy) += 1;
    // Nothing inside the box.
    EXPECT_FALSE(p.x[0] > 0 && p.x[0] < nx * dp && p.x[1] > 0 && p.x[1] < ny * dp && p.x[2] > 0) << p.x.transpose();
    EXPECT_LT(p.x[2], nz * dp);  // open top: nothing above the box
  }
  // Floor, four sides, their edges and corners: the shells between the grown boxes.
  EXPECT_EQ(n_wall, grown(nx, ny, nz, 1, true) - grown(nx, ny, nz, 0, true));
  EXPECT_EQ(n_dummy, grown(nx, ny, nz, 3, true) - grown(nx, ny, nz, 1, true));
  // The fluid that fills the box sits exactly dp from the wall layer, never closer.
  auto all = fill_rectangle(Vec::Zero(), Vec(nx * dp, ny * dp, nz * dp), dp);
  for (const auto& p : w) all.push_back(p.x);
  EXPECT_NEAR(min_spacing(all, 2 * dp), dp, 1e-15);
}

TEST(Geometry, ClosedBoxHasALid) {
  const Real dp = 0.01;
  const int n = 10;
  const auto open = box_walls(Vec::Zero(), Vec::Constant(n * dp), dp, true);
  const auto closed = box_walls(Vec::Zero(), Vec::Constant(n * dp), dp, false);
  EXPECT_EQ(closed.size(), grown(n, n, n, 3, false) - grown(n, n, n, 0, false));
  // The lid adds 3 full layers of the widened box (16 x 16 particles each).
  EXPECT_EQ(closed.size() - open.size(), 3u * 16u * 16u);
}

TEST(Geometry, BlockKeepsOuterWallAndTwoDummyLayers) {
  const Real dp = 0.001;
  const auto b = block_walls(Vec::Zero(), Vec(0.012, 0.010, 0.008), dp);  // 12 x 10 x 8 cells
  std::size_t n_wall = 0;
  for (const auto& p : b) n_wall += p.is_wall;
  EXPECT_EQ(n_wall, static_cast<std::size_t>(12 * 10 * 8 - 10 * 8 * 6));
  EXPECT_EQ(b.size(), static_cast<std::size_t>(12 * 10 * 8 - 6 * 4 * 2));  // the core deeper than 3 layers is left out
}
#endif

#if MPSFSI_DIM == 3
// A cylinder along z, radius 6 dp, length 10 dp: 10 layers of the same disc, spaced dp, every point within the
// radius; the disc's area is within 3 % of pi r^2. An oblique cylinder has the volume pi r^2 L within 3 %.
TEST(Geometry, CylinderAlongZAndOblique) {
  const Real dp = 0.01, r = 0.06;
  const std::vector<Vec> c = fill_cylinder(Vec(0.1, 0.2, 0.0), Vec(0, 0, 0.1), r, dp);
  ASSERT_FALSE(c.empty());
  EXPECT_EQ(c.size() % 10, 0u);
  const std::size_t per_layer = c.size() / 10;
  EXPECT_NEAR(static_cast<Real>(per_layer) * dp * dp, pi * r * r, 0.03 * pi * r * r);
  for (const Vec& x : c) {
    EXPECT_LE(std::hypot(x[0] - 0.1, x[1] - 0.2), r + 1e-12);
    EXPECT_GE(x[2], 0.0);
    EXPECT_LE(x[2], 0.1);
  }
  EXPECT_NEAR(min_spacing(c, 2 * dp), dp, 1e-12);
  const Vec axis = 0.2 * Vec(1, 2, 2).normalized();
  const std::vector<Vec> o = fill_cylinder(Vec::Zero(), axis, r, dp);
  EXPECT_NEAR(static_cast<Real>(o.size()) * dp * dp * dp, pi * r * r * 0.2, 0.03 * pi * r * r * 0.2);
  EXPECT_NEAR(min_spacing(o, 2 * dp), dp, 1e-12);
  EXPECT_THROW(fill_cylinder(Vec::Zero(), Vec::Zero(), r, dp), std::invalid_argument);
  EXPECT_THROW(fill_cylinder(Vec::Zero(), axis, 0, dp), std::invalid_argument);
}
#endif

namespace {
/// The wall point at x (within 1e-9 dp); fails the test when there is none.
WallPoint point_at(const std::vector<WallPoint>& points, const Vec& x, const Real dp) {
  for (const auto& p : points)
    if ((p.x - x).norm() < 1e-9 * dp) return p;
  ADD_FAILURE() << "no wall point at " << x.transpose();
  return {x, false, Vec::Zero()};
}
}  // namespace

// Every wall point knows the way to the wetted surface: the offset ends on the box's inner faces (the lattice's:
// a side that is not a whole number of dp is rounded), across a face along its normal, at an edge or a corner
// on the edge or corner point.
TEST(Geometry, BoxWallPointsPointToTheInnerFaces) {
  const Real dp = 0.01;
  const Vec lo = Vec::Zero(), hi = Vec::Constant(10.4 * dp);  // 10 cells per side: the faces at 0 and 10 dp
  const auto w = box_walls(lo, hi, dp, false);
  const Vec face_hi = Vec::Constant(10 * dp);
  for (const auto& p : w) {
    const Vec q = p.x + p.to_surface;
    EXPECT_TRUE((q.array() >= -1e-12).all() && (q.array() <= face_hi.array() + 1e-12).all()) << p.x.transpose();
    const Real to_face = std::min(q.minCoeff(), (face_hi - q).minCoeff());
    EXPECT_NEAR(to_face, 0.0, 1e-12) << p.x.transpose();
    EXPECT_GE(p.to_surface.norm(), 0.5 * dp - 1e-12);
    EXPECT_EQ(p.is_wall, p.to_surface.cwiseAbs().maxCoeff() < dp) << p.x.transpose();
  }
  const Vec middle = Vec::Constant(5.5 * dp);
  Vec left = middle, floor3 = middle, corner = Vec::Constant(-0.5 * dp), right = middle;
  left[0] = -0.5 * dp;
  right[0] = 10.5 * dp;
  floor3[dim - 1] = -2.5 * dp;
  Vec expected = Vec::Zero();
  expected[0] = 0.5 * dp;
  EXPECT_LT((point_at(w, left, dp).to_surface - expected).norm(), 1e-12);
  EXPECT_LT((point_at(w, right, dp).to_surface + expected).norm(), 1e-12);
  expected = Vec::Zero();
  expected[dim - 1] = 2.5 * dp;
  EXPECT_LT((point_at(w, floor3, dp).to_surface - expected).norm(), 1e-12);
  EXPECT_LT((point_at(w, corner, dp).to_surface - Vec::Constant(0.5 * dp)).norm(), 1e-12);
}

// A block's points point out of it: to the nearest face, and where faces are equally near (the block's edges and
// corners, and the diagonals of the deeper layers) to the edge or corner point.
TEST(Geometry, BlockWallPointsPointOutOfTheBlock) {
  const Real dp = 0.01;
  const auto b = block_walls(Vec::Zero(), Vec::Constant(10 * dp), dp);
  for (const auto& p : b) {
    const Vec q = p.x + p.to_surface;
    const Real to_face = std::min(q.minCoeff(), (Vec::Constant(10 * dp) - q).minCoeff());
    EXPECT_NEAR(to_face, 0.0, 1e-12) << p.x.transpose();
  }
  Vec top = Vec::Constant(4.5 * dp), below_top = top;
  top[dim - 1] = 9.5 * dp;
  below_top[dim - 1] = 8.5 * dp;
  Vec expected = Vec::Zero();
  expected[dim - 1] = 0.5 * dp;
  EXPECT_LT((point_at(b, top, dp).to_surface - expected).norm(), 1e-12);
  expected[dim - 1] = 1.5 * dp;
  EXPECT_LT((point_at(b, below_top, dp).to_surface - expected).norm(), 1e-12);
  EXPECT_LT((point_at(b, Vec::Constant(0.5 * dp), dp).to_surface - Vec::Constant(-0.5 * dp)).norm(), 1e-12);
  EXPECT_LT((point_at(b, Vec::Constant(1.5 * dp), dp).to_surface - Vec::Constant(-1.5 * dp)).norm(), 1e-12);
}

// A ball (a disc in 2D) on its lattice: every point within the radius, the count near the volume (area), the
// lattice's spacing; its wall layers: depth below dp is wall, below 3 dp dummy, deeper points left out, and
// every offset ends on the sphere along the radius.
TEST(Geometry, SphereFillAndWalls) {
  const Real dp = 0.01, r = 0.1;
  const Vec c = Vec::Constant(0.3);
  const std::vector<Vec> s = fill_sphere(c, r, dp);
  const Real volume = dim == 2 ? pi * r * r : 4.0 / 3.0 * pi * r * r * r;
  EXPECT_NEAR(static_cast<Real>(s.size()) * std::pow(dp, dim), volume, 0.02 * volume);
  for (const Vec& x : s) EXPECT_LE((x - c).norm(), r + 1e-12);
  EXPECT_NEAR(min_spacing(s, 2 * dp), dp, 1e-12);
  const auto w = sphere_walls(c, r, dp);
  std::size_t n_wall = 0, n_dummy = 0;
  for (const auto& p : w) {
    const Real depth = r - (p.x - c).norm();
    EXPECT_GE(depth, -1e-12);
    EXPECT_LT(depth, 3 * dp);
    EXPECT_EQ(p.is_wall, depth < dp) << p.x.transpose();
    EXPECT_NEAR((p.x + p.to_surface - c).norm(), r, 1e-12);
    EXPECT_NEAR(p.to_surface.norm(), depth, 1e-12);
    (p.is_wall ? n_wall : n_dummy) += 1;
  }
  // The wall layer is the shell of depth dp: its particles fill the shell's volume (area).
  const Real shell = dim == 2 ? pi * (r * r - (r - dp) * (r - dp))
                              : 4.0 / 3.0 * pi * (std::pow(r, 3) - std::pow(r - dp, 3));
  EXPECT_NEAR(static_cast<Real>(n_wall) * std::pow(dp, dim), shell, 0.1 * shell);
  EXPECT_GT(n_dummy, n_wall);
  EXPECT_LT(w.size(), s.size());
  EXPECT_THROW(fill_sphere(c, 0, dp), std::invalid_argument);
  EXPECT_THROW(sphere_walls(c, r, -dp), std::invalid_argument);
}

// A cylinder of wall particles: the depth of a point is its distance to the nearest of the lateral surface and
// the end faces, and its offset ends on that surface: on the mantle along the radius, on an end face along the
// axis.
TEST(Geometry, CylinderWallsFollowTheSurface) {
  const Real dp = 0.01, r = 0.05, length = 0.2;
  Vec base = Vec::Constant(0.1), axis = Vec::Zero();
  axis[dim - 1] = length;
  const auto w = cylinder_walls(base, axis, r, dp);
  ASSERT_FALSE(w.empty());
  const Vec e = axis / length;
  for (const auto& p : w) {
    const Real s = (p.x - base).dot(e);
    const Real rho = (p.x - base - s * e).norm();
    const Real depth = std::min({r - rho, s, length - s});
    EXPECT_GE(depth, -1e-12);
    EXPECT_LT(depth, 3 * dp);
    EXPECT_EQ(p.is_wall, depth < dp) << p.x.transpose();
    EXPECT_NEAR(p.to_surface.norm(), depth, 1e-12) << p.x.transpose();
    const Vec q = p.x + p.to_surface;
    const Real sq = (q - base).dot(e);
    const Real rq = (q - base - sq * e).norm();
    const bool on_surface = std::abs(rq - r) < 1e-12 || std::abs(sq) < 1e-12 || std::abs(sq - length) < 1e-12;
    EXPECT_TRUE(on_surface) << p.x.transpose();
  }
  // The points of a layer in the middle, away from the ends, are those of a ring (in 2D two strips) 3 dp deep.
  const auto in_middle = [&](const Vec& x) {
    const Real s = (x - base).dot(e);
    return s >= 0.5 * length && s < 0.5 * length + dp;
  };
  std::size_t n_ring = 0, n_fill = 0;
  for (const auto& p : w)
    if (in_middle(p.x)) ++n_ring;
  for (const Vec& x : fill_cylinder(base, axis, r, dp))
    if (in_middle(x) && (x - base - (x - base).dot(e) * e).norm() > r - 3 * dp) ++n_fill;
  EXPECT_GT(n_ring, 0u);
  EXPECT_EQ(n_ring, n_fill);
  EXPECT_THROW(cylinder_walls(base, Vec::Zero(), r, dp), std::invalid_argument);
}

// The signed distances of the built-in shapes: negative inside, zero on the surface, and the nearest surface point.
TEST(Geometry, ShapeDistancesAndNearestPoints) {
  Vec nearest, x = Vec::Zero();
  const auto ball = sphere_distance(Vec::Zero(), 1.0);
  x[0] = 2;
  EXPECT_DOUBLE_EQ(ball(x, nearest), 1.0);
  EXPECT_DOUBLE_EQ(nearest[0], 1.0);
  x[0] = 0.25;
  EXPECT_DOUBLE_EQ(ball(x, nearest), -0.75);
  EXPECT_DOUBLE_EQ(nearest[0], 1.0);
  // A cylinder along the last axis from 0 to 2, radius 0.5: the mantle, an end face and an edge nearest.
  Vec axis = Vec::Zero();
  axis[dim - 1] = 2;
  const auto pile = cylinder_distance(Vec::Zero(), axis, 0.5);
  x = Vec::Zero();
  x[0] = 0.2, x[dim - 1] = 1.0;
  EXPECT_DOUBLE_EQ(pile(x, nearest), -0.3);
  EXPECT_DOUBLE_EQ(nearest[0], 0.5);
  EXPECT_DOUBLE_EQ(nearest[dim - 1], 1.0);
  x[0] = 0, x[dim - 1] = 1.9;
  EXPECT_NEAR(pile(x, nearest), -0.1, 1e-15);
  EXPECT_DOUBLE_EQ(nearest[dim - 1], 2.0);
  x[0] = 1.0, x[dim - 1] = 2.5;
  EXPECT_NEAR(pile(x, nearest), std::sqrt(0.5), 1e-15);
  EXPECT_DOUBLE_EQ(nearest[0], 0.5);
  EXPECT_DOUBLE_EQ(nearest[dim - 1], 2.0);
  // A box: inside, outside, and on a face (zero, which is not inside).
  const auto box = box_distance(Vec::Zero(), Vec::Ones());
  x = Vec::Constant(0.5);
  x[0] = 0.1;
  EXPECT_DOUBLE_EQ(box(x, nearest), -0.1);
  EXPECT_DOUBLE_EQ(nearest[0], 0.0);
  EXPECT_DOUBLE_EQ(nearest[1], 0.5);
  x[0] = 2;
  EXPECT_DOUBLE_EQ(box(x, nearest), 1.0);
  EXPECT_DOUBLE_EQ(nearest[0], 1.0);
  x[0] = 0;
  EXPECT_EQ(box(x, nearest), 0.0);
}

// A box given by its signed distance is filled and walled as the built-in rectangle, box tank and block, point for
// point and in their order: a region's lattice and layers are those of the boxes.
TEST(Geometry, RegionOfABoxIsTheRectangleBoxAndBlock) {
  const Real dp = 0.01;
  const Vec lo = Vec::Constant(0.1);
  Vec hi = Vec::Constant(0.16);
  hi[0] = 0.2;
  const auto box = box_distance(lo, hi);
  EXPECT_EQ(fill_region(lo, hi, dp, box), fill_rectangle(lo, hi, dp));
  for (const bool open_top : {true, false}) {
    const auto region = region_walls(lo, hi, dp, box, true, open_top);
    const auto built = box_walls(lo, hi, dp, open_top);
    ASSERT_EQ(region.size(), built.size()) << "open_top " << open_top;
    for (std::size_t k = 0; k < built.size(); ++k) {
      EXPECT_EQ(region[k].x, built[k].x);
      EXPECT_EQ(region[k].is_wall, built[k].is_wall) << built[k].x.transpose();
      EXPECT_LT((region[k].to_surface - built[k].to_surface).norm(), 1e-15) << built[k].x.transpose();
    }
  }
  // An obstacle: the block's points and layers; the offset ends on the nearest face.
  const auto region = region_walls(lo, hi, dp, box, false, false);
  const auto built = block_walls(lo, hi, dp);
  ASSERT_EQ(region.size(), built.size());
  for (std::size_t k = 0; k < built.size(); ++k) {
    EXPECT_EQ(region[k].x, built[k].x);
    EXPECT_EQ(region[k].is_wall, built[k].is_wall) << built[k].x.transpose();
    const Real depth = std::min((built[k].x - lo).minCoeff(), (hi - built[k].x).minCoeff());
    EXPECT_NEAR(region[k].to_surface.norm(), depth, 1e-15) << built[k].x.transpose();
  }
}

// A region that is not a box: a ball as an obstacle. Its points are the ball's lattice points within three layers of
// the outside (counted in cells, the largest over the axes); every point less than dp deep is a wall point, and a wall
// point is less than sqrt(dim) dp deep.
TEST(Geometry, RegionWallsOfABallKeepThreeLayers) {
  const Real dp = 0.01, r = 0.083;
  const Vec c = Vec::Constant(0.3);
  const auto ball = sphere_distance(c, r);
  const auto walls = region_walls(c - Vec::Constant(r), c + Vec::Constant(r), dp, ball, false, false);
  ASSERT_FALSE(walls.empty());
  std::size_t n_wall = 0;
  for (const auto& p : walls) {
    const Real depth = r - (p.x - c).norm();
    EXPECT_GT(depth, 0);
    EXPECT_LT(depth, 3 * std::sqrt(Real(dim)) * dp);
    EXPECT_NEAR(p.to_surface.norm(), depth, 1e-15);
    if (p.is_wall) {
      ++n_wall;
      EXPECT_LT(depth, std::sqrt(Real(dim)) * dp) << p.x.transpose();
    }
  }
  std::size_t n_shallow = 0;
  for (const Vec& x : fill_region(c - Vec::Constant(r), c + Vec::Constant(r), dp, ball)) {
    if (r - (x - c).norm() >= dp) continue;
    ++n_shallow;
    const bool is_wall = std::any_of(walls.begin(), walls.end(), [&](const WallPoint& p) { return p.x == x && p.is_wall; });
    EXPECT_TRUE(is_wall) << x.transpose();
  }
  EXPECT_GT(n_shallow, 0u);
  EXPECT_GE(n_wall, n_shallow);
}
