// O(N) cell-linked neighbour search. Particles are binned into square cells of side >= radius with a
// counting sort; each particle's neighbours (all j != i with |x_j - x_i| < radius) are then found in
// the 3^d surrounding cells and stored in one compressed (CSR) list, rebuilt once per step.
#pragma once

#include "core/types.hpp"

#include <vector>

namespace mpsfsi {

/// Neighbours of every particle in CSR form: the neighbours of i are
/// index[offset[i] .. offset[i+1]), in increasing order of j (or in cell order when built unsorted).
struct NeighbourList {
  Real radius = 0;
  std::vector<std::size_t> offset;  ///< size n + 1
  std::vector<LocalIndex> index;

  std::size_t n_particles() const { return offset.empty() ? 0 : offset.size() - 1; }
  std::size_t n_pairs() const { return index.size(); }
  std::size_t begin(const std::size_t i) const { return offset[i]; }
  std::size_t end(const std::size_t i) const { return offset[i + 1]; }
  std::size_t count(const std::size_t i) const { return offset[i + 1] - offset[i]; }
  std::size_t memory_bytes() const {
    return offset.capacity() * sizeof(std::size_t) + index.capacity() * sizeof(LocalIndex);
  }
};

/// A uniform grid of cells over the bounding box of the points, with the points sorted by cell.
class CellGrid {
 public:
  /// Bin the points into cells of side `cell_size` (> 0).
  void build(const std::vector<Vec>& x, Real cell_size);

  Real cell_size() const { return cell_size_; }
  int n_cells(const int axis) const { return n_cells_[axis]; }
  /// Cell coordinates of a point (clamped to the grid).
  Eigen::Vector2i cell_of(const Vec& x) const;
  /// Linear cell index of cell coordinates.
  std::size_t cell_index(const int cx, const int cy) const {
    return static_cast<std::size_t>(cy) * static_cast<std::size_t>(n_cells_[0]) + static_cast<std::size_t>(cx);
  }
  /// Points in cell c: sorted()[cell_start(c) .. cell_start(c + 1)).
  std::size_t cell_start(const std::size_t c) const { return cell_start_[c]; }
  const std::vector<LocalIndex>& sorted() const { return sorted_; }
  /// Positions in the order of sorted() (contiguous per cell, for fast scanning).
  const std::vector<Vec>& sorted_positions() const { return sorted_x_; }
  /// Cell coordinates of point i as binned by build().
  Eigen::Vector2i cell_of_point(const std::size_t i) const {
    const auto c = static_cast<int>(cell_of_point_[i]);
    return Eigen::Vector2i(c % n_cells_[0], c / n_cells_[0]);
  }

 private:
  Real cell_size_ = 0;
  Vec origin_ = Vec::Zero();
  int n_cells_[2] = {0, 0};
  std::vector<std::size_t> cell_start_;
  std::vector<LocalIndex> sorted_;
  std::vector<LocalIndex> cell_of_point_;
  std::vector<Vec> sorted_x_;
};

/// Build the neighbour list of all points for `radius` (strictly closer than radius, j != i).
/// Cells of side radius / 2 and a 5 x 5 cell stencil: fewer candidates than 3 x 3 cells of side radius.
/// `grid` is reused between calls to avoid reallocation.
/// With sorted = false each particle's neighbours come in cell order (a little faster).
void build_neighbour_list(const std::vector<Vec>& x, Real radius, NeighbourList& out, CellGrid& grid,
                          bool sorted = true);
void build_neighbour_list(const std::vector<Vec>& x, Real radius, NeighbourList& out);

/// A particle order that follows the cells (row by row), for memory locality:
/// reorder particles with ParticleSet::reorder(cell_order(x, radius / 2)). With the same cell side
/// as build_neighbour_list uses (radius / 2), the lists of unmoved particles come out already sorted.
std::vector<LocalIndex> cell_order(const std::vector<Vec>& x, Real cell_size);

}  // namespace mpsfsi
