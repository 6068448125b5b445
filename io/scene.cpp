// Scene building from a case: lattice bodies, walls, clamps, initial motion, overlap check; the particle
// count and memory a case needs, from its rectangles alone, checked against the machine before building.
#include "io/scene.hpp"

#include "core/geometry.hpp"
#include "core/kernel.hpp"
#include "core/neighbours.hpp"
#include "core/text.hpp"
#include "io/surface.hpp"

#include <fmt/format.h>

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace mpsfsi {

namespace {

/// The volume (area in 2D) of a sphere or cylinder.
double round_volume(const RoundShape& s) {
  if (s.kind == RoundShape::Kind::sphere)
    return dim == 2 ? pi * s.radius * s.radius : 4.0 / 3.0 * pi * std::pow(s.radius, 3);
  return (dim == 2 ? 2 * s.radius : pi * s.radius * s.radius) * s.axis.norm();
}

/// The signed distance of an obstacle wall's shape (block, sphere, cylinder, surface), for the bodies it is cut out of.
SignedDistance wall_distance(const WallSpec& w) {
  if (w.type == WallType::surface) return ClosedSurface::distance_function(w.surface);
  if (w.type == WallType::sphere) return sphere_distance(w.round->centre, w.round->radius);
  if (w.type == WallType::cylinder) return cylinder_distance(w.round->centre, w.round->axis, w.round->radius);
  return box_distance(w.rect.lo, w.rect.hi);
}

/// Whether a point of a solid body is in its clamp (a point on the clamp's face to round-off, its centre
/// lo + (i + 1/2) dp, is in).
bool in_clamp(const CaseSpec& spec, const BodySpec& b, const Vec& x) {
  if (!b.clamp) return false;
  return Rect{b.clamp->lo.array() - 1e-9 * spec.dp, b.clamp->hi.array() + 1e-9 * spec.dp}.contains(x);
}

/// The corner of the case's lattice (core/geometry.hpp, lattice_rect): the first box wall's (the tank's) low corner,
/// else the first rectangle body's, else the origin. Every body and wall is filled on it: rectangles by lattice_rect,
/// spheres, cylinders and surfaces from the lattice corner below their bounding box (lattice_corner).
Vec lattice_origin(const CaseSpec& spec) {
  for (const auto& w : spec.walls)
    if (w.type == WallType::box) return w.rect.lo;
  for (const auto& b : spec.bodies)
    if (!b.surface && !b.round) return b.rect.lo;
  return Vec::Zero();
}

/// A rectangle of the case on its lattice.
Rect on_lattice(const CaseSpec& spec, const Rect& r) { return lattice_rect(r.lo, r.hi, lattice_origin(spec), spec.dp); }

/// The dummy layers behind every wall layer: the wall builders' default (core/geometry.hpp).
constexpr int n_dummy_layers = 2;

/// The corner from which a region of the case (a surface's bounding box from lo) is filled: on the case's lattice.
Vec region_corner(const CaseSpec& spec, const Vec& lo) { return lattice_corner(lo, lattice_origin(spec), spec.dp); }

/// The lattice points of a sphere or cylinder and of its wall layers (core/geometry.hpp) on the case's lattice, counted.
RoundCount count_round(const CaseSpec& spec, const RoundShape& s) {
  return s.kind == RoundShape::Kind::sphere
             ? count_sphere(s.centre, s.radius, spec.dp, n_dummy_layers, lattice_origin(spec))
             : count_cylinder(s.centre, s.axis, s.radius, spec.dp, n_dummy_layers, lattice_origin(spec));
}

/// The lattice points of a body: its shape filled, less the points of the walls it names in `subtract` and the
/// points inside them. Walls and bodies share the lattice, so every point next to a wall's surface is either the
/// wall's or the body's: a face off the lattice (a slope, a curve) leaves no empty points between them.
std::vector<Vec> body_points(const CaseSpec& spec, const BodySpec& b) {
  const Rect rect = b.surface || b.round ? b.rect : on_lattice(spec, b.rect);
  std::vector<Vec> points =
      b.surface  ? fill_region(region_corner(spec, b.rect.lo), b.rect.hi, spec.dp, ClosedSurface::distance_function(b.surface))
      : !b.round ? fill_rectangle(rect.lo, rect.hi, spec.dp)
      : b.round->kind == RoundShape::Kind::sphere
          ? fill_sphere(b.round->centre, b.round->radius, spec.dp, lattice_origin(spec))
          : fill_cylinder(b.round->centre, b.round->axis, b.round->radius, spec.dp, lattice_origin(spec));
  for (const std::string& name : b.subtract) {
    const auto w = std::find_if(spec.walls.begin(), spec.walls.end(), [&](const WallSpec& x) { return x.name == name; });
    if (w == spec.walls.end()) throw CaseError(fmt::format("{}: body '{}': no wall '{}' to subtract", spec.file, b.name, name));
    // A block's walls stand on its rectangle on the lattice; a sphere's and a cylinder's take the points on
    // their surface, a surface's leave them to the fluid's side (core/geometry.hpp).
    const bool block = w->type == WallType::box || w->type == WallType::block;
    const Rect on_grid = on_lattice(spec, w->rect);
    const SignedDistance distance = block ? box_distance(on_grid.lo, on_grid.hi) : wall_distance(*w);
    const Real on_surface = surface_tolerance * spec.dp;
    const bool takes_surface = w->type == WallType::sphere || w->type == WallType::cylinder;
    Vec nearest;
    points.erase(std::remove_if(points.begin(), points.end(),
                                [&](const Vec& x) {
                                  const Real d = distance(x, nearest);
                                  return takes_surface ? d <= on_surface : d < -on_surface;
                                }),
                 points.end());
  }
  return points;
}

/// The wall points of a wall (core/geometry.hpp's builders).
std::vector<WallPoint> wall_points(const CaseSpec& spec, const WallSpec& w) {
  switch (w.type) {
    case WallType::box: {
      const Rect r = on_lattice(spec, w.rect);
      return box_walls(r.lo, r.hi, spec.dp, w.open_top, n_dummy_layers);
    }
    case WallType::block: {
      const Rect r = on_lattice(spec, w.rect);
      return block_walls(r.lo, r.hi, spec.dp, n_dummy_layers);
    }
    case WallType::sphere:
      return sphere_walls(w.round->centre, w.round->radius, spec.dp, n_dummy_layers, lattice_origin(spec));
    case WallType::cylinder:
      return cylinder_walls(w.round->centre, w.round->axis, w.round->radius, spec.dp, n_dummy_layers, lattice_origin(spec));
    case WallType::surface:
      return region_walls(region_corner(spec, w.rect.lo), w.rect.hi, spec.dp, ClosedSurface::distance_function(w.surface),
                          w.fluid_inside, w.open_top, n_dummy_layers);
  }
  return {};
}

/// What a body's or wall's shape is, for `check`: "" for a rectangle.
std::string shape_name(const std::optional<RoundShape>& round, const std::shared_ptr<const ClosedSurface>& surface) {
  if (surface) return dim == 2 ? "polygon" : "surface";
  if (round) return round->kind == RoundShape::Kind::sphere ? (dim == 2 ? "disc" : "sphere") : "cylinder";
  return "";
}

/// Where a surface comes from, for `check`: "hull.stl, 1204 triangles", "a polygon of 4 points, 4 edges".
std::string surface_source(const ClosedSurface& surface) {
  return fmt::format("{}, {} {}", surface.source(), surface.n_facets(), dim == 2 ? "edges" : "triangles");
}

void add_body(const CaseSpec& spec, const BodySpec& b, Scene& scene) {
  auto& p = scene.particles;
  const int body_index = static_cast<int>(p.bodies.size());
  const bool is_solid = b.kind == BodyKind::solid;
  const int material = is_solid ? spec.solid_material_index(b.material) : spec.fluid_material_index(b.material);
  if (material < 0) throw CaseError(fmt::format("{}: body '{}': unknown material '{}'", spec.file, b.name, b.material));
  p.bodies.push_back({b.name, is_solid ? ParticleKind::solid : ParticleKind::fluid, material});
  const auto points = body_points(spec, b);
  if (points.empty())
    throw CaseError(fmt::format("{}: body '{}' holds no lattice point at dp = {:g} m; expected a larger body or a smaller dp",
                                spec.file, b.name, spec.dp));
  Vec centroid = Vec::Zero();
  for (const auto& x : points) centroid += x;
  centroid /= static_cast<Real>(points.size());
  BodyCount count;
  count.name = b.name;
  count.kind = is_solid ? "solid" : "fluid";
  count.n_particles = points.size();
  // The free length is measured along the axis the clamp cuts (free_part), else along the longest side
  // (the last of equally long ones).
  const Rect free_rect = free_part(b);
  int free_axis = 0;
  for (int a = 1; a < dim; ++a)
    if (b.rect.size()[a] >= b.rect.size()[free_axis]) free_axis = a;
  for (int a = 0; a < dim; ++a)
    if (free_rect.lo[a] != b.rect.lo[a] || free_rect.hi[a] != b.rect.hi[a]) free_axis = a;
  Vec lo = Vec::Constant(std::numeric_limits<Real>::max()), hi = -lo;
  Real free_lo = std::numeric_limits<Real>::max(), free_hi = -free_lo;
  for (const auto& x : points) {
    const bool clamp = is_solid && in_clamp(spec, b, x);
    const Vec r = x - centroid;
    // Rigid motion: v = v0 + omega x r.
    const Vec v = clamp ? Vec::Zero() : Vec(b.velocity + cross(b.angular_velocity, r));
    p.add(x, v, is_solid ? ParticleKind::solid : ParticleKind::fluid, body_index, material, clamp);
    count.n_clamped += clamp;
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
    if (!clamp) free_lo = std::min(free_lo, x[free_axis]), free_hi = std::max(free_hi, x[free_axis]);
  }
  const Vec half = Vec::Constant(0.5 * spec.dp);
  count.extent = {lo - half, hi + half};
  count.shape = shape_name(b.round, b.surface);
  if (b.surface) {
    count.shape_volume = b.surface->volume();
    count.shape_bounds = b.surface->bounds();
    count.shape_source = surface_source(*b.surface);
  } else if (b.round) {
    count.shape_volume = round_volume(*b.round);
  } else if (b.subtract.empty()) {
    count.extent_difference = std::max((count.extent.lo - b.rect.lo).cwiseAbs().maxCoeff(),
                                       (count.extent.hi - b.rect.hi).cwiseAbs().maxCoeff());
  }
  if (is_solid && b.clamp) {
    count.free_axis = free_axis;
    count.free_length = free_hi >= free_lo ? free_hi - free_lo + spec.dp : 0;
    count.file_free_length = free_rect.size()[free_axis];
  }
  scene.counts.push_back(count);
}

/// Wall particles give way to clamped solid particles embedded in the wall (a plate clamped into the
/// floor): a wall point closer than dp/2 to a clamped particle (`clamped`: their positions) is left out.
bool taken_by_clamp(const std::vector<Vec>& clamped, const Vec& x, const Real dp) {
  for (const Vec& c : clamped)
    if ((c - x).squaredNorm() < 0.25 * dp * dp) return true;
  return false;
}

/// `clamped`: the positions of the clamped particles of the bodies (added before the walls).
void add_wall(const CaseSpec& spec, const WallSpec& w, const std::vector<Vec>& clamped, Scene& scene) {
  auto& p = scene.particles;
  const int body_index = static_cast<int>(p.bodies.size());
  p.bodies.push_back({w.name, ParticleKind::wall, -1});
  const auto all_points = wall_points(spec, w);
  std::vector<WallPoint> points;
  for (const auto& pt : all_points)
    if (!taken_by_clamp(clamped, pt.x, spec.dp)) points.push_back(pt);
  BodyCount count;
  count.name = w.name;
  count.kind = "wall";
  count.n_particles = points.size();
  count.shape = shape_name(w.round, w.surface);
  if (w.surface) {
    count.shape_volume = w.surface->volume();
    count.shape_bounds = w.surface->bounds();
    count.shape_source = surface_source(*w.surface);
  }
  const std::size_t first = p.size();
  for (const auto& pt : points) {
    p.add(pt.x, Vec::Zero(), pt.is_wall ? ParticleKind::wall : ParticleKind::dummy, body_index, -1);
    (pt.is_wall ? count.n_wall : count.n_dummy) += 1;
  }
  auto& to_surface = p.add_vector_field(wall_surface_field);
  for (std::size_t k = 0; k < points.size(); ++k) to_surface[first + k] = points[k].to_surface;
  scene.counts.push_back(count);
}

/// Points sorted by the cells of side `side` that hold them, with the cells at hand as a sorted list (memory of
/// the points only, not of a grid over their bounding box): which points lie in the 3^dim cells around a point.
class SparseCells {
 public:
  SparseCells(const Real side, const std::vector<Vec>& x, const std::vector<std::size_t>& index) : side_(side) {
    cells_.reserve(index.size());
    for (const std::size_t i : index) cells_.emplace_back(cell_of(x[i]), i);
    std::sort(cells_.begin(), cells_.end(), [](const auto& a, const auto& b) { return less(a.first, b.first); });
  }

  /// Call visit(i) for every point i in the 3^dim cells around q's cell (all points within `side` of q, and some
  /// farther), until visit returns true; return whether it did.
  template <class Visit>
  bool any_near(const Vec& q, Visit&& visit) const {
    const IVec c = cell_of(q);
    int n_around = 1;
    for (int a = 0; a < dim; ++a) n_around *= 3;
    for (int m = 0; m < n_around; ++m) {
      IVec k = c;
      for (int a = 0, r = m; a < dim; ++a, r /= 3) k[a] += r % 3 - 1;
      const auto range = std::equal_range(cells_.begin(), cells_.end(), std::make_pair(k, std::size_t{0}),
                                          [](const auto& x, const auto& y) { return less(x.first, y.first); });
      for (auto it = range.first; it != range.second; ++it)
        if (visit(it->second)) return true;
    }
    return false;
  }

 private:
  static bool less(const IVec& a, const IVec& b) {
    return std::lexicographical_compare(a.data(), a.data() + dim, b.data(), b.data() + dim);
  }
  IVec cell_of(const Vec& x) const { return IVec((x / side_).array().floor().cast<int>()); }

  Real side_;
  std::vector<std::pair<IVec, std::size_t>> cells_;
};

bool is_wall(const ParticleSet& p, const std::size_t i) {
  return p.kind[i] == ParticleKind::wall || p.kind[i] == ParticleKind::dummy;
}

std::vector<std::size_t> walls_of(const ParticleSet& p) {
  std::vector<std::size_t> walls;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (is_wall(p, i)) walls.push_back(i);
  return walls;
}

/// The closed lattice cells (side dp) of the wall and dummy particles, to ask which other body's cell covers a
/// point.
class WallCells {
 public:
  WallCells(const Real dp, const ParticleSet& p) : dp_(dp), p_(p), cells_(dp, p.position, walls_of(p)) {}

  /// Whether q lies in the closed cell of a wall or dummy particle of a body other than `body`.
  bool covered(const Vec& q, const int body) const {
    const Real reach = 0.5 * dp_ * (1 + 1e-9);
    return cells_.any_near(q, [&](const std::size_t j) {
      return p_.body[j] != body && (q - p_.position[j]).cwiseAbs().maxCoeff() <= reach;
    });
  }

 private:
  Real dp_;
  const ParticleSet& p_;
  SparseCells cells_;
};

/// A wall particle on an edge or corner of its body (its offset to the surface has two or more components: the
/// faces at the same distance) whose nearest surface point, that edge or corner, lies on another wall body (a block
/// standing on the floor, a piston sliding on it) points at its faces that are not covered instead: a fluid particle
/// put back out of the corner's cell then leaves towards the water, not into the seam between the two bodies,
/// along which it could slide under the block. A point is covered when it is in the closed cell (side dp) of a
/// wall or dummy particle of another body. Offsets of other particles, and corners whose faces are all covered
/// or none, are left as they are.
void uncover_wall_corners(const WallCells& cells, ParticleSet& p) {
  auto& to_surface = p.vector_field(wall_surface_field);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec s = to_surface[i];
    if (!is_wall(p, i) || (s.array() != 0).count() < 2 || !cells.covered(p.position[i] + s, p.body[i])) continue;
    Vec open = Vec::Zero();
    for (int a = 0; a < dim; ++a) {
      if (s[a] == 0) continue;
      Vec face = Vec::Zero();
      face[a] = s[a];
      if (!cells.covered(p.position[i] + face, p.body[i])) open[a] = s[a];
    }
    if (!open.isZero()) to_surface[i] = open;
  }
}

/// A wall or dummy particle of a body given by its surface (`shaped`: polygon, STL or OBJ surface, sphere, cylinder)
/// whose nearest surface point lies on another wall body (the foot of a beach on the floor, the end of a wedge
/// against the tank's side) points instead at the plane of the nearest surface point of its body that is not
/// covered (of the body's particles within 6 dp): the foot of the perpendicular onto that point's plane. So the
/// put-back of fluid near where the two bodies meet goes to the wetted face, not to the covered one, and the planes
/// of the particles there close the gaps between their cells and the wetted face (docs/architecture.md, "Walls
/// hold water"). Along a shallow slope on the floor the covered foot is the nearest face of the particles up to
/// 1.5 dp below the slope, over a stretch of dp / slope. Particles with no uncovered surface point within reach
/// (deep in a body lying on another) are left as they are.
void uncover_shaped_walls(const WallCells& cells, const std::vector<const WallSpec*>& wall_of_body, const Real dp,
                          ParticleSet& p) {
  auto& to_surface = p.vector_field(wall_surface_field);
  const auto is_shaped = [&](const std::size_t i) {
    const auto b = static_cast<std::size_t>(p.body[i]);
    return is_wall(p, i) && b < wall_of_body.size() && wall_of_body[b] != nullptr && wall_of_body[b]->is_shaped();
  };
  std::vector<char> open(p.size(), 0);  // the particle's surface point is not covered
  std::vector<std::size_t> hidden;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!is_shaped(i)) continue;
    open[i] = !cells.covered(p.position[i] + to_surface[i], p.body[i]);
    if (!open[i]) hidden.push_back(i);
  }
  // The open particles by cells of side `reach`: a hidden particle's candidates are in the 3^dim cells around it.
  const Real reach = 6 * dp, reach2 = reach * reach;
  std::vector<std::size_t> opened;
  for (std::size_t k = 0; k < p.size(); ++k)
    if (open[k]) opened.push_back(k);
  const SparseCells open_cells(reach, p.position, opened);
  std::vector<Vec> moved(hidden.size(), Vec::Zero());
  for (std::size_t h = 0; h < hidden.size(); ++h) {
    const std::size_t i = hidden[h];
    std::size_t best = p.size();
    Real best2 = std::numeric_limits<Real>::max();
    open_cells.any_near(p.position[i], [&](const std::size_t k) {
      if (p.body[k] != p.body[i] || (p.position[k] - p.position[i]).squaredNorm() >= reach2) return false;
      const Real d2 = (p.position[k] + to_surface[k] - p.position[i]).squaredNorm();
      if (d2 < best2 || (d2 == best2 && best < p.size() && p.global_id[k] < p.global_id[best])) {
        best = k;
        best2 = d2;
      }
      return false;
    });
    if (best == p.size()) continue;
    const Vec n = to_surface[best].normalized();
    const Real depth = (p.position[best] + to_surface[best] - p.position[i]).dot(n);
    if (depth > 0) moved[h] = depth * n;
  }
  for (std::size_t h = 0; h < hidden.size(); ++h)
    if (!moved[h].isZero()) to_surface[hidden[h]] = moved[h];
}

