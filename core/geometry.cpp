// Lattice geometry in MPSFSI_DIM dimensions: filled rectangles / boxes, spheres and cylinders; box walls, and
// blocks, spheres and cylinders of wall particles (seed 004 §4.3). Every builder walks the lattice cells with
// axis 0 fastest (row by row in 2D). Regions given by a signed distance are filled and walled on the same lattice.
#include "core/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mpsfsi {

namespace {

/// Cells per axis of the box [lo, hi].
IVec cells_of(const Vec& lo, const Vec& hi, const Real dp) {
  IVec n;
  for (int a = 0; a < dim; ++a) n[a] = lattice_cells(hi[a] - lo[a], dp);
  return n;
}

/// Centre lo + (i + 1/2) dp of lattice cell i.
Vec centre(const Vec& lo, const IVec& i, const Real dp) {
  Vec x;
  for (int a = 0; a < dim; ++a) x[a] = lo[a] + (i[a] + 0.5) * dp;
  return x;
}

/// Calls f(i) for every cell i with first[a] <= i[a] <= last[a], axis 0 fastest.
template <class F>
void for_each_cell(const IVec& first, const IVec& last, F&& f) {
  for (int a = 0; a < dim; ++a)
    if (last[a] < first[a]) return;
  IVec i = first;
  for (;;) {
    f(i);
    int a = 0;
    for (; a < dim; ++a) {
      if (++i[a] <= last[a]) break;
      i[a] = first[a];
    }
    if (a == dim) return;
  }
}

}  // namespace

int lattice_cells(const Real length, const Real dp) {
  if (!(dp > 0)) throw std::invalid_argument("lattice: dp must be positive");
  if (!(length > 0)) throw std::invalid_argument("lattice: rectangle side must be positive");
  const double n = std::round(length / dp);
  if (n > 1e8) throw std::invalid_argument("lattice: too many particles along one side");
  return std::max(1, static_cast<int>(n));
}

Rect lattice_rect(const Vec& lo, const Vec& hi, const Vec& origin, const Real dp) {
  if (!(dp > 0)) throw std::invalid_argument("lattice: dp must be positive");
  const Real tol = 1e-9;
  Rect r;
  for (int a = 0; a < dim; ++a) {
    if (!(hi[a] > lo[a])) throw std::invalid_argument("lattice: rectangle side must be positive");
    // Cell k has the centre origin + (k + 1/2) dp; the first with a centre above lo, the last with one at or below hi.
    const double f_lo = (lo[a] - origin[a]) / dp, f_hi = (hi[a] - origin[a]) / dp;
    const double first = std::floor(f_lo - 0.5 + tol) + 1, last = std::floor(f_hi - 0.5 + tol);
    if (std::abs(f_lo) > 1e8 || std::abs(f_hi) > 1e8) throw std::invalid_argument("lattice: too many particles along one side");
    if (last < first) {
      r.lo[a] = lo[a];
      r.hi[a] = lo[a] + dp;
      continue;
    }
    r.lo[a] = std::abs(f_lo - std::round(f_lo)) < tol ? lo[a] : origin[a] + first * dp;
    r.hi[a] = r.lo[a] + (last - first + 1) * dp;
  }
  return r;
}

Vec lattice_corner(const Vec& x, const Vec& origin, const Real dp) {
  if (!(dp > 0)) throw std::invalid_argument("lattice: dp must be positive");
  Vec corner;
  for (int a = 0; a < dim; ++a) {
    const double f = (x[a] - origin[a]) / dp;
    if (std::abs(f) > 1e8) throw std::invalid_argument("lattice: too many particles along one side");
    corner[a] = std::abs(f - std::round(f)) < 1e-9 ? x[a] : origin[a] + std::floor(f) * dp;
  }
  return corner;
}

std::vector<Vec> fill_rectangle(const Vec& lo, const Vec& hi, const Real dp) {
  const IVec n = cells_of(lo, hi, dp);
  std::vector<Vec> x;
  std::size_t total = 1;
  for (int a = 0; a < dim; ++a) total *= static_cast<std::size_t>(n[a]);
  x.reserve(total);
  for_each_cell(IVec::Zero(), n - IVec::Ones(), [&](const IVec& i) { x.push_back(centre(lo, i, dp)); });
  return x;
}

