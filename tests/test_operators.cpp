// Unit tests of the MPS operators (seed 004 eq. 8-15): exactness on linear/quadratic fields and
// convergence as dp halves, in the 2D build (a 1 x 0.5 block) and the 3D build (a 0.4 x 0.3 x 0.3 box;
// fields with a z part, lap of the quadratic 12 instead of 6).
#include "core/geometry.hpp"
#include "core/kernel.hpp"
#include "core/neighbours.hpp"
#include "core/operators.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using namespace mpsfsi;

namespace {

struct Block {
  Real dp;
  std::vector<Vec> x;
  std::vector<std::uint8_t> interior;  ///< full kernel support inside the block
};

#if MPSFSI_DIM == 2
const Vec block_size(1.0, 0.5);
#else
const Vec block_size(0.4, 0.3, 0.3);
#endif

/// A block [0, size] on the lattice, optionally jittered by up to `jitter` dp in each direction.
Block make_block(const Real dp, const Real support, const Real jitter = 0, const unsigned seed = 1,
                 const Vec& size = block_size) {
  Block b{dp, fill_rectangle(Vec::Zero(), size, dp), {}};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<Real> u(-jitter * dp, jitter * dp);
  if (jitter > 0)
#if MPSFSI_DIM == 2
    for (auto& p : b.x) p += Vec(u(rng), u(rng));
#else
    for (auto& p : b.x) p += Vec(u(rng), u(rng), u(rng));
#endif
  for (const auto& p : b.x) {
    bool inside = true;
    for (int a = 0; a < dim; ++a) inside = inside && p[a] > support + dp && p[a] < size[a] - support - dp;
    b.interior.push_back(inside ? 1 : 0);
  }
  return b;
}

std::vector<Real> field(const std::vector<Vec>& x, Real (*f)(const Vec&)) {
  std::vector<Real> phi(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) phi[i] = f(x[i]);
  return phi;
}

#if MPSFSI_DIM == 2
Real linear(const Vec& p) { return 3.0 - 2.0 * p[0] + 5.0 * p[1]; }
const Vec linear_grad(-2.0, 5.0);
Real quadratic(const Vec& p) { return 1.0 + p[0] * p[0] + 2.0 * p[1] * p[1] - p[0] * p[1]; }  // lap = 6
constexpr Real quadratic_lap = 6.0;
/// A linear vector field and its divergence.
Vec linear_v(const Vec& p) { return Vec(1.0 + 2.0 * p[0] + 0.5 * p[1], -3.0 * p[0] + 4.0 * p[1]); }
constexpr Real linear_v_div = 6.0;
Real smooth(const Vec& p) { return std::sin(3.0 * p[0]) * std::cos(2.0 * p[1]); }
Vec smooth_grad(const Vec& p) {
  return Vec(3.0 * std::cos(3.0 * p[0]) * std::cos(2.0 * p[1]), -2.0 * std::sin(3.0 * p[0]) * std::sin(2.0 * p[1]));
}
Real smooth_lap(const Vec& p) { return -13.0 * smooth(p); }
#else
Real linear(const Vec& p) { return 3.0 - 2.0 * p[0] + 5.0 * p[1] + 1.5 * p[2]; }
const Vec linear_grad(-2.0, 5.0, 1.5);
Real quadratic(const Vec& p) {  // lap = 2 + 4 + 6 = 12
  return 1.0 + p[0] * p[0] + 2.0 * p[1] * p[1] - p[0] * p[1] + 3.0 * p[2] * p[2] + p[1] * p[2];
}
constexpr Real quadratic_lap = 12.0;
Vec linear_v(const Vec& p) {
  return Vec(1.0 + 2.0 * p[0] + 0.5 * p[1] - p[2], -3.0 * p[0] + 4.0 * p[1] + p[2], 0.5 * p[0] + 3.0 * p[2]);
}
constexpr Real linear_v_div = 9.0;
Real smooth(const Vec& p) { return std::sin(3.0 * p[0]) * std::cos(2.0 * p[1]) * std::cos(p[2]); }
Vec smooth_grad(const Vec& p) {
  const Real s = std::sin(3.0 * p[0]), c = std::cos(3.0 * p[0]), cy = std::cos(2.0 * p[1]), sy = std::sin(2.0 * p[1]);
  return Vec(3.0 * c * cy * std::cos(p[2]), -2.0 * s * sy * std::cos(p[2]), -s * cy * std::sin(p[2]));
}
Real smooth_lap(const Vec& p) { return -14.0 * smooth(p); }
#endif

}  // namespace

