// O(N) cell-linked neighbour search (counting sort into cells, then a 3x3 cell stencil).
#include "core/neighbours.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>

namespace mpsfsi {

void CellGrid::build(const std::vector<Vec>& x, const Real cell_size) {
  if (!(cell_size > 0)) throw std::invalid_argument("CellGrid: cell size must be positive");
  cell_size_ = cell_size;
  const std::size_t n = x.size();
  Vec lo = Vec::Constant(0), hi = Vec::Constant(0);
  if (n > 0) {
    lo = hi = x[0];
    for (const auto& p : x) {
      if (!p.allFinite()) throw std::runtime_error("CellGrid: a particle position is not finite");
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  if (!lo.allFinite() || !hi.allFinite())
    throw std::runtime_error("CellGrid: a particle position is not finite");
  origin_ = lo;
  for (int a = 0; a < 2; ++a) {
    const double extent = (hi[a] - lo[a]) / cell_size;
    if (extent > 1e8) throw std::runtime_error("CellGrid: particles spread over too many cells");
    n_cells_[a] = static_cast<int>(std::floor(extent)) + 1;
  }
  const std::size_t n_total = static_cast<std::size_t>(n_cells_[0]) * static_cast<std::size_t>(n_cells_[1]);
  cell_start_.assign(n_total + 1, 0);
  cell_of_point_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = cell_of(x[i]);
    const auto ci = static_cast<LocalIndex>(cell_index(c[0], c[1]));
    cell_of_point_[i] = ci;
    ++cell_start_[static_cast<std::size_t>(ci) + 1];
  }
  for (std::size_t c = 0; c < n_total; ++c) cell_start_[c + 1] += cell_start_[c];
  sorted_.resize(n);
  // Stable counting sort: points keep increasing index order inside a cell.
  std::vector<std::size_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) sorted_[fill[static_cast<std::size_t>(cell_of_point_[i])]++] = static_cast<LocalIndex>(i);
}

Eigen::Vector2i CellGrid::cell_of(const Vec& x) const {
  Eigen::Vector2i c;
  for (int a = 0; a < 2; ++a) {
    const int k = static_cast<int>((x[a] - origin_[a]) / cell_size_);
    c[a] = std::clamp(k, 0, n_cells_[a] - 1);
  }
  return c;
}

void build_neighbour_list(const std::vector<Vec>& x, const Real radius, NeighbourList& out, CellGrid& grid) {
  const std::size_t n = x.size();
  grid.build(x, radius);
  const Real r2 = radius * radius;
  out.radius = radius;
  out.offset.resize(n + 1);
  out.index.clear();
  out.offset[0] = 0;
  const int nx = grid.n_cells(0), ny = grid.n_cells(1);
  const auto& sorted = grid.sorted();
  std::vector<LocalIndex> found;
  found.reserve(128);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec xi = x[i];
    const auto c = grid.cell_of(xi);
    found.clear();
    for (int cy = std::max(c[1] - 1, 0); cy <= std::min(c[1] + 1, ny - 1); ++cy) {
      // Cells (cx-1 .. cx+1, cy) are contiguous in the sorted array.
      const std::size_t first = grid.cell_start(grid.cell_index(std::max(c[0] - 1, 0), cy));
      const std::size_t last = grid.cell_start(grid.cell_index(std::min(c[0] + 1, nx - 1), cy) + 1);
      for (std::size_t k = first; k < last; ++k) {
        const LocalIndex j = sorted[k];
        const Vec d = x[static_cast<std::size_t>(j)] - xi;
        if (d.squaredNorm() < r2 && static_cast<std::size_t>(j) != i) found.push_back(j);
      }
    }
    std::sort(found.begin(), found.end());
    out.index.insert(out.index.end(), found.begin(), found.end());
    out.offset[i + 1] = out.index.size();
  }
}

void build_neighbour_list(const std::vector<Vec>& x, const Real radius, NeighbourList& out) {
  CellGrid grid;
  build_neighbour_list(x, radius, out, grid);
}

std::vector<LocalIndex> cell_order(const std::vector<Vec>& x, const Real cell_size) {
  CellGrid grid;
  grid.build(x, cell_size);
  return grid.sorted();
}

}  // namespace mpsfsi