namespace {

/// The anchor of a shape's lattice, lo (or lattice_corner(lo) with an origin), and in `last` the last cell per
/// axis of that lattice that covers the bounding box [lo, hi].
Vec round_lattice(const Vec& lo, const Vec& hi, const Real dp, const std::optional<Vec>& origin, IVec& last) {
  const Vec anchor = origin ? lattice_corner(lo, *origin, dp) : lo;
  for (int a = 0; a < dim; ++a) last[a] = static_cast<int>(std::ceil((hi[a] - anchor[a]) / dp)) - 1;
  return anchor;
}

/// Checks the cylinder's arguments and calls f(x, s, r) for every lattice point x of fill_cylinder inside it,
/// s its coordinate along the unit axis e from `base` and r = x - base - s e its offset from the axis.
template <class F>
void for_each_cylinder_point(const Vec& base, const Vec& axis, const Real radius, const Real dp,
                             const std::optional<Vec>& origin, F&& f) {
  if (!(dp > 0)) throw std::invalid_argument("cylinder: dp must be positive");
  if (!(radius > 0)) throw std::invalid_argument("cylinder: radius must be positive");
  const Real length = axis.norm();
  if (!(length > 0)) throw std::invalid_argument("cylinder: the axis must be non-zero");
  const Vec e = axis / length;
  // Bounding box: the end discs' extents along each coordinate axis, radius sqrt(1 - e_a^2).
  Vec reach;
  for (int a = 0; a < dim; ++a) reach[a] = radius * std::sqrt(std::max(Real(0), 1 - e[a] * e[a]));
  IVec last;
  const Vec lo = round_lattice(base.cwiseMin(base + axis) - reach, base.cwiseMax(base + axis) + reach, dp, origin, last);
  const Real tol = 1e-9 * dp;
  for_each_cell(IVec::Zero(), last, [&](const IVec& i) {
    const Vec x = centre(lo, i, dp);
    const Real s = (x - base).dot(e);
    if (s < -tol || s > length + tol) return;
    const Vec r = x - base - s * e;
    if (r.norm() <= radius + tol) f(x, s, r);
  });
}

/// Checks the ball's arguments and calls f(x) for every lattice point x of fill_sphere inside it.
template <class F>
void for_each_sphere_point(const Vec& centre_point, const Real radius, const Real dp, const std::optional<Vec>& origin,
                           F&& f) {
  if (!(dp > 0)) throw std::invalid_argument("sphere: dp must be positive");
  if (!(radius > 0)) throw std::invalid_argument("sphere: radius must be positive");
  IVec last;
  const Vec lo = round_lattice(centre_point - Vec::Constant(radius), centre_point + Vec::Constant(radius), dp, origin, last);
  const Real tol = 1e-9 * dp;
  for_each_cell(IVec::Zero(), last, [&](const IVec& i) {
    const Vec x = centre(lo, i, dp);
    if ((x - centre_point).norm() <= radius + tol) f(x);
  });
}

/// The wall layer (depth below dp) or a dummy layer (below (1 + n_dummy) dp) of a point at `depth` below a
/// surface: 0 wall, 1 dummy, -1 neither.
int wall_layer(const Real depth, const Real dp, const int n_dummy) {
  if (depth < dp) return 0;
  return depth < (1 + n_dummy) * dp ? 1 : -1;
}

}  // namespace

std::vector<Vec> fill_cylinder(const Vec& base, const Vec& axis, const Real radius, const Real dp,
                               const std::optional<Vec>& origin) {
  std::vector<Vec> points;
  for_each_cylinder_point(base, axis, radius, dp, origin, [&](const Vec& x, Real, const Vec&) { points.push_back(x); });
  return points;
}

std::vector<Vec> fill_sphere(const Vec& centre_point, const Real radius, const Real dp,
                             const std::optional<Vec>& origin) {
  std::vector<Vec> points;
  for_each_sphere_point(centre_point, radius, dp, origin, [&](const Vec& x) { points.push_back(x); });
  return points;
}

