// O(N) cell-linked neighbour search in MPSFSI_DIM dimensions. Particles are binned into square (2D) or
// cubic (3D) cells with a counting sort; each particle's neighbours (all j != i with |x_j - x_i| <
// radius) are then found in the (2 reach + 1)^d surrounding cells and stored in one compressed (CSR)
// list, rebuilt once per step. Cells are numbered with axis 0 fastest (row by row in 2D, then layer by
// layer in 3D), so the cells of one row of a stencil are contiguous in the sorted arrays.
#pragma once

#include "core/types.hpp"

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

namespace mpsfsi {

/// Neighbours of every particle in CSR form: the neighbours of i are
/// index[offset[i] .. offset[i+1]), in increasing order of j (or in cell order when built unsorted).
struct NeighbourList {
  Real radius = 0;
  /// Every pair lies inside the support of `radius` (in_support): set by lists filtered with it, so that the
  /// operators skip the test (core/operators.hpp for_each_pair).
  bool support_only = false;
  std::vector<std::size_t> offset;  ///< size n + 1
  std::vector<LocalIndex> index;

  std::size_t n_particles() const { return offset.empty() ? 0 : offset.size() - 1; }
  /// Pairs in the rows. `index` may be longer: builders keep its size between steps (no zero-filling of a
  /// list that grows again), so only the entries up to offset.back() belong to the rows.
  std::size_t n_pairs() const { return offset.empty() ? 0 : offset.back(); }
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
  /// Cell coordinates, one per axis.
  using Cell = IVec;

  /// Bin the points into cells of side `cell_size` (> 0); with `include`, only the points i with include[i] != 0
  /// (the others are in no cell, and cell_of_point() holds their cell all the same).
  void build(const std::vector<Vec>& x, Real cell_size, const std::vector<std::uint8_t>* include = nullptr);

  Real cell_size() const { return cell_size_; }
  int n_cells(const int axis) const { return n_cells_[axis]; }
  /// Cell coordinates of a point (clamped to the grid).
  Cell cell_of(const Vec& x) const;
  /// Linear cell index of cell coordinates: c_0 + n_0 (c_1 + n_1 (c_2 ...)), axis 0 fastest.
  std::size_t cell_index(const Cell& c) const {
    std::size_t k = static_cast<std::size_t>(c[dim - 1]);
    for (int a = dim - 2; a >= 0; --a) k = k * static_cast<std::size_t>(n_cells_[a]) + static_cast<std::size_t>(c[a]);
    return k;
  }
  /// Points in cell c: sorted()[cell_start(c) .. cell_start(c + 1)).
  std::size_t cell_start(const std::size_t c) const { return cell_start_[c]; }
  const std::vector<LocalIndex>& sorted() const { return sorted_; }
  /// Positions in the order of sorted() (contiguous per cell, for fast scanning).
  const std::vector<Vec>& sorted_positions() const { return sorted_x_; }
  /// Cell coordinates of point i as binned by build().
  Cell cell_of_point(const std::size_t i) const {
    int k = static_cast<int>(cell_of_point_[i]);
    Cell c;
    for (int a = 0; a < dim - 1; ++a) {
      c[a] = k % n_cells_[a];
      k /= n_cells_[a];
    }
    c[dim - 1] = k;
    return c;
  }

 private:
  Real cell_size_ = 0;
  Vec origin_ = Vec::Zero();
  Cell n_cells_ = Cell::Zero();
  std::vector<std::size_t> cell_start_;
  std::vector<LocalIndex> sorted_;
  std::vector<LocalIndex> cell_of_point_;
  std::vector<Vec> sorted_x_;
};

/// Build the neighbour list of all points for `radius` (strictly closer than radius, j != i).
/// Cells of side radius / 2 and a stencil of 5^d cells: fewer candidates than 3^d cells of side radius.
/// `grid` is reused between calls to avoid reallocation.
/// With sorted = false each particle's neighbours come in cell order (a little faster).
/// With n_rows, only the first n_rows points get rows (e.g. the owned particles: the ghosts are neighbours
/// but need no list of their own); all points are candidates.
void build_neighbour_list(const std::vector<Vec>& x, Real radius, NeighbourList& out, CellGrid& grid,
                          bool sorted = true, std::optional<std::size_t> n_rows = std::nullopt);
void build_neighbour_list(const std::vector<Vec>& x, Real radius, NeighbourList& out);
/// Rows that a list of a larger radius holds already (build_neighbour_list_masked): its rows i with rows[i] != 0
/// (rows beyond its size are searched).
struct WiderRows {
  const NeighbourList& list;
  const std::vector<std::uint8_t>& rows;
};

/// As build_neighbour_list (sorted rows), with rows only for the points i < n_rows with rows[i] != 0 (the other
/// rows empty) and neighbours only among the points j with candidates[j] != 0: e.g. a wide list for the few
/// particles whose operator needs it, or the pairs of the particles that take part. Cells of side `cell_size`
/// (at most radius; a stencil of (2 ceil(radius / cell_size) + 1)^d cells): lists of several radii built with
/// one cell side come out nearly sorted for particles kept in the cell_order of that side. With `support_only`,
/// the pairs inside the operators' support of `radius` (in_support, core/kernel.hpp; out.support_only set), and
/// with `wider` (support_only only) the rows that it holds are its rows filtered instead of searched: the same
/// rows when the wider list's radius covers `radius` plus twice the largest displacement of any point since it
/// was built, which the caller checks; sorted rows if its rows are. With `second_block` < x.size(), the points
/// from that index on are a block of their own (the ghosts after the owned particles, each block in cell order): a
/// searched row puts its neighbours of that block after the others before it is sorted, so that sorting the
/// row does not move them one by one past the first block's (with a stencil of at least 125 cells, where the rows
/// are long; shorter ones are sorted as they are). The same rows as without it.
void build_neighbour_list_masked(const std::vector<Vec>& x, Real radius, NeighbourList& out, CellGrid& grid,
                                 std::size_t n_rows, const std::vector<std::uint8_t>& rows,
                                 const std::vector<std::uint8_t>& candidates, Real cell_size,
                                 bool support_only = false, const WiderRows* wider = nullptr,
                                 std::size_t second_block = std::numeric_limits<std::size_t>::max());
/// The neighbours of a few points only: row q of `out` lists every j != rows[q] with |x_j - x_rows[q]| <
/// radius, in cell order (e.g. the solid surface particles whose fluid load is summed). Cells of side radius.
void build_neighbour_list_of(const std::vector<Vec>& x, const std::vector<LocalIndex>& rows, Real radius,
                             NeighbourList& out, CellGrid& grid);

/// A particle order that follows the cells (axis 0 fastest: row by row), for memory locality:
/// reorder particles with ParticleSet::reorder(cell_order(x, radius / 2)). With the same cell side
/// as build_neighbour_list uses (radius / 2), the lists of unmoved particles come out already sorted.
std::vector<LocalIndex> cell_order(const std::vector<Vec>& x, Real cell_size);

}  // namespace mpsfsi
