// O(N) cell-linked neighbour search in MPSFSI_DIM dimensions (counting sort into cells, then a stencil
// of (2 reach + 1)^d cells scanned row by row: the cells of a row along axis 0 are contiguous).
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
  std::size_t n_total = 1;
  for (int a = 0; a < dim; ++a) {
    const double extent = (hi[a] - lo[a]) / cell_size;
    if (extent > 1e8) throw std::runtime_error("CellGrid: particles spread over too many cells");
    n_cells_[a] = static_cast<int>(std::floor(extent)) + 1;
    n_total *= static_cast<std::size_t>(n_cells_[a]);
  }
  if constexpr (dim > 2) {  // (in 2D 1e8 x 1e8 cells overflow nothing; the allocation fails first)
    // Cell indices are stored as LocalIndex.
    if (static_cast<double>(n_cells_.cast<double>().prod()) > 2e9)
      throw std::runtime_error("CellGrid: particles spread over too many cells");
  }
  cell_start_.assign(n_total + 1, 0);
  cell_of_point_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto ci = static_cast<LocalIndex>(cell_index(cell_of(x[i])));
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

CellGrid::Cell CellGrid::cell_of(const Vec& x) const {
  Cell c;
  for (int a = 0; a < dim; ++a) {
    const int k = static_cast<int>((x[a] - origin_[a]) / cell_size_);
    c[a] = std::clamp(k, 0, n_cells_[a] - 1);
  }
  return c;
}

void build_neighbour_list(const std::vector<Vec>& x, const Real radius, NeighbourList& out, CellGrid& grid,
                          const bool sorted_lists) {
  constexpr int reach = 2;  // cells of side radius / reach; stencil of (2 reach + 1)^d cells
  const std::size_t n = x.size();
  grid.build(x, radius / reach);
  const Real r2 = radius * radius;
  out.radius = radius;
  out.offset.resize(n + 1);
  // Keep last step's capacity; the list length changes little from step to step.
  out.index.resize(out.index.capacity());
  out.offset[0] = 0;
  const auto& sorted = grid.sorted();
  const auto& xs = grid.sorted_positions();
  std::size_t n_pairs = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec xi = x[i];
    const CellGrid::Cell c = grid.cell_of_point(i);
    // Stencil bounds per axis, clipped to the grid.
    CellGrid::Cell lo, hi;
    for (int a = 0; a < dim; ++a) {
      lo[a] = std::max(c[a] - reach, 0);
      hi[a] = std::min(c[a] + reach, grid.n_cells(a) - 1);
    }
    // Rows of the stencil: every cell coordinate of axes 1 .. d-1 (an odometer, axis 1 fastest); the
    // cells lo[0] .. hi[0] of a row are contiguous in the sorted arrays.
    CellGrid::Cell row = lo, row_end = lo;
    row_end[0] = hi[0];
    for (;;) {
      const std::size_t first = grid.cell_start(grid.cell_index(row));
      const std::size_t last = grid.cell_start(grid.cell_index(row_end) + 1);
      if (n_pairs + (last - first) > out.index.size()) out.index.resize(2 * (n_pairs + (last - first)) + 1024);
      LocalIndex* dst = out.index.data() + n_pairs;
      for (std::size_t k = first; k < last; ++k) {
        Real d2 = (xs[k][0] - xi[0]) * (xs[k][0] - xi[0]);
        for (int a = 1; a < dim; ++a) d2 += (xs[k][a] - xi[a]) * (xs[k][a] - xi[a]);
        // Branch-free append: write always, advance only for a neighbour.
        *dst = sorted[k];
        dst += (d2 < r2) & (static_cast<std::size_t>(sorted[k]) != i);
      }
      n_pairs = static_cast<std::size_t>(dst - out.index.data());
      int a = 1;
      for (; a < dim; ++a) {
        if (++row[a] <= hi[a]) break;
        row[a] = lo[a];
      }
      if (a == dim) break;
      for (int b = 1; b < dim; ++b) row_end[b] = row[b];
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
