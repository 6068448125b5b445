// Unit tests of the cell-linked neighbour search: identical neighbour sets to brute force, in the 2D
// and the 3D build (random points, lattices, clusters, points on a line, rows and candidates masked), and the
// cell numbering.
#include "core/geometry.hpp"
#include "core/kernel.hpp"
#include "core/neighbours.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

using namespace mpsfsi;

namespace {
std::vector<std::vector<LocalIndex>> brute_force(const std::vector<Vec>& x, const Real radius) {
  std::vector<std::vector<LocalIndex>> nb(x.size());
  for (std::size_t i = 0; i < x.size(); ++i)
    for (std::size_t j = 0; j < x.size(); ++j)
      if (i != j && (x[j] - x[i]).squaredNorm() < radius * radius) nb[i].push_back(static_cast<LocalIndex>(j));
  return nb;
}

/// n points uniform in the unit square or cube.
std::vector<Vec> random_points(const std::size_t n, const unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Real> u(0, 1);
  std::vector<Vec> x(n);
  for (auto& p : x)
    for (int a = 0; a < dim; ++a) p[a] = u(rng);
  return x;
}

void expect_same_as_brute_force(const std::vector<Vec>& x, const Real radius) {
  NeighbourList nl;
  build_neighbour_list(x, radius, nl);
  const auto ref = brute_force(x, radius);
  ASSERT_EQ(nl.n_particles(), x.size());
  std::size_t n_pairs = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    std::vector<LocalIndex> got(nl.index.begin() + static_cast<long>(nl.begin(i)),
                                nl.index.begin() + static_cast<long>(nl.end(i)));
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, ref[i]) << "particle " << i;
    n_pairs += ref[i].size();
  }
  EXPECT_EQ(nl.n_pairs(), n_pairs);
  EXPECT_GT(n_pairs, 0u);
}
}  // namespace

TEST(Neighbours, RandomPointsMatchBruteForce) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<Real> u(-0.5, 1.5);
  std::vector<Vec> x(2000);
#if MPSFSI_DIM == 2
  for (auto& p : x) p = Vec(u(rng), 0.3 * u(rng));
#else
  for (auto& p : x) p = Vec(u(rng), 0.3 * u(rng), 0.5 * u(rng));
#endif
  for (const Real radius : {0.01, 0.05, 0.13, 0.5}) expect_same_as_brute_force(x, radius);
}

// The neighbours of a few points (build_neighbour_list_of): row q holds those of point rows[q], as brute force.
TEST(Neighbours, ListOfSelectedPointsMatchesBruteForce) {
  std::vector<Vec> x = random_points(1500, 7);
  const std::vector<LocalIndex> rows = {0, 17, 17, 400, 1499, 3};
  for (const Real radius : {0.02, 0.1, 0.3}) {
    NeighbourList nl;
    CellGrid grid;
    build_neighbour_list_of(x, rows, radius, nl, grid);
    const auto ref = brute_force(x, radius);
    ASSERT_EQ(nl.n_particles(), rows.size());
    for (std::size_t q = 0; q < rows.size(); ++q) {
      std::vector<LocalIndex> got(nl.index.begin() + static_cast<long>(nl.begin(q)),
                                  nl.index.begin() + static_cast<long>(nl.end(q)));
      std::sort(got.begin(), got.end());
      EXPECT_EQ(got, ref[static_cast<std::size_t>(rows[q])]) << "row " << q << ", radius " << radius;
    }
  }
}

