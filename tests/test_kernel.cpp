// Unit tests of the weight function (seed 004 eq. 7) and the lattice constants n0, N0, lambda.
#include "core/kernel.hpp"
#include "core/neighbours.hpp"
#include "core/operators.hpp"
#include "core/geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace mpsfsi;

TEST(Kernel, WeightMatchesEquation7) {
  const Real re = 2.1;
  EXPECT_DOUBLE_EQ(weight(1.0, re), 1.1);
  EXPECT_NEAR(weight(2.0, re), 0.05, 1e-15);
  EXPECT_DOUBLE_EQ(weight(0.5, re), 3.2);
  EXPECT_EQ(weight(re, re), 0.0);      // vanishes at re
  EXPECT_EQ(weight(2.2, re), 0.0);     // zero outside
  EXPECT_EQ(weight(0.0, re), 0.0);     // a particle is not its own neighbour
  EXPECT_GT(weight(1e-3, re), 1000.0); // singular towards r = 0
}

TEST(Kernel, LatticeConstantsRe21) {
  const Real dp = 0.01;
  const auto c = lattice_constants(dp, 2.1 * dp);
  EXPECT_EQ(c.n_neighbours, 12);
  // 4 at dp, 4 at sqrt(2) dp, 4 at 2 dp.
  const Real n0 = 4 * (2.1 - 1) + 4 * (2.1 / std::sqrt(2.0) - 1) + 4 * (2.1 / 2 - 1);
  EXPECT_NEAR(c.n0, n0, 1e-12);
  const Real lambda = (4 * 1.0 * 1.1 + 4 * 2.0 * (2.1 / std::sqrt(2.0) - 1) + 4 * 4.0 * 0.05) * dp * dp / n0;
  EXPECT_NEAR(c.lambda, lambda, 1e-16);
}

TEST(Kernel, LatticeConstantsRe40) {
  const auto c = lattice_constants(1.0, 4.0);
  EXPECT_EQ(c.n_neighbours, 44);
  EXPECT_GT(c.n0, 0.0);
}

// The constants of a real interior particle of a filled lattice equal lattice_constants().
TEST(Kernel, InteriorParticleMatchesLatticeConstants) {
  const Real dp = 0.02;
  for (const Real factor : {2.1, 4.0}) {
    const auto c = lattice_constants(dp, factor * dp);
    const auto x = fill_rectangle(Vec(0, 0), Vec(0.4, 0.4), dp);
    NeighbourList nl;
    build_neighbour_list(x, factor * dp, nl);
    std::vector<Real> n;
    std::vector<int> count;
    number_density(x, nl, factor * dp, n);
    neighbour_count(x, nl, factor * dp, count);
    const std::size_t centre = 10 * 20 + 10;  // particle (10, 10) of a 20 x 20 lattice
    EXPECT_NEAR(n[centre], c.n0, 1e-12);
    EXPECT_EQ(count[centre], c.n_neighbours);
  }
}