// Eq. 14-15 reproduce the gradient of a linear field exactly at every particle, also at the free
// surface (edges and corners of the block) and on a disordered particle set.
TEST(Operators, CorrectedGradientExactForLinearFieldEverywhere) {
  const Real dp = 0.02, re = 2.1 * dp;
  for (const Real jitter : {0.0, 0.2}) {
    const auto b = make_block(dp, re, jitter);
    NeighbourList nl;
    build_neighbour_list(b.x, re, nl);
    std::vector<Vec> g;
    corrected_gradient(b.x, nl, re, field(b.x, linear), g);
    Real err = 0;
    for (const auto& gi : g) err = std::max(err, (gi - linear_grad).norm());
    EXPECT_LT(err, 1e-12) << "jitter " << jitter;
  }
}

// Eq. 9 without correction is exact for a linear field only where the support is full and symmetric.
TEST(Operators, GradientOfLinearFieldInInterior) {
  const Real dp = 0.02, re = 2.1 * dp;
  const auto c = lattice_constants(dp, re);
  const auto b = make_block(dp, re);
  NeighbourList nl;
  build_neighbour_list(b.x, re, nl);
  std::vector<Vec> g, gmin;
  gradient(b.x, nl, re, c.n0, field(b.x, linear), g);
  gradient_min(b.x, nl, re, c.n0, field(b.x, linear), gmin);
  for (std::size_t i = 0; i < b.x.size(); ++i) {
    if (!b.interior[i]) continue;
    EXPECT_LT((g[i] - linear_grad).norm(), 1e-10);
  }
  // The minimum-value variant of a constant field is zero, of a linear field it only adds a
  // repulsive (outward from the minimum) part: every pair term is >= 0 along r_ij.
  std::vector<Vec> g0;
  gradient_min(b.x, nl, re, c.n0, std::vector<Real>(b.x.size(), 7.0), g0);
  for (const auto& gi : g0) EXPECT_EQ(gi.norm(), 0.0);
}

TEST(Operators, DivergenceOfLinearField) {
  const Real dp = 0.02, re = 2.1 * dp;
  const auto c = lattice_constants(dp, re);
  const auto b = make_block(dp, re);
  NeighbourList nl;
  build_neighbour_list(b.x, re, nl);
  std::vector<Vec> v(b.x.size());
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = linear_v(b.x[i]);
  std::vector<Real> div;
  divergence(b.x, nl, re, c.n0, v, div);
  std::size_t n = 0;
  for (std::size_t i = 0; i < b.x.size(); ++i) {
    if (!b.interior[i]) continue;
    EXPECT_NEAR(div[i], linear_v_div, 1e-10);
    ++n;
  }
  EXPECT_GT(n, 500u);
}