// Rows of some points only, neighbours among some points only, cells of another side than the radius, the
// pairs of the operators' support, and the points from an index on gathered as a block of their own
// (build_neighbour_list_masked): as brute force, each row in increasing order.
TEST(Neighbours, MaskedListMatchesBruteForce) {
  std::vector<Vec> x = random_points(1500, 11);
  x[6] = x[3];  // coincident: neighbours by distance, outside the support
  std::vector<std::uint8_t> rows(x.size()), candidates(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    rows[i] = i % 3 != 1;
    candidates[i] = i % 7 != 2;
  }
  const std::size_t n_rows = 1200;  // the last points are candidates without rows (ghosts)
  const std::size_t no_block = std::numeric_limits<std::size_t>::max();  // no second block
  std::size_t n_checked = 0;
  for (const Real radius : {0.03, 0.1})
    for (const Real cell : {radius, radius / 2, radius / 2.7, radius / 6})  // radius / 6: 13^2 stencil cells
      for (const bool support : {false, true})
      for (const std::size_t second_block : {no_block, std::size_t{1000}, std::size_t{0}}) {
        NeighbourList nl;
        CellGrid grid;
        build_neighbour_list_masked(x, radius, nl, grid, n_rows, rows, candidates, cell, support, nullptr, second_block);
        ASSERT_EQ(nl.n_particles(), n_rows);
        EXPECT_EQ(nl.support_only, support);
        for (std::size_t i = 0; i < n_rows; ++i) {
          std::vector<LocalIndex> ref;
          for (std::size_t j = 0; rows[i] && j < x.size(); ++j) {
            const Real r2 = (x[j] - x[i]).squaredNorm();
            if (i != j && candidates[j] && (support ? in_support(r2, radius) : r2 < radius * radius))
              ref.push_back(static_cast<LocalIndex>(j));
          }
          const std::vector<LocalIndex> got(nl.index.begin() + static_cast<long>(nl.begin(i)),
                                            nl.index.begin() + static_cast<long>(nl.end(i)));
          ASSERT_EQ(got, ref) << "row " << i << ", radius " << radius << ", cell " << cell << ", support " << support
                              << ", second block from " << second_block;
          n_checked += ref.size();
        }
        const auto row_3 = nl.index.begin() + static_cast<long>(nl.begin(3));
        const auto row_3_end = nl.index.begin() + static_cast<long>(nl.end(3));
        const bool coincident = std::find(row_3, row_3_end, 6) != row_3_end;
        EXPECT_EQ(coincident, !support);
      }
  EXPECT_GT(n_checked, 1000u);
  NeighbourList nl;
  CellGrid grid;
  EXPECT_THROW(build_neighbour_list_masked(x, 0.1, nl, grid, n_rows, rows, candidates, 0.2), std::logic_error);
  EXPECT_THROW(build_neighbour_list_masked(x, 0.1, nl, grid, x.size() + 1, rows, candidates, 0.05), std::logic_error);
}

// Rows taken from a wider list (the fluid's near rows from its wide rows) are the rows a search gives, when the
// wider radius covers the narrower one plus the points' moves since the wider list was built.
TEST(Neighbours, RowsFromAWiderListMatchTheSearch) {
  std::vector<Vec> x = random_points(1500, 5);
  std::mt19937 rng(5);
  std::uniform_real_distribution<Real> move(-0.004, 0.004);
  std::vector<std::uint8_t> all(x.size(), 1), wide_rows(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) wide_rows[i] = i % 4 != 0;
  const Real radius = 0.05;
  NeighbourList wide, from_wide, searched;
  CellGrid grid;
  build_neighbour_list_masked(x, 2 * radius, wide, grid, x.size(), wide_rows, all, radius / 2);
  for (auto& p : x)
    for (int a = 0; a < dim; ++a) p[a] += move(rng);  // |move| < 0.004 sqrt(dim) < radius / 2 per point
  const WiderRows wider{wide, wide_rows};
  build_neighbour_list_masked(x, radius, from_wide, grid, x.size(), all, all, radius / 2, true, &wider);
  build_neighbour_list_masked(x, radius, searched, grid, x.size(), all, all, radius / 2, true);
  EXPECT_EQ(from_wide.offset, searched.offset);
  EXPECT_TRUE(std::equal(searched.index.begin(), searched.index.begin() + static_cast<long>(searched.n_pairs()),
                         from_wide.index.begin()));
  EXPECT_GT(searched.n_pairs(), 1000u);
  // With a second block, rows taken from the wider list and rows searched alike.
  NeighbourList two_blocks;
  build_neighbour_list_masked(x, radius, two_blocks, grid, x.size(), all, all, radius / 6, true, &wider, 700);
  EXPECT_EQ(two_blocks.offset, searched.offset);
  EXPECT_TRUE(std::equal(searched.index.begin(), searched.index.begin() + static_cast<long>(searched.n_pairs()),
                         two_blocks.index.begin()));
  // The rows are the wider list's: one emptied there (its entries pointing at itself) comes out empty.
  NeighbourList poisoned = wide;
  const std::size_t r = 1;
  ASSERT_TRUE(wide_rows[r] && searched.count(r) > 0);
  for (std::size_t k = poisoned.begin(r); k < poisoned.end(r); ++k) poisoned.index[k] = static_cast<LocalIndex>(r);
  const WiderRows poisoned_rows{poisoned, wide_rows};
  build_neighbour_list_masked(x, radius, from_wide, grid, x.size(), all, all, radius / 2, true, &poisoned_rows);
  EXPECT_EQ(from_wide.count(r), 0u);
  EXPECT_EQ(from_wide.count(r + 1), searched.count(r + 1));
  // A wider list must be another list, of a radius at least this one, and only for the support's pairs.
  EXPECT_THROW(build_neighbour_list_masked(x, 3 * radius, from_wide, grid, x.size(), all, all, radius, true, &wider),
               std::logic_error);
  EXPECT_THROW(build_neighbour_list_masked(x, radius, from_wide, grid, x.size(), all, all, radius / 2, false, &wider),
               std::logic_error);
}

