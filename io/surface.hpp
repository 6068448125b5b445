// Closed surfaces for bodies and walls given by a shape instead of a rectangle: an STL or OBJ file (3D) or a
// polygon (2D, its points in the case file or in a text file), scaled, rotated and translated as the case says,
// checked (closed, consistently oriented with outward normals, not empty), and queried by signed distance for
// the lattice builders of core/geometry.hpp (fill_region, region_walls). VTK reads the files and answers the
// queries (vtkSTLReader, vtkOBJReader, vtkImplicitPolyDataDistance; vtkPolygon and vtkLine in 2D).
#pragma once

#include "core/geometry.hpp"
#include "core/types.hpp"

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpsfsi {

/// A surface that cannot be used: the message says what is wrong with it (the parser adds the key and value).
class SurfaceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Scale, then rotate about the origin, then translate. In 3D the rotation is about x, then y, then z by the
/// angles [rx, ry, rz] in degrees; in 2D about the origin by `rotate`[0] degrees (counter-clockwise).
struct SurfaceTransform {
  Vec scale = Vec::Ones();
  Eigen::Matrix<Real, 3, 1> rotate_deg = Eigen::Matrix<Real, 3, 1>::Zero();
  Vec translate = Vec::Zero();
  /// The map x -> R (S x) + t.
  Vec apply(const Vec& x) const;
};

class ClosedSurface {
 public:
  /// 3D: an STL (ASCII or binary) or OBJ file; 2D: a text file of polygon points, "x y" or "x, y" per line ('#'
  /// starts a comment). Throws SurfaceError when the file cannot be read or the surface is not a closed,
  /// consistently oriented surface with outward normals (3D) or a simple polygon (2D).
  static std::shared_ptr<const ClosedSurface> from_file(const std::string& path, const SurfaceTransform& transform);
  /// 2D: the polygon through `points` (either orientation; the last point joins the first, a repeated first point
  /// at the end is dropped). Throws SurfaceError for fewer than 3 distinct points, repeated consecutive points, a
  /// polygon that crosses itself or one of zero area. In 3D it throws (polygons are 2D).
  static std::shared_ptr<const ClosedSurface> from_polygon(std::vector<Vec> points, const SurfaceTransform& transform);

  ~ClosedSurface();
  ClosedSurface(const ClosedSurface&) = delete;
  ClosedSurface& operator=(const ClosedSurface&) = delete;

  /// The bounding box of the transformed surface.
  const Rect& bounds() const { return bounds_; }
  /// The enclosed volume (area in 2D) [m^dim].
  Real volume() const { return volume_; }
  /// Triangles (3D) or edges (2D).
  std::size_t n_facets() const { return n_facets_; }
  /// Where it comes from: the file's path, or "a polygon of N points".
  const std::string& source() const { return source_; }

  /// The signed distance of x (negative inside) and the nearest surface point.
  Real signed_distance(const Vec& x, Vec& nearest) const;
  /// The same as a function for core/geometry.hpp's builders (it keeps this surface alive).
  static SignedDistance distance_function(const std::shared_ptr<const ClosedSurface>& surface);

 private:
  ClosedSurface();
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Rect bounds_;
  Real volume_ = 0;
  std::size_t n_facets_ = 0;
  std::string source_;
};

}  // namespace mpsfsi