TEST(Operators, LaplacianOfQuadraticWithin5PercentOnDisorderedParticles) {
  const Real dp = 0.01, re = 4.0 * dp;
  const auto c = lattice_constants(dp, re);
  for (const Real jitter : {0.0, 0.05}) {
    const auto b = make_block(dp, re, jitter);
    NeighbourList nl;
    build_neighbour_list(b.x, re, nl);
    std::vector<Real> lap;
    laplacian(b.x, nl, re, c.n0, c.lambda, field(b.x, quadratic), lap);
    Real worst = 0, sum = 0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < b.x.size(); ++i) {
      if (!b.interior[i]) continue;
      worst = std::max(worst, std::abs(lap[i] - quadratic_lap) / quadratic_lap);
      sum += lap[i];
      ++n;
    }
    // Exact at every interior particle of the lattice; on a disordered set eq. 12 is only
    // consistent on average (pointwise errors are O(jitter / dp)), so the mean is checked.
    if (jitter == 0.0) {
      EXPECT_LT(worst, 1e-9);
    } else {
      EXPECT_LT(std::abs(sum / n - quadratic_lap) / quadratic_lap, 0.05) << "mean";
    }
    std::printf("laplacian of quadratic, jitter %.2f dp: worst relative error %.3e, mean %.6f (exact %g)\n", jitter,
                worst, sum / n, quadratic_lap);
  }
  // The vector Laplacian is the scalar one per component.
  const auto b = make_block(dp, re);
  NeighbourList nl;
  build_neighbour_list(b.x, re, nl);
  std::vector<Vec> v(b.x.size());
  Vec scale = Vec::Ones();  // component a is scale[a] * quadratic
  scale[1] = -2.0;
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = quadratic(b.x[i]) * scale;
  std::vector<Vec> lv;
  laplacian(b.x, nl, re, c.n0, c.lambda, v, lv);
  for (std::size_t i = 0; i < b.x.size(); ++i) {
    if (!b.interior[i]) continue;
    EXPECT_LT((lv[i] - quadratic_lap * scale).norm(), 1e-8);
  }
}

// Errors of eq. 9 and eq. 12 on a smooth field fall as dp^2 on the lattice; print the observed rates.
// (3D: dp from 0.04 to 0.01 on a 0.6 x 0.4 x 0.4 box, 1e5 particles at the finest.)
TEST(Operators, ConvergenceAsDpHalves) {
  Real prev_g = 0, prev_l = 0, prev_c = 0;
#if MPSFSI_DIM == 2
  const std::vector<Real> dps = {0.04, 0.02, 0.01, 0.005};
  const Vec size = block_size;
#else
  const std::vector<Real> dps = {0.04, 0.02, 0.01};
  const Vec size(0.6, 0.4, 0.4);
#endif
  for (const Real dp : dps) {
    const Real re_g = 2.1 * dp, re_l = 4.0 * dp;
    const auto cg = lattice_constants(dp, re_g);
    const auto cl = lattice_constants(dp, re_l);
    const auto b = make_block(dp, 0.12, 0, 1, size);  // same interior region for every dp
    NeighbourList nl;
    build_neighbour_list(b.x, re_l, nl);
    const auto phi = field(b.x, smooth);
    std::vector<Vec> g, gc;
    std::vector<Real> l;
    gradient(b.x, nl, re_g, cg.n0, phi, g);
    corrected_gradient(b.x, nl, re_g, phi, gc);
    laplacian(b.x, nl, re_l, cl.n0, cl.lambda, phi, l);
    Real eg = 0, el = 0, ec = 0;
    for (std::size_t i = 0; i < b.x.size(); ++i) {
      if (!b.interior[i]) continue;
      eg = std::max(eg, (g[i] - smooth_grad(b.x[i])).norm());
      ec = std::max(ec, (gc[i] - smooth_grad(b.x[i])).norm());
      el = std::max(el, std::abs(l[i] - smooth_lap(b.x[i])));
    }
    if (prev_g > 0) {
      const Real rg = std::log2(prev_g / eg), rl = std::log2(prev_l / el), rc = std::log2(prev_c / ec);
      std::printf("dp %.4f: gradient error %.3e (rate %.2f), corrected %.3e (rate %.2f), laplacian %.3e (rate %.2f)\n",
                  dp, eg, rg, ec, rc, el, rl);
      EXPECT_GT(rg, 1.8);
      EXPECT_GT(rc, 1.8);
      EXPECT_GT(rl, 1.8);
    } else {
      std::printf("dp %.4f: gradient error %.3e, corrected %.3e, laplacian %.3e\n", dp, eg, ec, el);
    }
    prev_g = eg;
    prev_l = el;
    prev_c = ec;
  }
}

