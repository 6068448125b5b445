// O(N) cell-linked neighbour search in MPSFSI_DIM dimensions (counting sort into cells, then a stencil
// of (2 reach + 1)^d cells scanned row by row: the cells of a row along axis 0 are contiguous).
#include "core/neighbours.hpp"

#include "core/buffers.hpp"
#include "core/kernel.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace mpsfsi {

void CellGrid::build(const std::vector<Vec>& x, const Real cell_size, const std::vector<std::uint8_t>* include) {
  if (!(cell_size > 0)) throw std::invalid_argument("CellGrid: cell size must be positive");
  cell_size_ = cell_size;
  const std::size_t n = x.size();
  assert(!include || include->size() >= n);
  const auto binned = [&](const std::size_t i) { return !include || (*include)[i] != 0; };
  // The grid spans the binned points alone (the others' cells are clamped to it, cell_of): points left out far
  // from the ones binned (walls far from the water) neither widen it nor fill it with empty cells.
  Vec lo = Vec::Constant(std::numeric_limits<Real>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    if (!x[i].allFinite()) throw std::runtime_error("CellGrid: a particle position is not finite");
    if (!binned(i)) continue;
    lo = lo.cwiseMin(x[i]);
    hi = hi.cwiseMax(x[i]);
  }
  if (!(lo.array() <= hi.array()).all()) lo = hi = n > 0 ? x[0] : Vec::Zero();  // nothing binned: one cell
  origin_ = lo;
  std::size_t n_total = 1;
  for (int a = 0; a < dim; ++a) {
    const double extent = (hi[a] - lo[a]) / cell_size;
    if (extent > 1e8) throw std::runtime_error("CellGrid: particles spread over too many cells");
    n_cells_[a] = static_cast<int>(std::floor(extent)) + 1;
    n_total *= static_cast<std::size_t>(n_cells_[a]);
  }
  // 3D: cell indices are stored as LocalIndex, and 1e8 cells per axis would overflow the count (2D keeps
  // its behaviour: there the allocation fails first).
  if (dim > 2 && n_cells_.cast<double>().prod() > 2e9)
    throw std::runtime_error("CellGrid: particles spread over too many cells");
  cell_start_.assign(n_total + 1, 0);
  resize_with_headroom(cell_of_point_, n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto ci = static_cast<LocalIndex>(cell_index(cell_of(x[i])));
    cell_of_point_[i] = ci;
    if (binned(i)) ++cell_start_[static_cast<std::size_t>(ci) + 1];
  }
  for (std::size_t c = 0; c < n_total; ++c) cell_start_[c + 1] += cell_start_[c];
  const std::size_t n_binned = cell_start_[n_total];
  resize_with_headroom(sorted_, n_binned);
  // Stable counting sort: points keep increasing index order inside a cell.
  std::vector<std::size_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    if (binned(i)) sorted_[fill[static_cast<std::size_t>(cell_of_point_[i])]++] = static_cast<LocalIndex>(i);
  resize_with_headroom(sorted_x_, n_binned);
  for (std::size_t k = 0; k < n_binned; ++k) sorted_x_[k] = x[static_cast<std::size_t>(sorted_[k])];
}

CellGrid::Cell CellGrid::cell_of(const Vec& x) const {
  Cell c;
  for (int a = 0; a < dim; ++a) {
    // Clamped before the conversion: a point far outside the grid (not binned) has no representable cell.
    const Real k = std::clamp((x[a] - origin_[a]) / cell_size_, Real(0), Real(n_cells_[a] - 1));
    c[a] = static_cast<int>(k);
  }
  return c;
}

