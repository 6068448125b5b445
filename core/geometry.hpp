// Particle geometry on a lattice of spacing dp (square in 2D, simple cubic in 3D): filled rectangles
// (boxes in 3D), spheres and cylinders; box walls, and blocks, spheres and cylinders made of one wall layer plus
// dummy layers (seed 004 §4.3), and any region given by its signed distance (a surface read from a file: io/surface.hpp)
// filled, or made into walls, on the same lattice. A rectangle of n x m (x l) cells of side dp gets one particle at the centre of
// each cell. The rectangles of a scene are first put on one lattice (lattice_rect), so bodies that touch along a face sit
// exactly dp apart at any dp and never overlap. "Rectangle" below means the axis-aligned box [lo, hi] in the build's dimension.
#pragma once

#include "core/types.hpp"

#include <functional>
#include <optional>
#include <vector>

namespace mpsfsi {

/// Axis-aligned rectangle [lo, hi] (a box in 3D): the regions of a case (domain, bodies, walls, loads).
struct Rect {
  Vec lo = Vec::Zero();
  Vec hi = Vec::Zero();
  Vec size() const { return hi - lo; }
  bool contains(const Vec& x) const { return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all(); }
};

/// True when the interiors of a and b intersect (touching edges do not overlap).
inline bool overlaps(const Rect& a, const Rect& b) {
  return (a.lo.array() < b.hi.array()).all() && (b.lo.array() < a.hi.array()).all();
}

/// Number of lattice cells that fit a length: round(length / dp), at least 1. Throws
/// std::invalid_argument when length or dp is not positive.
int lattice_cells(Real length, Real dp);

/// The rectangle of the cells of the lattice with faces at origin + k dp (k whole) whose centres c satisfy
/// lo < c <= hi on every axis: a centre on the face between two touching rectangles belongs to the lower one, so
/// touching rectangles share no cell and leave none out between them, whatever dp. Its lo is `lo` itself where `lo`
/// is on the lattice (to 1e-9 dp), and its sides are whole cells. An axis that holds no such centre (a side shorter
/// than dp) keeps one cell from lo, as fill_rectangle does. Throws as lattice_cells.
Rect lattice_rect(const Vec& lo, const Vec& hi, const Vec& origin, Real dp);

/// The corner of the lattice with faces at origin + k dp (k whole) at or below x on every axis: the face at x
/// itself where x is on the lattice (to 1e-9 dp). A region filled from this corner (fill_region, and the round
/// shapes given the origin) lies on the same lattice as the rectangles of lattice_rect. Throws
/// std::invalid_argument when dp is not positive or x is more than 1e8 cells from origin.
Vec lattice_corner(const Vec& x, const Vec& origin, Real dp);

/// Particle centres filling the rectangle [lo, hi]: lo + (i + 1/2, j + 1/2 [, k + 1/2]) dp for
/// i < lattice_cells(hi_x - lo_x), j < lattice_cells(hi_y - lo_y) [, k < ...], row by row (x fastest,
/// then y, then z).
std::vector<Vec> fill_rectangle(const Vec& lo, const Vec& hi, Real dp);

/// Particle centres filling the cylinder of radius `radius` around the segment from `base` to `base + axis`: the
/// points lo + (i + 1/2, j + 1/2 [, k + 1/2]) dp of the lattice anchored at the low corner lo of the cylinder's
/// bounding box (with `origin`: at lattice_corner of that corner, the lattice of the case's rectangles) whose
/// projection on the axis falls within the segment and whose distance from the axis is at most `radius` (in 2D
/// the cylinder's section through its axis: a strip of width 2 radius). Throws std::invalid_argument when dp or
/// radius is not positive or the axis is zero.
std::vector<Vec> fill_cylinder(const Vec& base, const Vec& axis, Real radius, Real dp,
                               const std::optional<Vec>& origin = std::nullopt);

/// Particle centres filling the ball of radius `radius` about `centre` (a disc in 2D): the points
/// lo + (i + 1/2 [, ...]) dp of the lattice anchored at the ball's low corner lo = centre - radius (with
/// `origin`: at lattice_corner of it) whose distance from the centre is at most `radius`. Throws
/// std::invalid_argument when dp or radius is not positive.
std::vector<Vec> fill_sphere(const Vec& centre, Real radius, Real dp, const std::optional<Vec>& origin = std::nullopt);

/// A lattice point of a wall, whether it belongs to the wall layer (true) or a dummy layer (false), and the
/// offset from it to the nearest point of the wetted surface (the face the fluid touches; at an edge or a corner
/// the edge or corner point). The wall particles keep the offset (particle field wall_surface_field) so that the
/// fluid can tell a particle that has crossed the surface (docs/architecture.md, "Walls hold water").
struct WallPoint {
  Vec x;
  bool is_wall;
  Vec to_surface = Vec::Zero();
};

/// The particle vector field that holds, for wall and dummy particles, WallPoint::to_surface in the tank's rest
/// frame (zero for other particles). Internal (not written to the output).
inline constexpr const char* wall_surface_field = "_wall_surface";

/// Walls of a box whose inner (wetted) rectangle is [lo, hi]: one wall layer and n_dummy dummy layers
/// outside it, edges and corners included; to_surface points to the nearest point of [lo, hi]. With open_top the top side (the last axis: y in 2D, z in 3D)
/// has no lid (side walls reach hi_y, resp. hi_z). Points come row by row like fill_rectangle.
std::vector<WallPoint> box_walls(const Vec& lo, const Vec& hi, Real dp, bool open_top, int n_dummy = 2);

/// A solid block [lo, hi] made of wall particles: the outer layer is wall, the next n_dummy layers are
/// dummy; deeper particles are not needed by the kernel and are left out. to_surface points to the nearest
/// face, or to the edge or corner where two or three faces are equally near.
std::vector<WallPoint> block_walls(const Vec& lo, const Vec& hi, Real dp, int n_dummy = 2);

/// A solid ball (a disc in 2D) made of wall particles, on the lattice of fill_sphere: the points less than dp
/// below the surface are wall, the next n_dummy layers (depth below (1 + n_dummy) dp) dummy; deeper points are
/// left out, as in block_walls. to_surface points radially out to the surface.
std::vector<WallPoint> sphere_walls(const Vec& centre, Real radius, Real dp, int n_dummy = 2,
                                    const std::optional<Vec>& origin = std::nullopt);

/// A solid cylinder made of wall particles, on the lattice of fill_cylinder: the depth of a point is its
/// distance to the nearest of the lateral surface and the two end faces; layers as in sphere_walls, and
/// to_surface points to the nearest point of that surface.
std::vector<WallPoint> cylinder_walls(const Vec& base, const Vec& axis, Real radius, Real dp, int n_dummy = 2,
                                      const std::optional<Vec>& origin = std::nullopt);

/// The points of a sphere's or cylinder's lattice, counted without making them: `filled` those of fill_sphere
/// (fill_cylinder), `wall` and `layers` the wall points and the wall and dummy points of sphere_walls
/// (cylinder_walls) with n_dummy dummy layers.
struct RoundCount {
  std::size_t filled = 0, wall = 0, layers = 0;
};
RoundCount count_sphere(const Vec& centre, Real radius, Real dp, int n_dummy = 2,
                        const std::optional<Vec>& origin = std::nullopt);
RoundCount count_cylinder(const Vec& base, const Vec& axis, Real radius, Real dp, int n_dummy = 2,
                          const std::optional<Vec>& origin = std::nullopt);


/// A region given by its signed distance: negative inside, positive outside, and in `nearest` the nearest point
/// of its surface.
using SignedDistance = std::function<Real(const Vec& x, Vec& nearest)>;

/// The signed distances of a box [lo, hi], a ball and a cylinder (as in fill_cylinder; in 2D its section, a strip):
/// the shapes of block, sphere and cylinder walls, for bodies that are cut by them.
SignedDistance box_distance(const Vec& lo, const Vec& hi);
SignedDistance sphere_distance(const Vec& centre, Real radius);
SignedDistance cylinder_distance(const Vec& base, const Vec& axis, Real radius);

/// Cells per axis of a region's lattice in its bounding box [lo, hi]: ceil(side / dp) (within 1e-9 of a whole
/// number: that number), at least 1, so that the lattice covers the box (a rectangle's side is rounded instead).
IVec region_cells(const Vec& lo, const Vec& hi, Real dp);

/// A lattice point within surface_tolerance dp of a region's surface is on it, whatever the sign of its distance's
/// round-off: it counts as outside (on the fluid's side of a wall).
inline constexpr Real surface_tolerance = 1e-9;

/// Particle centres filling a region: the points lo + (i + 1/2 [, ...]) dp, i_a < region_cells, of the lattice
/// anchored at the low corner lo of its bounding box whose signed distance is negative (a point on the surface is
/// outside). For a box [lo, hi] with whole cells these are fill_rectangle's points, in its order; a side that is no
/// whole number of cells ends at the surface (a rectangle's side is rounded to whole cells instead).
std::vector<Vec> fill_region(const Vec& lo, const Vec& hi, Real dp, const SignedDistance& distance);

/// Walls of a region on the lattice of fill_region. With `fluid_inside` false the region is a solid obstacle: its
/// wall and dummy layers lie inside the surface; with true it is a container (a tank): they lie outside, on the
/// lattice extended by 1 + n_dummy cells on each side, and with open_top none above the bounding box (the last
/// axis). A point's layer is its distance in cells (the largest over the axes) from the nearest lattice point on
/// the fluid's side (a point on the surface is on the fluid's side): 1 is the wall layer, 2 to 1 + n_dummy the
/// dummy layers, deeper points are left out. So a box container is box_walls and a box obstacle block_walls, point
/// for point and in their order. to_surface is the offset to the nearest surface point.
std::vector<WallPoint> region_walls(const Vec& lo, const Vec& hi, Real dp, const SignedDistance& distance,
                                    bool fluid_inside, bool open_top, int n_dummy = 2);

}  // namespace mpsfsi