TEST(Neighbours, LatticeMatchesBruteForce) {
  const Real dp = 0.01;
#if MPSFSI_DIM == 2
  const auto x = fill_rectangle(Vec(0, 0), Vec(0.45, 0.4), dp);  // 45 x 40 = 1800 points
#else
  const auto x = fill_rectangle(Vec::Zero(), Vec(0.15, 0.12, 0.1), dp);  // 15 x 12 x 10 = 1800 points
#endif
  ASSERT_EQ(x.size(), 1800u);
  // Radii on lattice distances exercise the strict "< radius" test.
  for (const Real factor : {1.0, 2.0, 2.1, 4.0}) expect_same_as_brute_force(x, factor * dp);
}

TEST(Neighbours, ClusteredAndDegeneratePoints) {
#if MPSFSI_DIM == 2
  std::vector<Vec> x = {Vec(0, 0), Vec(0, 0), Vec(1e-9, 0), Vec(5, 5), Vec(5, 5.05)};
#else
  std::vector<Vec> x = {Vec(0, 0, 0), Vec(0, 0, 0), Vec(1e-9, 0, 0), Vec(5, 5, 5), Vec(5, 5.05, 5), Vec(5, 5, 4.95)};
#endif
  expect_same_as_brute_force(x, 0.1);
  // Points on a line along every axis (a grid one cell wide in the other axes).
  for (int axis = 0; axis < dim; ++axis) {
    std::vector<Vec> line(300, Vec::Zero());
    for (std::size_t i = 0; i < line.size(); ++i) line[i][axis] = 0.003 * static_cast<Real>(i);
    expect_same_as_brute_force(line, 0.0071);
  }
}

TEST(Neighbours, EmptyAndNonFinite) {
  NeighbourList nl;
  build_neighbour_list({}, 0.1, nl);
  EXPECT_EQ(nl.n_particles(), 0u);
  std::vector<Vec> bad = {Vec::Zero(), Vec::Zero()};
  bad[1][0] = std::nan("");
  EXPECT_THROW(build_neighbour_list(bad, 0.1, nl), std::runtime_error);
}

// cell_of_point decodes the linear cell index (axis 0 fastest) into the coordinates cell_of gives.
TEST(Neighbours, CellIndexRoundTrip) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<Real> u(0, 1);
  std::vector<Vec> x(500);
  for (auto& p : x)
    for (int a = 0; a < dim; ++a) p[a] = (a + 1) * u(rng);
  CellGrid grid;
  grid.build(x, 0.07);
  std::size_t n_total = 1;
  for (int a = 0; a < dim; ++a) n_total *= static_cast<std::size_t>(grid.n_cells(a));
  for (std::size_t i = 0; i < x.size(); ++i) {
    const CellGrid::Cell c = grid.cell_of_point(i);
    ASSERT_EQ(c, grid.cell_of(x[i]));
    const std::size_t k = grid.cell_index(c);
    ASSERT_LT(k, n_total);
    // Point i sits in the sorted range of its cell.
    bool found = false;
    for (std::size_t q = grid.cell_start(k); q < grid.cell_start(k + 1); ++q) found = found || grid.sorted()[q] == static_cast<LocalIndex>(i);
    ASSERT_TRUE(found) << i;
  }
  CellGrid::Cell c = CellGrid::Cell::Zero();
  c[0] = 1;
  EXPECT_EQ(grid.cell_index(c), 1u);
  c[0] = 0;
  c[dim - 1] = 1;
  EXPECT_EQ(grid.cell_index(c), n_total / static_cast<std::size_t>(grid.n_cells(dim - 1)));
}

TEST(Neighbours, CellOrderIsAPermutation) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<Real> u(0, 1);
  std::vector<Vec> x(1000);
#if MPSFSI_DIM == 2
  for (auto& p : x) p = Vec(u(rng), u(rng));
#else
  for (auto& p : x) p = Vec(u(rng), u(rng), u(rng));
#endif
  auto order = cell_order(x, 0.1);
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < order.size(); ++i) ASSERT_EQ(order[i], static_cast<LocalIndex>(i));
}