/// A wall or dummy particle whose surface point lies on a face it shares with a shaped obstacle wall (a polygon,
/// STL or OBJ surface, sphere or cylinder that is not a container) that is thinner than dp/2 above it, too thin for
/// particles of its own (the floor under the toe of a beach standing on it), points at the wetted face over it
/// instead: the foot of the perpendicular onto the plane of the face where the normal through its surface point
/// leaves the shape. So the put-back's gap rule closes the sliver between its cell and that face
/// (docs/architecture.md, "Walls hold water").
void point_under_slivers(const CaseSpec& spec, const std::vector<const WallSpec*>& wall_of_body, ParticleSet& p) {
  auto& to_surface = p.vector_field(wall_surface_field);
  const Real sliver = 0.5 * spec.dp, step_in = 1e-6 * spec.dp;
  for (std::size_t b = 0; b < wall_of_body.size(); ++b) {
    if (wall_of_body[b] == nullptr || !wall_of_body[b]->is_shaped() || wall_of_body[b]->is_container()) continue;
    const WallSpec& w = *wall_of_body[b];
    const int body = static_cast<int>(b);
    const SignedDistance distance = wall_distance(w);
    const Vec lo = w.rect.lo.array() - spec.dp, hi = w.rect.hi.array() + spec.dp;
    Vec nearest;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (!is_wall(p, i) || p.body[i] == body) continue;
      const Vec q = p.position[i] + to_surface[i];
      if ((q.array() < lo.array()).any() || (q.array() > hi.array()).any()) continue;
      const Vec n = to_surface[i].normalized();  // towards the water
      if (distance(q + step_in * n, nearest) >= 0 || distance(q + sliver * n, nearest) <= 0) continue;
      Real inside = step_in, outside = sliver;  // where the normal through q leaves the shape
      for (int k = 0; k < 40; ++k) {
        const Real t = 0.5 * (inside + outside);
        (distance(q + t * n, nearest) < 0 ? inside : outside) = t;
      }
      const Vec beyond = q + (outside + step_in) * n;
      if (!(distance(beyond, nearest) > 0)) continue;
      const Vec m = (beyond - nearest).normalized();  // the face's outward normal there
      const Real depth = (nearest - p.position[i]).dot(m);
      if (depth > 0) to_surface[i] = depth * m;
    }
  }
}