namespace {
/// Insertion sort of a[0 .. m): the lists are short and, for particles kept in cell order, nearly
/// sorted. Unguarded inner loop (as in std::sort's final pass): a value smaller than a[0] is moved to the
/// front directly, so the scan for the others needs no bounds test. Kept out of line: the speed of the
/// short inner loop then does not depend on the stencil loop it would be inlined into.
__attribute__((noinline)) void sort_short_list(LocalIndex* a, const std::size_t m) {
  for (std::size_t p = 1; p < m; ++p) {
    const LocalIndex v = a[p];
    if (!(a[p - 1] > v)) continue;  // already in place (the usual case in cell order)
    if (v < a[0]) {
      std::move_backward(a, a + p, a + p + 1);
      a[0] = v;
      continue;
    }
    LocalIndex* q = a + p;  // a[0] <= v < a[p - 1]
    for (; q[-1] > v; --q) *q = q[-1];
    *q = v;
  }
}

/// The rows of a neighbour list: row q holds the neighbours of point particle_of(q) among all points x,
/// found in the (2 reach + 1)^d cells around it of `grid` (built over x with cells of side radius / reach).
/// Rows q with has_row(q) false stay empty. With `support_only`, the pairs in_support of radius (core/kernel.hpp),
/// by the same arithmetic. take_row(i, n_pairs) may write point i's row itself (appending at n_pairs, which it
/// advances) and return true; otherwise the row is searched. With `two_blocks`, a searched row's neighbours
/// j >= second_block are moved after the others (a stable partition), and each part is sorted on its own.
template <bool support_only, bool two_blocks = false, class ParticleOf, class HasRow, class TakeRow>
void fill_rows(const std::vector<Vec>& x, const std::size_t n, ParticleOf&& particle_of, HasRow&& has_row,
               TakeRow&& take_row, const Real radius, const int reach, NeighbourList& out, const CellGrid& grid,
               const bool sorted_lists, const std::size_t second_block = 0) {
  thread_local std::vector<LocalIndex> late;  // a row's neighbours of the second block
  thread_local std::vector<std::size_t> late_before;  // the grid's points of the second block before each one
  const Real r2 = radius * radius;
  const Real support2 = radius * radius * (1.0 - support_margin);
  out.radius = radius;
  out.support_only = support_only;
  out.offset.resize(n + 1);
  // The index keeps last step's size (the list length changes little from step to step) and grows
  // below when needed; it is not trimmed (n_pairs() = offset.back()).
  out.offset[0] = 0;
  const auto& sorted = grid.sorted();
  const auto& xs = grid.sorted_positions();
  if constexpr (two_blocks) {
    late_before.resize(sorted.size() + 1);
    late_before[0] = 0;
    for (std::size_t k = 0; k < sorted.size(); ++k)
      late_before[k + 1] = late_before[k] + (static_cast<std::size_t>(sorted[k]) >= second_block);
  }
  // Grid size in locals: the list writes below are ints and could alias the grid's members.
  CellGrid::Cell n_cells;
  for (int a = 0; a < dim; ++a) n_cells[a] = grid.n_cells(a);
  std::size_t n_pairs = 0;
  for (std::size_t q = 0; q < n; ++q) {
    if (!has_row(q)) {
      out.offset[q + 1] = n_pairs;
      continue;
    }
    const std::size_t i = particle_of(q);
    if (take_row(i, n_pairs)) {
      out.offset[q + 1] = n_pairs;
      continue;
    }
    const Vec xi = x[i];
    const CellGrid::Cell c = grid.cell_of_point(i);
    // Stencil bounds per axis, clipped to the grid.
    CellGrid::Cell lo, hi;
    for (int a = 0; a < dim; ++a) {
      lo[a] = std::max(c[a] - reach, 0);
      hi[a] = std::min(c[a] + reach, n_cells[a] - 1);
    }
    const auto row_length = static_cast<std::size_t>(hi[0] - lo[0] + 1);
    // Rows of the stencil: every cell coordinate of axes 1 .. d-1 (an odometer, axis 1 fastest); the
    // cells lo[0] .. hi[0] of a row are contiguous in the sorted arrays.
    CellGrid::Cell row = lo;
    bool has_late = false;  // a candidate of the second block in the row's cells
    for (;;) {
      std::size_t cell = static_cast<std::size_t>(row[dim - 1]);  // linear index of the row's first cell
      for (int a = dim - 2; a >= 0; --a) cell = cell * static_cast<std::size_t>(n_cells[a]) + static_cast<std::size_t>(row[a]);
      const std::size_t first = grid.cell_start(cell);
      const std::size_t last = grid.cell_start(cell + row_length);
      if (n_pairs + (last - first) > out.index.size()) out.index.resize(2 * (n_pairs + (last - first)) + 1024);
      if constexpr (two_blocks) has_late |= late_before[last] != late_before[first];
      LocalIndex* dst = out.index.data() + n_pairs;
      // Branch-free append: write always, advance only for a neighbour. The write comes after the distance's
      // loads (written before them, it can stall them: the list and the positions are different arrays, but
      // the loads wait for the store).
      for (std::size_t k = first; k < last; ++k) {
        if constexpr (support_only) {
          const Real d2 = (xs[k] - xi).squaredNorm();
          *dst = sorted[k];
          dst += (d2 > 0) & (d2 < support2);
        } else {
          Real d2 = (xs[k][0] - xi[0]) * (xs[k][0] - xi[0]);
          for (int a = 1; a < dim; ++a) d2 += (xs[k][a] - xi[a]) * (xs[k][a] - xi[a]);
          *dst = sorted[k];
          dst += (d2 < r2) & (static_cast<std::size_t>(sorted[k]) != i);
        }
      }
      n_pairs = static_cast<std::size_t>(dst - out.index.data());
      int a = 1;
      for (; a < dim; ++a) {
        if (++row[a] <= hi[a]) break;
        row[a] = lo[a];
      }
      if (a == dim) break;
    }
    out.offset[q + 1] = n_pairs;
    if (!sorted_lists) continue;
    LocalIndex* a = out.index.data() + out.offset[q];
    const std::size_t m = n_pairs - out.offset[q];
    if (two_blocks && has_late) {
      // A stable partition (the second block's neighbours after the others), then each part sorted.
      if (m > late.size()) late.resize(2 * m);
      std::size_t n_first = 0, n_late = 0;
      for (std::size_t k = 0; k < m; ++k) {
        const LocalIndex v = a[k];
        const bool second = static_cast<std::size_t>(v) >= second_block;
        a[n_first] = v;
        late[n_late] = v;
        n_first += !second;
        n_late += second;
      }
      std::copy(late.data(), late.data() + n_late, a + n_first);
      sort_short_list(a, n_first);
      sort_short_list(a + n_first, n_late);
    } else {
      sort_short_list(a, m);
    }
  }
}

}  // namespace