namespace {

/// The offset of a wall point `depth` below a surface with outward normal `out`: never zero (a point on the
/// surface, within the lattice's tolerance, gets a millionth of dp), since the fluid takes the surface's normal
/// from it (fluid/fluid_core.cpp keep_out_of_walls).
Vec surface_offset(const Real depth, const Vec& out, const Real dp) { return std::max(depth, 1e-6 * dp) * out; }

/// A unit vector normal to the unit vector e.
Vec normal_to(const Vec& e) {
  int a = 0;  // the coordinate axis least along e
  for (int b = 1; b < dim; ++b)
    if (std::abs(e[b]) < std::abs(e[a])) a = b;
  const Vec u = Vec::Unit(a) - e[a] * e;
  return u.normalized();
}

/// A point x of a sphere's lattice: its depth below the surface and the offset to the nearest surface point.
WallPoint sphere_point(const Vec& x, const Vec& centre_point, const Real radius, const Real dp, Real& depth) {
  const Vec r = x - centre_point;
  const Real rho = r.norm();
  depth = std::max(Real(0), radius - rho);
  // At the centre (a ball of a few particles) any direction is nearest: the last axis.
  const Vec out = rho > 0 ? Vec(r / rho) : Vec(Vec::Unit(dim - 1));
  return {x, false, surface_offset(depth, out, dp)};
}

/// A point x of a cylinder's lattice (s along the unit axis e, r off the axis): its depth below the nearest of
/// the lateral surface and the end faces, and the offset to that surface's nearest point.
WallPoint cylinder_point(const Vec& x, const Real s, const Vec& r, const Vec& e, const Real length, const Real radius,
                         const Real dp, Real& depth) {
  const Real rho = r.norm();
  const Real lateral = std::max(Real(0), radius - rho);
  const Real to_base = std::max(Real(0), s), to_top = std::max(Real(0), length - s);
  depth = std::min({lateral, to_base, to_top});
  if (depth == to_base) return {x, false, surface_offset(depth, -e, dp)};
  if (depth == to_top) return {x, false, surface_offset(depth, e, dp)};
  // On the axis of a thin cylinder any direction normal to it is nearest.
  return {x, false, surface_offset(depth, rho > 0 ? Vec(r / rho) : normal_to(e), dp)};
}

}  // namespace

std::vector<WallPoint> sphere_walls(const Vec& centre_point, const Real radius, const Real dp, const int n_dummy,
                                    const std::optional<Vec>& origin) {
  std::vector<WallPoint> pts;
  for_each_sphere_point(centre_point, radius, dp, origin, [&](const Vec& x) {
    Real depth = 0;
    WallPoint p = sphere_point(x, centre_point, radius, dp, depth);
    const int layer = wall_layer(depth, dp, n_dummy);
    if (layer < 0) return;
    p.is_wall = layer == 0;
    pts.push_back(p);
  });
  return pts;
}

std::vector<WallPoint> cylinder_walls(const Vec& base, const Vec& axis, const Real radius, const Real dp,
                                      const int n_dummy, const std::optional<Vec>& origin) {
  const Real length = axis.norm();
  std::vector<WallPoint> pts;
  for_each_cylinder_point(base, axis, radius, dp, origin, [&](const Vec& x, const Real s, const Vec& r) {
    Real depth = 0;
    WallPoint p = cylinder_point(x, s, r, axis / length, length, radius, dp, depth);
    const int layer = wall_layer(depth, dp, n_dummy);
    if (layer < 0) return;
    p.is_wall = layer == 0;
    pts.push_back(p);
  });
  return pts;
}

RoundCount count_sphere(const Vec& centre_point, const Real radius, const Real dp, const int n_dummy,
                        const std::optional<Vec>& origin) {
  RoundCount c;
  for_each_sphere_point(centre_point, radius, dp, origin, [&](const Vec& x) {
    Real depth = 0;
    sphere_point(x, centre_point, radius, dp, depth);
    const int layer = wall_layer(depth, dp, n_dummy);
    ++c.filled;
    c.wall += layer == 0;
    c.layers += layer >= 0;
  });
  return c;
}

RoundCount count_cylinder(const Vec& base, const Vec& axis, const Real radius, const Real dp, const int n_dummy,
                          const std::optional<Vec>& origin) {
  const Real length = axis.norm();
  RoundCount c;
  for_each_cylinder_point(base, axis, radius, dp, origin, [&](const Vec& x, const Real s, const Vec& r) {
    Real depth = 0;
    cylinder_point(x, s, r, axis / length, length, radius, dp, depth);
    const int layer = wall_layer(depth, dp, n_dummy);
    ++c.filled;
    c.wall += layer == 0;
    c.layers += layer >= 0;
  });
  return c;
}