/// Each body's wall spec (by name), or null for a body that is not a wall.
std::vector<const WallSpec*> walls_by_body(const CaseSpec& spec, const ParticleSet& p) {
  std::vector<const WallSpec*> wall_of_body(p.bodies.size(), nullptr);
  for (std::size_t b = 0; b < p.bodies.size(); ++b)
    for (const auto& w : spec.walls)
      if (w.name == p.bodies[b].name && p.bodies[b].kind == ParticleKind::wall) wall_of_body[b] = &w;
  return wall_of_body;
}

/// No two particles of different bodies closer than dp, to round-off: every body is filled on the case's lattice,
/// so bodies that touch sit dp apart, and a closer pair is an overlap (or a body thinner than dp beside another,
/// which keeps one cell off the lattice). The particles sorted by cells of side dp (SparseCells).
void check_overlap(const CaseSpec& spec, const ParticleSet& p) {
  const Real h = spec.dp * (1 - 1e-6);
  std::vector<std::size_t> all(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!p.position[i].allFinite()) throw CaseError(fmt::format("{}: a particle position is not finite", spec.file));
    all[i] = i;
  }
  const SparseCells cells(h, p.position, all);
  for (std::size_t i = 0; i < p.size(); ++i) {
    // The first pair in index order: the lowest i, then its lowest j (then i < j).
    std::size_t j_min = p.size();
    cells.any_near(p.position[i], [&](const std::size_t j) {
      // r = 0 included (unlike in_support): two walls on the same lattice points overlap too.
      if (p.body[i] != p.body[j] && (p.position[j] - p.position[i]).squaredNorm() < h * h)
        j_min = std::min(j_min, j);
      return false;
    });
    if (j_min == p.size()) continue;
    const std::size_t j = j_min;
    throw CaseError(fmt::format(
        "{}: bodies '{}' and '{}' overlap: particles at {} and {} are closer than dp = {:g} m; "
        "expected bodies that at most touch (bodies thinner than dp need a smaller dp)",
        spec.file, p.bodies[p.body[i]].name, p.bodies[p.body[j]].name, show_point(p.position[i]),
        show_point(p.position[j]), spec.dp));
  }
}

}  // namespace

