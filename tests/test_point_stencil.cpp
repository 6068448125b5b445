// Unit tests of the point stencils of sources and receivers (core/point_stencil.hpp): the
// interpolation weights reproduce linear fields exactly inside the lattice, between particles, at a
// free surface and at a corner (one-sided neighbourhoods); the moment stencil of an explosive source
// has no net force, the moment tensor I and no torque wherever the source sits; too few particles in
// range is an error.
#include "core/geometry.hpp"
#include "core/point_stencil.hpp"

#include <gtest/gtest.h>

#include <numeric>
#include <stdexcept>
#include <vector>

namespace mpsfsi {
namespace {

constexpr Real dp = 0.1;

/// A 2 x 1 m block of particles (lattice with centres at lo + (i + 1/2) dp), all candidates.
struct Block {
  std::vector<Vec> x = fill_rectangle(Vec(0, -1), Vec(2, 0), dp);
  std::vector<std::size_t> all = [this] {
    std::vector<std::size_t> a(x.size());
    std::iota(a.begin(), a.end(), 0);
    return a;
  }();
};

// Points: interior on a particle, interior between four particles, on the top surface (y = 0, half
// a spacing above the top row), at the top-left corner, slightly off-lattice near the bottom.
const std::vector<Vec> points = {Vec(1.05, -0.45), Vec(1.0, -0.5), Vec(0.7, 0.0), Vec(0.0, 0.0), Vec(1.234, -0.97)};

TEST(PointStencil, KernelIsCompactAndSmooth) {
  EXPECT_DOUBLE_EQ(stencil_weight(0, 1), 1);
  EXPECT_DOUBLE_EQ(stencil_weight(1, 1), 0);
  EXPECT_DOUBLE_EQ(stencil_weight(1.5, 1), 0);
  EXPECT_GT(stencil_weight(0.5, 1), stencil_weight(0.6, 1));
  // C2 at the edge: w ~ (1 - q)^4 near q = 1.
  EXPECT_LT(stencil_weight(0.99, 1), 1e-6);
}

TEST(PointStencil, InterpolationIsExactForLinearFields) {
  const Block b;
  const Vec a(0.3, -0.7);
  Mat g;
  g << 0.2, -1.1, 0.5, 0.9;
  for (const Real radius : {2 * dp, 2.5 * dp, 3 * dp}) {
    for (const Vec& p : points) {
      const PointStencil s = interpolation_stencil(b.x, b.all, p, radius);
      ASSERT_GE(s.index.size(), 3u);
      Real sum = 0;
      Vec first = Vec::Zero(), u = Vec::Zero();
      for (std::size_t q = 0; q < s.index.size(); ++q) {
        const Vec x = b.x[s.index[q]];
        EXPECT_LT((x - p).norm(), radius);
        sum += s.weight[q];
        first += s.weight[q] * (x - p);
        u += s.weight[q] * (a + g * x);
      }
      EXPECT_NEAR(sum, 1, 1e-12) << p.transpose();
      EXPECT_LT(first.norm(), 1e-12) << p.transpose();
      EXPECT_LT((u - (a + g * p)).norm(), 1e-12) << "radius " << radius << " point " << p.transpose();
    }
  }
}

TEST(PointStencil, InteriorWeightsAreAPositiveAverage) {
  // Between four particles of the lattice the stencil is symmetric: the correction vanishes and the
  // weights are the normalised kernel (a plain kernel average).
  const Block b;
  const PointStencil s = interpolation_stencil(b.x, b.all, Vec(1.0, -0.5), 2 * dp);
  for (const Real w : s.weight) EXPECT_GT(w, 0);
}

TEST(PointStencil, MomentStencilHasNoForceNoTorqueAndUnitMoment) {
  const Block b;
  for (const Real radius : {2 * dp, 2.5 * dp, 3 * dp}) {
    for (const Vec& p : points) {
      const VectorStencil s = moment_stencil(b.x, b.all, p, radius);
      Vec force = Vec::Zero();
      Mat moment = Mat::Zero();
      Real torque = 0;
      for (std::size_t q = 0; q < s.index.size(); ++q) {
        const Vec d = b.x[s.index[q]] - p;
        force += s.value[q];
        moment += d * s.value[q].transpose();
        torque += cross(d, s.value[q]);
      }
      EXPECT_LT(force.norm() * dp, 1e-12) << p.transpose();
      EXPECT_LT((moment - Mat::Identity()).norm(), 1e-12) << "radius " << radius << " point " << p.transpose();
      EXPECT_LT(std::abs(torque), 1e-12);
    }
  }
}

TEST(PointStencil, MomentStencilPushesOutwardInTheInterior) {
  const Block b;
  const Vec p(1.0, -0.5);
  const VectorStencil s = moment_stencil(b.x, b.all, p, 2 * dp);
  for (std::size_t q = 0; q < s.index.size(); ++q) EXPECT_GT(s.value[q].dot(b.x[s.index[q]] - p), 0);
}

TEST(PointStencil, TooFewParticlesInRangeIsAnError) {
  const Block b;
  // Radius below the distance to the nearest particle, or a point far outside the block.
  EXPECT_THROW(interpolation_stencil(b.x, b.all, Vec(1.05, -0.45), 0.05), std::invalid_argument);
  EXPECT_THROW(moment_stencil(b.x, b.all, Vec(5, 5), 2 * dp), std::invalid_argument);
  // Particles on one line only.
  const std::vector<Vec> line = {Vec(0, 0), Vec(0.1, 0), Vec(0.2, 0), Vec(0.3, 0)};
  const std::vector<std::size_t> all = {0, 1, 2, 3};
  EXPECT_THROW(interpolation_stencil(line, all, Vec(0.15, 0), 2 * dp), std::invalid_argument);
  EXPECT_THROW(moment_stencil(line, all, Vec(0.15, 0), 2 * dp), std::invalid_argument);
  try {
    moment_stencil(b.x, b.all, Vec(5, 5), 2 * dp);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fewer than three particles"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mpsfsi