std::vector<WallPoint> box_walls(const Vec& lo, const Vec& hi, const Real dp, const bool open_top,
                                 const int n_dummy) {
  const IVec n = cells_of(lo, hi, dp);
  const Vec face_hi = lo + n.cast<Real>() * dp;  // the lattice's faces (hi rounded to whole cells)
  const int n_layers = 1 + n_dummy;
  std::vector<WallPoint> pts;
  // Cell i of the extended lattice has centre lo + (i + 1/2) dp; the inner box is 0 <= i_a < n_a.
  // Layer index = distance (in cells, the largest over the axes) outside the inner box. The top is
  // the last axis (y in 2D, z in 3D).
  const IVec first = IVec::Constant(-n_layers);
  IVec last = n + IVec::Constant(n_layers - 1);
  if (open_top) last[dim - 1] = n[dim - 1] - 1;
  for_each_cell(first, last, [&](const IVec& i) {
    int layer = 0;
    for (int a = 0; a < dim; ++a) layer = std::max(layer, i[a] < 0 ? -i[a] : (i[a] >= n[a] ? i[a] - n[a] + 1 : 0));
    if (layer == 0) return;  // inside the box
    const Vec x = centre(lo, i, dp);
    pts.push_back({x, layer == 1, x.cwiseMax(lo).cwiseMin(face_hi) - x});
  });
  return pts;
}

std::vector<WallPoint> block_walls(const Vec& lo, const Vec& hi, const Real dp, const int n_dummy) {
  const IVec n = cells_of(lo, hi, dp);
  std::vector<WallPoint> pts;
  for_each_cell(IVec::Zero(), n - IVec::Ones(), [&](const IVec& i) {
    int depth = i[0];  // 0 on the outer layer
    for (int a = 0; a < dim; ++a) depth = std::min({depth, i[a], n[a] - 1 - i[a]});
    if (depth > n_dummy) return;
    const Vec x = centre(lo, i, dp);
    // The faces at the smallest distance (cells are exact integers, so ties are exact).
    Vec to_surface = Vec::Zero();
    for (int a = 0; a < dim; ++a) {
      if (i[a] == depth) to_surface[a] = lo[a] - x[a];
      else if (n[a] - 1 - i[a] == depth) to_surface[a] = lo[a] + n[a] * dp - x[a];
    }
    pts.push_back({x, depth == 0, to_surface});
  });
  return pts;
}


SignedDistance box_distance(const Vec& lo, const Vec& hi) {
  return [lo, hi](const Vec& x, Vec& nearest) -> Real {
    nearest = x.cwiseMax(lo).cwiseMin(hi);
    if (nearest != x) return (x - nearest).norm();
    // Inside or on the surface: the nearest face (a point on a face is at distance 0, which is not negative).
    int axis = 0;
    bool upper = false;
    Real depth = x[0] - lo[0];
    for (int a = 0; a < dim; ++a)
      for (const bool u : {false, true}) {
        const Real d = u ? hi[a] - x[a] : x[a] - lo[a];
        if (d < depth) depth = d, axis = a, upper = u;
      }
    nearest[axis] = upper ? hi[axis] : lo[axis];
    return depth > 0 ? -depth : Real(0);
  };
}

SignedDistance sphere_distance(const Vec& centre_point, const Real radius) {
  return [centre_point, radius](const Vec& x, Vec& nearest) -> Real {
    const Vec r = x - centre_point;
    const Real rho = r.norm();
    nearest = centre_point + radius * (rho > 0 ? Vec(r / rho) : Vec(Vec::Unit(dim - 1)));
    return rho - radius;
  };
}

SignedDistance cylinder_distance(const Vec& base, const Vec& axis, const Real radius) {
  const Real length = axis.norm();
  const Vec e = axis / length;
  return [base, e, length, radius](const Vec& x, Vec& nearest) -> Real {
    const Real s = (x - base).dot(e);
    const Vec r = x - base - s * e;
    const Real rho = r.norm();
    const Vec u = rho > 0 ? Vec(r / rho) : normal_to(e);
    const Real radial = rho - radius, axial = std::max(-s, s - length);
    if (radial <= 0 && axial <= 0) {  // inside or on the surface: the nearest of the mantle and the end faces
      if (radial >= axial) nearest = base + s * e + radius * u;
      else nearest = base + (-s > s - length ? Real(0) : length) * e + r;
      return std::max(radial, axial);
    }
    nearest = base + std::clamp(s, Real(0), length) * e + std::min(rho, radius) * u;
    return (x - nearest).norm();
  };
}

