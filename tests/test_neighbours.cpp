// Unit tests of the cell-linked neighbour search: identical neighbour sets to brute force.
#include "core/geometry.hpp"
#include "core/neighbours.hpp"

#include <gtest/gtest.h>

#include <algorithm>
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
  for (auto& p : x) p = Vec(u(rng), 0.3 * u(rng));
  for (const Real radius : {0.01, 0.05, 0.13, 0.5}) expect_same_as_brute_force(x, radius);
}

TEST(Neighbours, LatticeMatchesBruteForce) {
  const Real dp = 0.01;
  const auto x = fill_rectangle(Vec(0, 0), Vec(0.45, 0.4), dp);  // 45 x 40 = 1800 points
  ASSERT_EQ(x.size(), 1800u);
  // Radii on lattice distances exercise the strict "< radius" test.
  for (const Real factor : {1.0, 2.0, 2.1, 4.0}) expect_same_as_brute_force(x, factor * dp);
}

TEST(Neighbours, ClusteredAndDegeneratePoints) {
  std::vector<Vec> x = {Vec(0, 0), Vec(0, 0), Vec(1e-9, 0), Vec(5, 5), Vec(5, 5.05)};
  expect_same_as_brute_force(x, 0.1);
  std::vector<Vec> line(300);
  for (std::size_t i = 0; i < line.size(); ++i) line[i] = Vec(0.0, 0.003 * static_cast<Real>(i));
  expect_same_as_brute_force(line, 0.0071);
}

TEST(Neighbours, EmptyAndNonFinite) {
  NeighbourList nl;
  build_neighbour_list({}, 0.1, nl);
  EXPECT_EQ(nl.n_particles(), 0u);
  std::vector<Vec> bad = {Vec(0, 0), Vec(std::nan(""), 0)};
  EXPECT_THROW(build_neighbour_list(bad, 0.1, nl), std::runtime_error);
}

TEST(Neighbours, CellOrderIsAPermutation) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<Real> u(0, 1);
  std::vector<Vec> x(1000);
  for (auto& p : x) p = Vec(u(rng), u(rng));
  auto order = cell_order(x, 0.1);
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < order.size(); ++i) ASSERT_EQ(order[i], static_cast<LocalIndex>(i));
}