Scene build_scene(const CaseSpec& spec, const std::optional<std::size_t>& available_memory) {
  check_scene_size(spec, available_memory);
  Scene scene;
  for (const auto& b : spec.bodies) add_body(spec, b, scene);
  std::vector<Vec> clamped;
  for (std::size_t i = 0; i < scene.particles.size(); ++i)
    if (scene.particles.clamped[i]) clamped.push_back(scene.particles.position[i]);
  for (const auto& w : spec.walls) add_wall(spec, w, clamped, scene);
  check_overlap(spec, scene.particles);
  if (scene.particles.has_vector_field(wall_surface_field)) {
    const WallCells cells(spec.dp, scene.particles);
    uncover_wall_corners(cells, scene.particles);
    const std::vector<const WallSpec*> wall_of_body = walls_by_body(spec, scene.particles);
    uncover_shaped_walls(cells, wall_of_body, spec.dp, scene.particles);
    point_under_slivers(spec, wall_of_body, scene.particles);
  }
  return scene;
}

namespace {

/// Lattice cells along each side of a rectangle of the case, on the case's lattice (as build_scene fills it).
using Cells = std::array<std::size_t, dim>;
Cells cells(const CaseSpec& spec, const Rect& r) {
  const Rect on = on_lattice(spec, r);
  Cells n;
  for (int a = 0; a < dim; ++a) n[a] = static_cast<std::size_t>(lattice_cells(on.size()[a], spec.dp));
  return n;
}

std::size_t product(const Cells& n) {
  std::size_t p = 1;
  for (const std::size_t k : n) p *= k;
  return p;
}

/// Cells of a box's wall (box_walls) within `layers` layers outside its inner n cells (no layers above
/// the top, the last axis, when it is open).
std::size_t box_cells(const Cells& n, const std::size_t layers, const bool open_top) {
  Cells outer = n;
  for (int a = 0; a < dim; ++a) outer[a] += (a == dim - 1 && open_top ? 1 : 2) * layers;
  return product(outer) - product(n);
}

/// Cells of a block (block_walls) at most `depth` cells deep from its boundary.
std::size_t block_cells(const Cells& n, const std::size_t depth) {
  const std::size_t core = 2 * (depth + 1);
  Cells inner = n;
  for (auto& k : inner) k = k > core ? k - core : 0;
  return product(n) - product(inner);
}

/// Bytes of one particle of a newly built scene (ParticleSet::memory_bytes, before the solvers add fields).
std::size_t particle_bytes() {
  ParticleSet one;
  one.add(Vec::Zero(), Vec::Zero(), ParticleKind::fluid, 0, 0);
  return one.memory_bytes();
}

std::string show_bytes(const double bytes) {
  const char* const units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
  double x = bytes;
  int u = 0;
  while (x >= 1024 && u < 6) x /= 1024, ++u;
  return fmt::format("{:.1f} {}", x, units[u]);
}

}  // namespace