IVec region_cells(const Vec& lo, const Vec& hi, const Real dp) {
  if (!(dp > 0)) throw std::invalid_argument("lattice: dp must be positive");
  IVec n;
  for (int a = 0; a < dim; ++a) {
    const double c = (hi[a] - lo[a]) / dp;
    if (!(c > 0)) throw std::invalid_argument("lattice: a region's bounding box must have a positive size");
    const double whole = std::round(c);
    const double k = std::abs(c - whole) <= 1e-9 * std::max(1.0, whole) ? whole : std::ceil(c);
    if (k > 1e8) throw std::invalid_argument("lattice: too many particles along one side");
    n[a] = std::max(1, static_cast<int>(k));
  }
  return n;
}

std::vector<Vec> fill_region(const Vec& lo, const Vec& hi, const Real dp, const SignedDistance& distance) {
  std::vector<Vec> points;
  Vec nearest;
  const Real on_surface = surface_tolerance * dp;
  for_each_cell(IVec::Zero(), region_cells(lo, hi, dp) - IVec::Ones(), [&](const IVec& i) {
    const Vec x = centre(lo, i, dp);
    if (distance(x, nearest) < -on_surface) points.push_back(x);
  });
  return points;
}

std::vector<WallPoint> region_walls(const Vec& lo, const Vec& hi, const Real dp, const SignedDistance& distance,
                                    const bool fluid_inside, const bool open_top, const int n_dummy) {
  const IVec n = region_cells(lo, hi, dp);
  const int n_layers = 1 + n_dummy;
  const IVec first = IVec::Constant(fluid_inside ? -n_layers : 0);
  IVec last = n - IVec::Ones() + IVec::Constant(fluid_inside ? n_layers : 0);
  if (fluid_inside && open_top) last[dim - 1] = n[dim - 1] - 1;
  IVec extent = last - first + IVec::Ones();
  std::size_t stride[dim], total = 1;
  for (int a = 0; a < dim; ++a) stride[a] = total, total *= static_cast<std::size_t>(extent[a]);
  const auto index = [&](const IVec& i) {
    std::size_t k = 0;
    for (int a = 0; a < dim; ++a) k += static_cast<std::size_t>(i[a] - first[a]) * stride[a];
    return k;
  };
  // Layer of every point: 0 on the fluid's side, -1 not yet known, else its distance in cells from that side.
  std::vector<signed char> layer(total);
  std::vector<Vec> nearest(total);
  const Real on_surface = surface_tolerance * dp;
  for_each_cell(first, last, [&](const IVec& i) {
    const std::size_t k = index(i);
    const Real d = distance(centre(lo, i, dp), nearest[k]);
    layer[k] = (fluid_inside ? d > on_surface : d < -on_surface) ? -1 : 0;
  });
  // Outside the lattice: the fluid's side around an obstacle, the wall's side (or the open top) around a container.
  const signed char beyond = fluid_inside ? -1 : 0;
  constexpr int n_near = dim == 2 ? 9 : 27;
  for (int l = 1; l <= n_layers; ++l) {
    for_each_cell(first, last, [&](const IVec& i) {
      const std::size_t k = index(i);
      if (layer[k] != -1) return;
      for (int m = 0; m < n_near; ++m) {
        IVec j = i;
        bool inside = true;
        for (int a = 0, q = m; a < dim; ++a, q /= 3) {
          j[a] += q % 3 - 1;
          inside = inside && j[a] >= first[a] && j[a] <= last[a];
        }
        const signed char lj = inside ? layer[index(j)] : beyond;
        if (lj == l - 1) {
          layer[k] = static_cast<signed char>(l);
          return;
        }
      }
    });
  }
  std::vector<WallPoint> points;
  for_each_cell(first, last, [&](const IVec& i) {
    const std::size_t k = index(i);
    if (layer[k] < 1) return;
    const Vec x = centre(lo, i, dp);
    points.push_back({x, layer[k] == 1, nearest[k] - x});
  });
  return points;
}

}  // namespace mpsfsi
