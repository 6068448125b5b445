// Unit tests of the weight function (seed 004 eq. 7) and the lattice constants n0, N0, lambda (eq. 8,
// 13) of the square lattice (2D build) and the simple cubic lattice (3D build): exact shell sums and a
// direct sum over the lattice written out independently of core/kernel.cpp.
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

#if MPSFSI_DIM == 2
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
#else
// Simple cubic lattice, re = 2.1 dp: the shells r^2 = 1, 2, 3, 4 (dp^2) hold 6, 12, 8, 6 points.
TEST(Kernel, LatticeConstantsRe21) {
  const Real dp = 0.01;
  const auto c = lattice_constants(dp, 2.1 * dp);
  EXPECT_EQ(c.n_neighbours, 32);
  const Real w1 = 2.1 - 1, w2 = 2.1 / std::sqrt(2.0) - 1, w3 = 2.1 / std::sqrt(3.0) - 1, w4 = 2.1 / 2 - 1;
  const Real n0 = 6 * w1 + 12 * w2 + 8 * w3 + 6 * w4;  // eq. 8
  EXPECT_NEAR(c.n0, n0, 1e-12);
  const Real lambda = (6 * 1.0 * w1 + 12 * 2.0 * w2 + 8 * 3.0 * w3 + 6 * 4.0 * w4) * dp * dp / n0;  // eq. 13
  EXPECT_NEAR(c.lambda, lambda, 1e-16);
}

// re = 4 dp: 250 lattice points with 0 < i^2 + j^2 + k^2 < 16.
TEST(Kernel, LatticeConstantsRe40) {
  const auto c = lattice_constants(1.0, 4.0);
  EXPECT_EQ(c.n_neighbours, 250);
  EXPECT_GT(c.n0, 0.0);
}
#endif

// The constants against a direct sum over the lattice points (nested loops written out per dimension).
TEST(Kernel, LatticeConstantsMatchDirectSum) {
  for (const Real factor : {2.1, 3.1, 4.0}) {
    const Real dp = 0.5, re = factor * dp;
    const auto c = lattice_constants(dp, re);
    const int m = 5;
    Real sw = 0, sr2w = 0;
    int count = 0;
    const int kmax = dim == 3 ? m : 0;
    for (int i = -m; i <= m; ++i)
      for (int j = -m; j <= m; ++j)
        for (int k = -kmax; k <= kmax; ++k) {
          const Real r = dp * std::sqrt(Real(i * i + j * j + k * k));
          const Real w = weight(r, re);
          if (w <= 0) continue;
          sw += w;
          sr2w += r * r * w;
          ++count;
        }
    EXPECT_EQ(c.n_neighbours, count) << factor;
    EXPECT_NEAR(c.n0, sw, 1e-12 * sw) << factor;
    EXPECT_NEAR(c.lambda, sr2w / sw, 1e-12 * c.lambda) << factor;
  }
}

// The constants of a real interior particle of a filled lattice equal lattice_constants().
TEST(Kernel, InteriorParticleMatchesLatticeConstants) {
  const Real dp = 0.02;
  for (const Real factor : {2.1, 4.0}) {
    const auto c = lattice_constants(dp, factor * dp);
    const auto x = fill_rectangle(Vec::Zero(), Vec::Constant(0.4), dp);  // 20^d points
    NeighbourList nl;
    build_neighbour_list(x, factor * dp, nl);
    std::vector<Real> n;
    std::vector<int> count;
    number_density(x, nl, factor * dp, n);
    neighbour_count(x, nl, factor * dp, count);
    std::size_t centre = 0;  // particle (10, 10[, 10]) of the 20^d lattice (x fastest)
    for (int a = dim - 1; a >= 0; --a) centre = 20 * centre + 10;
    EXPECT_NEAR(n[centre], c.n0, 1e-12);
    EXPECT_EQ(count[centre], c.n_neighbours);
  }
}

// Wendland's C2 kernel (the projection's density): w = (1 - q)^4 (1 + 4 q), 1 at r -> 0, 0 from re on, w'
// against central differences; the lattice sums: for the MPS weight n0 of lattice_constants and c = n0 + N0
// (-w' r = re / r = w + 1), for Wendland's against the direct sum.
TEST(Kernel, WendlandAndLatticeSums) {
  const Real re = 0.021;
  EXPECT_NEAR(kernel_at(DensityKernel::wendland, 1e-9 * re, re).w, 1.0, 1e-7);
  EXPECT_EQ(kernel_at(DensityKernel::wendland, re, re).w, 0.0);
  EXPECT_EQ(kernel_at(DensityKernel::wendland, 1.5 * re, re).dw, 0.0);
  for (const Real q : {0.1, 0.37, 0.5, 0.81, 0.99}) {
    const Real r = q * re, h = 1e-7 * re;
    EXPECT_NEAR(kernel_at(DensityKernel::wendland, r, re).w, std::pow(1 - q, 4) * (1 + 4 * q), 1e-15) << q;
    for (const DensityKernel k : {DensityKernel::mps, DensityKernel::wendland}) {
      const Real fd = (kernel_at(k, r + h, re).w - kernel_at(k, r - h, re).w) / (2 * h);
      EXPECT_NEAR(kernel_at(k, r, re).dw, fd, 1e-6 * std::abs(fd) + 1e-9 / re) << q;
    }
  }
  const Real dp = 0.01;
  for (const Real factor : {2.1, 4.0}) {
    const LatticeConstants c = lattice_constants(dp, factor * dp);
    const KernelSums mps = lattice_sums(DensityKernel::mps, dp, factor * dp);
    EXPECT_NEAR(mps.n0, c.n0, 1e-12 * c.n0);
    EXPECT_NEAR(mps.c, c.n0 + c.n_neighbours, 1e-12 * mps.c);
    const KernelSums w = lattice_sums(DensityKernel::wendland, dp, factor * dp);
    Real n0 = 0, sum_c = 0;
    const int m = 5, kmax = dim == 3 ? m : 0;
    for (int i = -m; i <= m; ++i)
      for (int j = -m; j <= m; ++j)
        for (int k = -kmax; k <= kmax; ++k) {
          const Real r = dp * std::sqrt(Real(i * i + j * j + k * k)), q = r / (factor * dp);
          if (r == 0 || q >= 1) continue;
          n0 += std::pow(1 - q, 4) * (1 + 4 * q);
          sum_c += 20 * q * q * std::pow(1 - q, 3);  // -w'(r) r
        }
    EXPECT_NEAR(w.n0, n0, 1e-12 * n0) << factor;
    EXPECT_NEAR(w.c, sum_c, 1e-12 * sum_c) << factor;
  }
}
