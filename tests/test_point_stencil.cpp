// Unit tests of the point stencils of sources and receivers (core/point_stencil.hpp): the
// interpolation weights reproduce linear fields exactly inside the lattice, between particles, at a
// free surface and at a corner (one-sided neighbourhoods); the moment stencil of an explosive source
// has no net force, the moment tensor I and no torque wherever the source sits; too few particles in
// range is an error. In the 3D build the block is a 2 x 1 x 1 box and the points get a z coordinate.
#include "core/geometry.hpp"
#include "core/point_stencil.hpp"

#include <gtest/gtest.h>

#include <numeric>
#include <stdexcept>
#include <vector>

namespace mpsfsi {
namespace {

constexpr Real dp = 0.1;

#if MPSFSI_DIM == 2
const Vec block_lo(0, -1), block_hi(2, 0);
#else
const Vec block_lo(0, -1, 0), block_hi(2, 0, 1);
#endif

/// A 2 x 1 (x 1) m block of particles (lattice with centres at lo + (i + 1/2) dp), all candidates.
struct Block {
  std::vector<Vec> x = fill_rectangle(block_lo, block_hi, dp);
  std::vector<std::size_t> all = [this] {
    std::vector<std::size_t> a(x.size());
    std::iota(a.begin(), a.end(), 0);
    return a;
  }();
};

// Points: interior on a particle, interior between four particles, on the top surface (y = 0, half
// a spacing above the top row), at the top-left corner, slightly off-lattice near the bottom.
#if MPSFSI_DIM == 2
const std::vector<Vec> points = {Vec(1.05, -0.45), Vec(1.0, -0.5), Vec(0.7, 0.0), Vec(0.0, 0.0), Vec(1.234, -0.97)};
const Vec centre(1.0, -0.5);  ///< between particles, in the middle of the block
#else
const std::vector<Vec> points = {Vec(1.05, -0.45, 0.45), Vec(1.0, -0.5, 0.5), Vec(0.7, 0.0, 0.45), Vec(0.0, 0.0, 0.0),
                                 Vec(1.234, -0.97, 0.61)};
const Vec centre(1.0, -0.5, 0.5);
#endif

/// A linear field a + G x.
struct LinearField {
  Vec a;
  Mat g;
  LinearField() {
#if MPSFSI_DIM == 2
    a = Vec(0.3, -0.7);
    g << 0.2, -1.1, 0.5, 0.9;
#else
    a = Vec(0.3, -0.7, 0.1);
    g << 0.2, -1.1, 0.4, 0.5, 0.9, -0.3, 0.8, 0.1, -0.6;
#endif
  }
};

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
  const LinearField f;
  const Vec& a = f.a;
  const Mat& g = f.g;
  for (const Real radius : {2 * dp, 2.5 * dp, 3 * dp}) {
    for (const Vec& p : points) {
      const PointStencil s = interpolation_stencil(b.x, b.all, p, radius);
      ASSERT_GE(s.index.size(), static_cast<std::size_t>(dim + 1));
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
  const PointStencil s = interpolation_stencil(b.x, b.all, centre, 2 * dp);
  for (const Real w : s.weight) EXPECT_GT(w, 0);
}

TEST(PointStencil, MomentStencilHasNoForceNoTorqueAndUnitMoment) {
  const Block b;
  for (const Real radius : {2 * dp, 2.5 * dp, 3 * dp}) {
    for (const Vec& p : points) {
      const VectorStencil s = moment_stencil(b.x, b.all, p, radius);
      Vec force = Vec::Zero();
      Mat moment = Mat::Zero();
      Angular torque = cross(Vec::Zero(), Vec::Zero());  // zero of the build's angular type
      for (std::size_t q = 0; q < s.index.size(); ++q) {
        const Vec d = b.x[s.index[q]] - p;
        force += s.value[q];
        moment += d * s.value[q].transpose();
        torque += cross(d, s.value[q]);
      }
      EXPECT_LT(force.norm() * dp, 1e-12) << p.transpose();
      EXPECT_LT((moment - Mat::Identity()).norm(), 1e-12) << "radius " << radius << " point " << p.transpose();
#if MPSFSI_DIM == 2
      EXPECT_LT(std::abs(torque), 1e-12);
#else
      EXPECT_LT(torque.norm(), 1e-12);
#endif
    }
  }
}

TEST(PointStencil, MomentStencilPushesOutwardInTheInterior) {
  const Block b;
  const Vec p = centre;
  const VectorStencil s = moment_stencil(b.x, b.all, p, 2 * dp);
  for (std::size_t q = 0; q < s.index.size(); ++q) EXPECT_GT(s.value[q].dot(b.x[s.index[q]] - p), 0);
}

TEST(PointStencil, TooFewParticlesInRangeIsAnError) {
  const Block b;
  // Radius below the distance to the nearest particle, or a point far outside the block.
  const Vec far = Vec::Constant(5);
  EXPECT_THROW(interpolation_stencil(b.x, b.all, points[0], 0.05), std::invalid_argument);
  EXPECT_THROW(moment_stencil(b.x, b.all, far, 2 * dp), std::invalid_argument);
  // Particles on one line only.
  std::vector<Vec> line(4, Vec::Zero());
  for (std::size_t k = 0; k < line.size(); ++k) line[k][0] = 0.1 * static_cast<Real>(k);
  const std::vector<std::size_t> all = {0, 1, 2, 3};
  Vec mid = Vec::Zero();
  mid[0] = 0.15;
  EXPECT_THROW(interpolation_stencil(line, all, mid, 2 * dp), std::invalid_argument);
  EXPECT_THROW(moment_stencil(line, all, mid, 2 * dp), std::invalid_argument);
#if MPSFSI_DIM == 3
  // 3D: particles in one plane only.
  std::vector<Vec> plane;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) plane.push_back(Vec(0.1 * i, 0.1 * j, 0.0));
  std::vector<std::size_t> all_plane(plane.size());
  std::iota(all_plane.begin(), all_plane.end(), 0);
  EXPECT_THROW(interpolation_stencil(plane, all_plane, Vec(0.1, 0.1, 0.0), 2 * dp), std::invalid_argument);
  EXPECT_THROW(moment_stencil(plane, all_plane, Vec(0.1, 0.1, 0.0), 2 * dp), std::invalid_argument);
#endif
  try {
    moment_stencil(b.x, b.all, far, 2 * dp);
  } catch (const std::invalid_argument& e) {
    const char* expected = dim == 2 ? "fewer than three particles" : "fewer than four particles";
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mpsfsi