ParticleCounts count_particles(const CaseSpec& spec) {
  ParticleCounts n;
  for (const auto& b : spec.bodies)
    (b.kind == BodyKind::solid ? n.solid : n.fluid) +=
        b.surface || !b.subtract.empty() ? body_points(spec, b).size()  // counted by building them
        : b.round                        ? count_round(spec, *b.round).filled
                                         : product(cells(spec, b.rect));
  constexpr auto n_dummy = static_cast<std::size_t>(n_dummy_layers);
  for (const auto& w : spec.walls) {
    if (w.surface) {  // counted by building them
      for (const WallPoint& x : wall_points(spec, w)) (x.is_wall ? n.wall : n.dummy) += 1;
      continue;
    }
    if (w.round) {  // the layers inside the surface
      const RoundCount c = count_round(spec, *w.round);
      n.wall += c.wall;
      n.dummy += c.layers - c.wall;
      continue;
    }
    const Cells c = cells(spec, w.rect);
    const std::size_t wall = w.type == WallType::box ? box_cells(c, 1, w.open_top) : block_cells(c, 0);
    const std::size_t all = w.type == WallType::box ? box_cells(c, 1 + n_dummy, w.open_top) : block_cells(c, n_dummy);
    n.wall += wall;
    n.dummy += all - wall;
  }
  // Wall points give way to clamped particles embedded in a wall (add_wall). Below a size at which building the
  // clamped particles and the walls takes a moment they are counted exactly; above it the count stays an upper bound
  // by at most the clamped particles, which is all the memory check needs.
  constexpr std::size_t exact_below = 2'000'000;
  if (n.total() >= exact_below) return n;
  std::vector<Vec> clamped;
  for (const auto& b : spec.bodies)
    if (b.kind == BodyKind::solid && b.clamp)
      for (const Vec& x : body_points(spec, b))
        if (in_clamp(spec, b, x)) clamped.push_back(x);
  if (clamped.empty()) return n;
  Vec lo = clamped.front(), hi = clamped.front();
  for (const Vec& x : clamped) lo = lo.cwiseMin(x), hi = hi.cwiseMax(x);
  const Rect near_clamps{lo.array() - spec.dp, hi.array() + spec.dp};
  for (const auto& w : spec.walls)
    for (const WallPoint& x : wall_points(spec, w))
      if (near_clamps.contains(x.x) && taken_by_clamp(clamped, x.x, spec.dp)) (x.is_wall ? n.wall : n.dummy) -= 1;
  return n;
}