void build_neighbour_list(const std::vector<Vec>& x, const Real radius, NeighbourList& out, CellGrid& grid,
                          const bool sorted_lists, const std::optional<std::size_t> n_rows) {
  constexpr int reach = 2;  // cells of side radius / reach; stencil of (2 reach + 1)^d cells
  assert(!n_rows || *n_rows <= x.size());
  grid.build(x, radius / reach);
  fill_rows<false>(x, n_rows.value_or(x.size()), [](const std::size_t q) { return q; }, [](std::size_t) { return true; },
                   [](std::size_t, std::size_t&) { return false; }, radius, reach, out, grid, sorted_lists);
}

void build_neighbour_list_masked(const std::vector<Vec>& x, const Real radius, NeighbourList& out, CellGrid& grid,
                                 const std::size_t n_rows, const std::vector<std::uint8_t>& rows,
                                 const std::vector<std::uint8_t>& candidates, const Real cell_size,
                                 const bool support_only, const WiderRows* wider, const std::size_t second_block) {
  if (n_rows > x.size() || rows.size() < n_rows || candidates.size() < x.size())
    throw std::logic_error("build_neighbour_list_masked: masks shorter than the points");
  if (!(cell_size > 0 && cell_size <= radius))
    throw std::logic_error("build_neighbour_list_masked: the cell side must be in (0, radius]");
  if (wider && (!support_only || &wider->list == &out || wider->rows.size() < wider->list.n_particles() ||
                !(wider->list.radius >= radius)))
    throw std::logic_error("build_neighbour_list_masked: rows from a wider list need support_only, another list at "
                           "a radius of at least this one, and a mask of its rows");
  const int reach = static_cast<int>(std::ceil(radius / cell_size));  // the cells that cover the radius
  grid.build(x, cell_size, &candidates);
  const auto particle_of = [](const std::size_t q) { return q; };
  const auto has_row = [&](const std::size_t q) { return rows[q] != 0; };
  // Rows long enough (a stencil of 5^3 cells or more) that the sort's moves cost more than the partition.
  int n_stencil = 1;
  for (int a = 0; a < dim; ++a) n_stencil *= 2 * reach + 1;
  const bool two_blocks = second_block < x.size() && n_stencil >= 125;
  const auto fill = [&](auto support, auto&& take_row) {
    constexpr bool pairs_in_support = decltype(support)::value;
    if (two_blocks)
      fill_rows<pairs_in_support, true>(x, n_rows, particle_of, has_row, take_row, radius, reach, out, grid, true,
                                        second_block);
    else
      fill_rows<pairs_in_support>(x, n_rows, particle_of, has_row, take_row, radius, reach, out, grid, true);
  };
  if (!support_only) {
    fill(std::false_type{}, [](std::size_t, std::size_t&) { return false; });
    return;
  }
  const Real support2 = radius * radius * (1.0 - support_margin);  // in_support's arithmetic
  const auto from_wider = [&](const std::size_t i, std::size_t& n_pairs) {
    if (!wider || i >= wider->list.n_particles() || wider->rows[i] == 0) return false;
    const NeighbourList& w = wider->list;
    if (n_pairs + w.count(i) > out.index.size()) out.index.resize(2 * (n_pairs + w.count(i)) + 1024);
    LocalIndex* dst = out.index.data() + n_pairs;
    const Vec xi = x[i];
    for (std::size_t k = w.begin(i); k < w.end(i); ++k) {
      const auto j = static_cast<std::size_t>(w.index[k]);
      const Real d2 = (x[j] - xi).squaredNorm();
      *dst = w.index[k];
      dst += (candidates[j] != 0) & (d2 > 0) & (d2 < support2);
    }
    n_pairs = static_cast<std::size_t>(dst - out.index.data());
    return true;
  };
  fill(std::true_type{}, from_wider);
}

void build_neighbour_list_of(const std::vector<Vec>& x, const std::vector<LocalIndex>& rows, const Real radius,
                             NeighbourList& out, CellGrid& grid) {
  constexpr int reach = 1;  // few rows: cells of side radius, a 3^d stencil, no finer grid to build
  grid.build(x, radius);
  fill_rows<false>(x, rows.size(), [&](const std::size_t q) { return static_cast<std::size_t>(rows[q]); },
                   [](std::size_t) { return true; }, [](std::size_t, std::size_t&) { return false; }, radius, reach,
                   out, grid, false);
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
