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
  sorted_x_.resize(n);
  for (std::size_t k = 0; k < n; ++k) sorted_x_[k] = x[static_cast<std::size_t>(sorted_[k])];
}

Eigen::Vector2i CellGrid::cell_of(const Vec& x) const {
  Eigen::Vector2i c;
  for (int a = 0; a < 2; ++a) {
    const int k = static_cast<int>((x[a] - origin_[a]) / cell_size_);
    c[a] = std::clamp(k, 0, n_cells_[a] - 1);
  }
  return c;
}

void build_neighbour_list(const std::vector<Vec>& x, const Real radius, NeighbourList& out, CellGrid& grid,
                          const bool sorted_lists) {
  constexpr int reach = 2;  // cells of side radius / reach; stencil of (2 reach + 1)^2 cells
  const std::size_t n = x.size();
  grid.build(x, radius / reach);
  const Real r2 = radius * radius;
  out.radius = radius;
  out.offset.resize(n + 1);
  // Keep last step's capacity; the list length changes little from step to step.
  out.index.resize(out.index.capacity());
  out.offset[0] = 0;
  const int nx = grid.n_cells(0), ny = grid.n_cells(1);
  const auto& sorted = grid.sorted();
  const auto& xs = grid.sorted_positions();
  std::size_t n_pairs = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec xi = x[i];
    const auto c = grid.cell_of_point(i);
    const int cx0 = std::max(c[0] - reach, 0), cx1 = std::min(c[0] + reach, nx - 1);
    for (int cy = std::max(c[1] - reach, 0); cy <= std::min(c[1] + reach, ny - 1); ++cy) {
      // The cells cx0 .. cx1 of a row are contiguous in the sorted arrays.
      const std::size_t first = grid.cell_start(grid.cell_index(cx0, cy));
      const std::size_t last = grid.cell_start(grid.cell_index(cx1, cy) + 1);
      if (n_pairs + (last - first) > out.index.size()) out.index.resize(2 * (n_pairs + (last - first)) + 1024);
      LocalIndex* dst = out.index.data() + n_pairs;
      for (std::size_t k = first; k < last; ++k) {
        const Real dx = xs[k][0] - xi[0], dy = xs[k][1] - xi[1];
        // Branch-free append: write always, advance only for a neighbour.
        *dst = sorted[k];
        dst += (dx * dx + dy * dy < r2) & (static_cast<std::size_t>(sorted[k]) != i);
      }
      n_pairs = static_cast<std::size_t>(dst - out.index.data());
    }
    out.offset[i + 1] = n_pairs;
    if (sorted_lists) {
      // Insertion sort: the lists are short and, for particles kept in cell order, nearly sorted.
      LocalIndex* a = out.index.data() + out.offset[i];
      const std::size_t m = n_pairs - out.offset[i];
      for (std::size_t p = 1; p < m; ++p) {
        const LocalIndex v = a[p];
        std::size_t q = p;
        for (; q > 0 && a[q - 1] > v; --q) a[q] = a[q - 1];
        a[q] = v;
      }
    }
  }
  out.index.resize(n_pairs);
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