std::size_t estimate_memory_bytes(const CaseSpec& spec, const ParticleCounts& count) {
  const auto lap = lattice_constants(spec.dp, spec.fluid.re_laplacian * spec.dp);
  const std::size_t n = count.total();
  const std::size_t n_rows = count.fluid + count.wall;
  const std::size_t nnz = n_rows * static_cast<std::size_t>(lap.n_neighbours + 1);
  // Particles (+ about 10 extra fields), one neighbour list at the largest radius,
  // the pressure matrix (values + column indices) and a preconditioner of similar size.
  const std::size_t fields = n * 10 * sizeof(Real);
  const std::size_t neighbours = n * static_cast<std::size_t>(lap.n_neighbours + 1) * sizeof(LocalIndex);
  const std::size_t matrix = nnz * (sizeof(Real) + sizeof(int));
  // The solid (solid/solid_solver.cpp): per particle about 300 bytes of state and contact scratch, per bond
  // (each pair once, half the neighbours within solid.re) about 85 bytes: reference vector, weights, index,
  // volumetric-strain weights, intact flag, scratch (checked against lamb_a: docs/performance.md, ## Lamb's problem).
  const auto bonds = lattice_constants(spec.dp, spec.solid.re * spec.dp);
  const std::size_t solid = count.solid * (300 + static_cast<std::size_t>(bonds.n_neighbours) / 2 * 85);
  // The run loop keeps a copy of the particle set as the last good frame (written if the run fails).
  return 2 * n * particle_bytes() + fields + neighbours + 3 * matrix + solid;
}

