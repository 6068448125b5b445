// Lattice geometry: filled rectangles, box walls, wall blocks (seed 004 §4.3).
#include "core/geometry.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mpsfsi {

int lattice_cells(const Real length, const Real dp) {
  if (!(dp > 0)) throw std::invalid_argument("lattice: dp must be positive");
  if (!(length > 0)) throw std::invalid_argument("lattice: rectangle side must be positive");
  const double n = std::round(length / dp);
  if (n > 1e8) throw std::invalid_argument("lattice: too many particles along one side");
  return std::max(1, static_cast<int>(n));
}

std::vector<Vec> fill_rectangle(const Vec& lo, const Vec& hi, const Real dp) {
  const int nx = lattice_cells(hi[0] - lo[0], dp);
  const int ny = lattice_cells(hi[1] - lo[1], dp);
  std::vector<Vec> x;
  x.reserve(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) x.emplace_back(lo[0] + (i + 0.5) * dp, lo[1] + (j + 0.5) * dp);
  return x;
}

std::vector<WallPoint> box_walls(const Vec& lo, const Vec& hi, const Real dp, const bool open_top,
                                 const int n_dummy) {
  const int nx = lattice_cells(hi[0] - lo[0], dp);
  const int ny = lattice_cells(hi[1] - lo[1], dp);
  const int n_layers = 1 + n_dummy;
  std::vector<WallPoint> pts;
  // Cell (i, j) of the extended lattice has centre lo + (i + 1/2, j + 1/2) dp; the inner box is
  // 0 <= i < nx, 0 <= j < ny. Layer index = distance (in cells) outside the inner box.
  const int j_top = open_top ? ny - 1 : ny - 1 + n_layers;
  for (int j = -n_layers; j <= j_top; ++j) {
    for (int i = -n_layers; i < nx + n_layers; ++i) {
      const int di = i < 0 ? -i : (i >= nx ? i - nx + 1 : 0);
      const int dj = j < 0 ? -j : (j >= ny ? j - ny + 1 : 0);
      const int layer = std::max(di, dj);
      if (layer == 0) continue;  // inside the box
      pts.push_back({Vec(lo[0] + (i + 0.5) * dp, lo[1] + (j + 0.5) * dp), layer == 1});
    }
  }
  return pts;
}

std::vector<WallPoint> block_walls(const Vec& lo, const Vec& hi, const Real dp, const int n_dummy) {
  const int nx = lattice_cells(hi[0] - lo[0], dp);
  const int ny = lattice_cells(hi[1] - lo[1], dp);
  std::vector<WallPoint> pts;
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int depth = std::min({i, j, nx - 1 - i, ny - 1 - j});  // 0 on the outer layer
      if (depth > n_dummy) continue;
      pts.push_back({Vec(lo[0] + (i + 0.5) * dp, lo[1] + (j + 0.5) * dp), depth == 0});
    }
  }
  return pts;
}

}  // namespace mpsfsi
