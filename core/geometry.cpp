// Lattice geometry in MPSFSI_DIM dimensions: filled rectangles / boxes, box walls, wall blocks
// (seed 004 §4.3). Every builder walks the lattice cells with axis 0 fastest (row by row in 2D).
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

std::vector<Vec> fill_rectangle(const Vec& lo, const Vec& hi, const Real dp) {
  const IVec n = cells_of(lo, hi, dp);
  std::vector<Vec> x;
  std::size_t total = 1;
  for (int a = 0; a < dim; ++a) total *= static_cast<std::size_t>(n[a]);
  x.reserve(total);
  for_each_cell(IVec::Zero(), n - IVec::Ones(), [&](const IVec& i) { x.push_back(centre(lo, i, dp)); });
  return x;
}

std::vector<Vec> fill_cylinder(const Vec& base, const Vec& axis, const Real radius, const Real dp) {
  if (!(dp > 0)) throw std::invalid_argument("cylinder: dp must be positive");
  if (!(radius > 0)) throw std::invalid_argument("cylinder: radius must be positive");
  const Real length = axis.norm();
  if (!(length > 0)) throw std::invalid_argument("cylinder: the axis must be non-zero");
  const Vec e = axis / length;
  // Bounding box: the end discs' extents along each coordinate axis, radius sqrt(1 - e_a^2).
  Vec reach;
  for (int a = 0; a < dim; ++a) reach[a] = radius * std::sqrt(std::max(Real(0), 1 - e[a] * e[a]));
  const Vec lo = base.cwiseMin(base + axis) - reach, hi = base.cwiseMax(base + axis) + reach;
  IVec last;
  for (int a = 0; a < dim; ++a) last[a] = static_cast<int>(std::ceil((hi[a] - lo[a]) / dp)) - 1;
  std::vector<Vec> points;
  const Real tol = 1e-9 * dp;
  for_each_cell(IVec::Zero(), last, [&](const IVec& i) {
    const Vec x = centre(lo, i, dp);
    const Real s = (x - base).dot(e);
    if (s < -tol || s > length + tol) return;
    if ((x - base - s * e).norm() <= radius + tol) points.push_back(x);
  });
  return points;
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

}  // namespace mpsfsi