std::size_t estimate_memory_bytes(const CaseSpec& spec, const Scene& scene) {
  const auto& p = scene.particles;
  return estimate_memory_bytes(spec, ParticleCounts{p.n_of_kind(ParticleKind::fluid), p.n_of_kind(ParticleKind::solid),
                                                    p.n_of_kind(ParticleKind::wall), p.n_of_kind(ParticleKind::dummy)});
}

namespace {

/// The value in kB of `key` ("MemAvailable:", "VmSize:") in a /proc file, in bytes.
std::optional<std::size_t> proc_kib(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string k, unit;
    double kib = 0;
    if (s >> k >> kib >> unit && k == key && unit == "kB" && kib >= 0) return static_cast<std::size_t>(kib * 1024);
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::size_t> available_memory_bytes() {
  std::optional<std::size_t> available = proc_kib("/proc/meminfo", "MemAvailable:");
  // A limit on the address space (ulimit -v) leaves this process less than the machine has.
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    const std::size_t used = proc_kib("/proc/self/status", "VmSize:").value_or(0);
    const std::size_t limit = static_cast<std::size_t>(as.rlim_cur);
    const std::size_t left = limit > used ? limit - used : 0;
    available = available ? std::min(*available, left) : left;
  }
  return available;
}

void check_scene_size(const CaseSpec& spec, const std::optional<std::size_t>& available) {
  // Counted in floating point first: the counts of an absurd dp overflow no integer here.
  // A wall is bounded by its faces' cells (2D: the sides') in 3 layers on each side, with 6 cells of margin.
  double cells_total = 0;
  for (const auto& b : spec.bodies) cells_total += (b.rect.size() / spec.dp).array().round().prod();
  for (const auto& w : spec.walls) {
    const Vec n = (w.rect.size() / spec.dp).array().round();
    cells_total += dim == 2 ? 6 * (n[0] + n[1] + 6)
                            : 6 * ((n[0] + 6) * (n[1] + 6) + (n[1] + 6) * (n[dim - 1] + 6) + (n[0] + 6) * (n[dim - 1] + 6));
  }
  const auto too_many = [&](const double n) {
    return CaseError(fmt::format("{}: dp = {:g}: the case would have about {:.3g} particles; expected at most {:g} (a "
                                 "larger dp)",
                                 spec.file, spec.dp, n, max_scene_particles));
  };
  if (!(cells_total <= max_scene_particles)) throw too_many(cells_total);
  // Shapes from surfaces are counted by filling them, point by point against the surface: first an estimate
  // (a body's volume over dp^dim, a wall's cells as above), so that a case far too large for the memory is
  // refused before that.
  if (available) {
    ParticleCounts estimate;
    bool has_surface = false;
    for (const auto& b : spec.bodies) {
      has_surface = has_surface || b.surface;
      const double count = b.surface ? b.surface->volume() / std::pow(spec.dp, dim) : (b.rect.size() / spec.dp).array().round().prod();
      (b.kind == BodyKind::solid ? estimate.solid : estimate.fluid) += static_cast<std::size_t>(count);
    }
    for (const auto& w : spec.walls) {
      has_surface = has_surface || w.surface;
      const Vec c = (w.rect.size() / spec.dp).array().round();
      const double shell = dim == 2 ? 6 * (c[0] + c[1] + 6)
                                    : 6 * ((c[0] + 6) * (c[1] + 6) + (c[1] + 6) * (c[dim - 1] + 6) + (c[0] + 6) * (c[dim - 1] + 6));
      estimate.wall += static_cast<std::size_t>(shell / 3);
      estimate.dummy += static_cast<std::size_t>(2 * shell / 3);
    }
    const double need = static_cast<double>(estimate_memory_bytes(spec, estimate)) + static_cast<double>(program_bytes);
    if (has_surface && need > static_cast<double>(*available))
      throw CaseError(fmt::format("{}: dp = {:g}: the case would have about {:.3g} particles and need about {} of memory, but "
                                  "this machine has {} available (MemAvailable in /proc/meminfo, or less under ulimit -v); "
                                  "expected a case that fits: a larger dp or smaller bodies and walls",
                                  spec.file, spec.dp, static_cast<double>(estimate.total()), show_bytes(need),
                                  show_bytes(static_cast<double>(*available))));
  }
  const ParticleCounts n = count_particles(spec);
  if (static_cast<double>(n.total()) > max_scene_particles) throw too_many(static_cast<double>(n.total()));
  if (!available) return;
  const double need = static_cast<double>(estimate_memory_bytes(spec, n)) + static_cast<double>(program_bytes);
  if (need > static_cast<double>(*available))
    throw CaseError(fmt::format("{}: dp = {:g}: the case would have {} particles ({} fluid, {} solid, {} wall, {} dummy) "
                                "and need about {} of memory, but this machine has {} available (MemAvailable in "
                                "/proc/meminfo, or less under ulimit -v); expected a case that fits: a larger dp or smaller bodies and walls",
                                spec.file, spec.dp, n.total(), n.fluid, n.solid, n.wall, n.dummy, show_bytes(need),
                                show_bytes(static_cast<double>(*available))));
}

}  // namespace mpsfsi