TEST(Operators, IsolatedParticleHasZeroGradientAndDensity) {
  const std::vector<Vec> x = {Vec::Zero(), Vec::Constant(10)};
  NeighbourList nl;
  build_neighbour_list(x, 0.1, nl);
  std::vector<Real> n;
  std::vector<Vec> g;
  number_density(x, nl, 0.1, n);
  corrected_gradient(x, nl, 0.1, {1.0, 2.0}, g);
  EXPECT_EQ(n[0], 0.0);
  EXPECT_EQ(g[0].norm(), 0.0);
  EXPECT_TRUE(g[1].allFinite());
}

// The derivatives of the number density (the exact projection's operator), for both kernels: dn_i/dx_k and
// dn_i/dx_i against central finite differences of eq. 8 on a jittered block, and dn_i/dx_i equal to the sum
// over the neighbours j of dn_j/dx_i (the symmetry of w).
class DensityDerivatives : public ::testing::TestWithParam<DensityKernel> {};

TEST_P(DensityDerivatives, MatchFiniteDifferences) {
  const DensityKernel kernel = GetParam();
  const Real dp = 0.02, re = 2.1 * dp, h = 1e-7 * dp;
  Block b = make_block(dp, re, 0.2, 3);
  NeighbourList nl;
  build_neighbour_list(b.x, re, nl);
  const auto n_at = [&](std::vector<Vec>& x, const std::size_t i) {
    Real n = 0;
    for (std::size_t j = 0; j < x.size(); ++j)
      if (j != i) n += kernel_at(kernel, (x[j] - x[i]).norm(), re).w;
    return n;
  };
  std::size_t checked = 0;
  for (std::size_t i = 0; i < b.x.size() && checked < 20; ++i) {
    if (!b.interior[i]) continue;
    ++checked;
    const Vec self = density_derivative_self_at(b.x, nl, re, i, AllNeighbours{}, kernel);
    Vec sum_of_pairs = Vec::Zero();
    for (std::size_t q = nl.begin(i); q < nl.end(i); ++q) {
      const auto j = static_cast<std::size_t>(nl.index[q]);
      const Vec r_ji = b.x[i] - b.x[j];  // x_i - x_j: dn_j/dx_i
      if (!in_support(r_ji.squaredNorm(), re)) continue;
      sum_of_pairs += density_derivative_pair(r_ji, r_ji.squaredNorm(), re, kernel);
    }
    EXPECT_LT((self - sum_of_pairs).norm(), 1e-12 * self.norm() + 1e-9) << "particle " << i;
    for (int a = 0; a < dim; ++a) {
      std::vector<Vec> x = b.x;
      x[i][a] += h;
      const Real up = n_at(x, i);
      x[i][a] -= 2 * h;
      const Real down = n_at(x, i);
      EXPECT_NEAR((up - down) / (2 * h), self[a], 1e-5 * (std::abs(self[a]) + 1 / dp)) << "particle " << i << " axis " << a;
      // dn_i/dx_k for the first neighbour k of i.
      const auto k = static_cast<std::size_t>(nl.index[nl.begin(i)]);
      const Vec r_ik = b.x[k] - b.x[i];
      const Vec pair = density_derivative_pair(r_ik, r_ik.squaredNorm(), re, kernel);
      x = b.x;
      x[k][a] += h;
      const Real up_k = n_at(x, i);
      x[k][a] -= 2 * h;
      const Real down_k = n_at(x, i);
      EXPECT_NEAR((up_k - down_k) / (2 * h), pair[a], 1e-5 * (std::abs(pair[a]) + 1 / dp)) << "particle " << i << " axis " << a;
    }
  }
  EXPECT_EQ(checked, 20u);
}

INSTANTIATE_TEST_SUITE_P(Operators, DensityDerivatives, ::testing::Values(DensityKernel::mps, DensityKernel::wendland));
