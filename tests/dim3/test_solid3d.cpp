// Unit tests of the rotation-aware elastic solid in 3D (solid/solid_solver.cpp with MPSFSI_DIM=3): a free
// body conserves momentum and angular momentum (orbital plus spin, a vector) to round-off over 1e4 steps;
// a body spinning about an arbitrary axis keeps its shape, and its particles' rotations follow the body's;
// a rigidly rotated body with rotated particles carries no force; bonds break and fragments separate.
#include "core/rotation.hpp"
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"
#include "support/solid_runs.hpp"
#include "support/spec_builders.hpp"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace mpsfsi {
namespace {

using test::base_case;
using test::material;
using test::solid_body;

/// The mean of the points.
Vec centroid(const std::vector<Vec>& x) {
  Vec c = Vec::Zero();
  for (const Vec& y : x) c += y;
  return c / static_cast<Real>(x.size());
}

/// The rotation that best maps the centred reference points onto the centred current points (Kabsch).
Mat best_rotation(const std::vector<Vec>& x0, const std::vector<Vec>& x) {
  const Vec c0 = centroid(x0), c = centroid(x);
  Mat h = Mat::Zero();
  for (std::size_t i = 0; i < x.size(); ++i) h += (x0[i] - c0) * (x[i] - c).transpose();
  const Eigen::JacobiSVD<Mat> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat d = Mat::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() > 0 ? 1 : -1;
  return svd.matrixV() * d * svd.matrixU().transpose();
}

/// Largest distance of a current point from the reference shape moved rigidly (best rotation, centroids).
Real shape_error(const std::vector<Vec>& x0, const std::vector<Vec>& x, const Mat& r) {
  const Vec c0 = centroid(x0), c = centroid(x);
  Real e = 0;
  for (std::size_t i = 0; i < x.size(); ++i) e = std::max(e, (x[i] - c - r * (x0[i] - c0)).norm());
  return e;
}

// A free block moving and spinning about an oblique axis: linear momentum and total angular momentum
// (sum m x cross v + I omega, a vector) are conserved to round-off by the symplectic Euler update (the bond
// forces are equal and opposite and their couple is the particles' torques, eq. 41-43), the energy stays
// within 1 %.
TEST(Solid3D, FreeBodyConservesMomentumAndAngularMomentum) {
  CaseSpec spec = base_case(0.01);
  spec.solid_materials.push_back(material("rubber", 1000, 1e5, 0.3));
  BodySpec b = solid_body("block", "rubber", Vec(0, 0, 0), Vec(0.08, 0.05, 0.04));
  b.velocity = Vec(0.2, -0.1, 0.05);
  b.angular_velocity = Vec(12.0, -20.0, 28.0);  // centrifugal stretch: strain energy of a few % of the total
  spec.bodies.push_back(b);
  Scene scene = build_scene(spec);
  SolidSolver solid(solid_setup(spec), scene.particles);
  const Real dt = solid.stable_dt();
  const SolidDiagnostics d0 = solid.diagnostics();
  ASSERT_GT(d0.rotational, 0);
  const test::EnergyRecord run = test::advance_recording_energy(solid, 10000, 100);
  const Real e_min = run.e_min, e_max = run.e_max;
  const SolidDiagnostics d1 = solid.diagnostics();
  const Real dp_rel = (d1.momentum - d0.momentum).norm() / d0.momentum.norm();
  const Real dl_rel = (d1.angular_momentum - d0.angular_momentum).norm() / d0.angular_momentum.norm();
  std::printf("free block, %d particles, 1e4 steps of %.3e s: |dP|/|P| = %.2e, |dL|/|L| = %.2e, energy range %.3e, "
              "strain energy at the end %.3f of the total\n",
              static_cast<int>(scene.particles.size()), dt, dp_rel, dl_rel, (e_max - e_min) / d0.total(),
              d1.strain / d1.total());
  EXPECT_LT(dp_rel, 1e-12);
  EXPECT_LT(dl_rel, 1e-12);
  EXPECT_LT((e_max - e_min) / d0.total(), 0.01);
  EXPECT_GT(d1.strain, 1e-3 * d1.total());  // the spin stretched the body: energy moved between the forms
}

// A stiff block spinning slowly about an oblique axis through several turns: it stays the same shape
// (moved rigidly to within 1e-3 dp), and every particle's rotation is the body's rotation (to 1e-3 rad), so
// the bonds see no relative rotation. Without rotation-aware bonds the particles' frames would lag behind.
TEST(Solid3D, SpinningBodyKeepsItsShape) {
  const Real dp = 0.01;
  CaseSpec spec = base_case(dp);
  spec.solid_materials.push_back(material("steel", 1000, 1e7, 0.3));
  spec.bodies.push_back(solid_body("block", "steel", Vec(0, 0, 0), Vec(0.06, 0.05, 0.04)));
  const Vec axis = Vec(1, 2, 3).normalized();
  spec.bodies.back().angular_velocity = 20.0 * axis;
  Scene scene = build_scene(spec);
  const std::vector<Vec> x0 = scene.particles.position;
  SolidSolver solid(solid_setup(spec), scene.particles);
  const Real dt = solid.stable_dt();
  Real t = 0, worst_shape = 0, worst_rotation = 0;
  const auto& rotation = scene.particles.vector_field("rotation");
  while (t < 0.6) {  // about two turns
    for (int q = 0; q < 200; ++q) {
      solid.advance(t, dt);
      t += dt;
    }
    const Mat r = best_rotation(x0, scene.particles.position);
    worst_shape = std::max(worst_shape, shape_error(x0, scene.particles.position, r));
    for (const Vec& phi : rotation) {
      const Mat ri = Rotation::from_vector(phi).matrix();
      worst_rotation = std::max(worst_rotation, Rotation(Eigen::Quaternion<Real>(Mat(r.transpose() * ri))).log().norm());
    }
  }
  std::printf("spinning block: %.3g turns, largest shape error %.3e dp, largest particle rotation off the body's %.3e rad\n",
              20.0 * t / (2 * pi), worst_shape / dp, worst_rotation);
  EXPECT_GT(20.0 * t, 3.5 * pi);
  EXPECT_LT(worst_shape, 1e-3 * dp);
  EXPECT_LT(worst_rotation, 1e-3);
}

// The bonds measure the relative rotation: a body turned rigidly through 40 degrees about an oblique axis,
// with each particle's rotation set to the same turn, is unstrained (force-free to round-off) and stays at
// rest; with the particles' rotations left at zero the same body is strained.
TEST(Solid3D, RigidlyRotatedBodyIsUnstrained) {
  CaseSpec spec = base_case(0.01);
  spec.solid_materials.push_back(material("rubber", 1000, 1e6, 0.3));
  spec.bodies.push_back(solid_body("block", "rubber", Vec(0, 0, 0), Vec(0.05, 0.04, 0.03)));
  const Rotation turn = Rotation::about_axis(Vec(-1, 2, 0.5), 40 * pi / 180);
  for (const bool rotate_particles : {true, false}) {
    Scene scene = build_scene(spec);
    SolidSolver solid(solid_setup(spec), scene.particles);
    auto& rotation = scene.particles.vector_field("rotation");
    for (std::size_t i = 0; i < scene.particles.size(); ++i) {
      scene.particles.position[i] = turn.apply(scene.particles.position[i]);
      if (rotate_particles) rotation[i] = turn.log();
    }
    const SolidDiagnostics d = solid.diagnostics();
    if (rotate_particles) {
      EXPECT_LT(d.strain, 1e-20);
      const Real dt = solid.stable_dt();
      for (int q = 0; q < 100; ++q) solid.advance(q * dt, dt);
      Real v_max = 0;
      for (const Vec& v : scene.particles.velocity) v_max = std::max(v_max, v.norm());
      EXPECT_LT(v_max, 1e-12);
    } else {
      EXPECT_GT(d.strain, 1e-6);
    }
  }
}

// Brittle fracture in 3D: a bar pulled apart at 5 m/s each way breaks (eq. 47) into two fragments that
// separate, and no particle of one fragment comes closer than dp to the other.
TEST(Solid3D, PulledBarBreaksIntoTwoFragments) {
  CaseSpec spec = test::brittle_bar_case();
  Scene scene = build_scene(spec);
  test::pull_bar_apart(scene.particles);
  SolidSolver solid(solid_setup(spec), scene.particles);
  const std::size_t bonds0 = solid.n_bonds();
  const Real dt = solid.stable_dt();
  Real t = 0;
  for (int q = 0; q < 2000; ++q) {
    solid.advance(t, dt);
    t += dt;
  }
  solid.prepare_output(t);
  EXPECT_LT(solid.n_bonds(), bonds0);
  EXPECT_EQ(solid.n_fragments(), 2u);
  EXPECT_GT(solid.min_distance_between_fragments(), 0.01);
}

// Contact in 3D (seed 004 §4.4): a cube thrown onto a block at an angle, spinning: the unbonded surface particles
// repel, the bodies never come closer than l0/2, the cube bounces, and momentum and angular momentum are kept
// through the contact (the contact force is central).
TEST(Solid3D, BodiesInContactRepelAndNeverInterpenetrate) {
  CaseSpec spec = base_case(0.05);
  spec.solid_materials.push_back(material("soft", 1000, 6e6, 0.3));
  spec.solid_materials.push_back(material("hard", 1000, 10e6, 0.3));
  BodySpec a = solid_body("cube", "soft", Vec(0, 0, 0.3), Vec(0.3, 0.3, 0.6));
  a.velocity = Vec(2, 1, -15);
  a.angular_velocity = Vec(3, -2, 5);
  spec.bodies.push_back(a);
  spec.bodies.push_back(solid_body("block", "hard", Vec(-0.3, -0.3, 0), Vec(0.6, 0.6, 0.25)));
  Scene scene = build_scene(spec);
  SolidSolver solid(solid_setup(spec), scene.particles);
  solid.prepare_output(0);
  EXPECT_EQ(solid.n_fragments(), 2u);
  const SolidDiagnostics d0 = solid.diagnostics();
  const test::ContactRecord c = test::advance_recording_contacts(solid, 1500, 10);
  const SolidDiagnostics d1 = solid.diagnostics();
  const Real v_up = test::mean_velocity(scene.particles, 0, 2) - test::mean_velocity(scene.particles, 1, 2);
  std::printf("3D contact: %zu pairs at most, closest %.3f l0, |dP|/|P| = %.2e, |dL|/|L| = %.2e, cube's vertical speed "
              "relative to the block %.3f m/s\n", c.max_contacts, c.closest / spec.dp,
              (d1.momentum - d0.momentum).norm() / d0.momentum.norm(),
              (d1.angular_momentum - d0.angular_momentum).norm() / d0.angular_momentum.norm(),
              v_up);
  EXPECT_GT(c.max_contacts, 0u);
  EXPECT_GT(c.closest, 0.5 * spec.dp);
  EXPECT_LT((d1.momentum - d0.momentum).norm() / d0.momentum.norm(), 1e-12);
  EXPECT_LT((d1.angular_momentum - d0.angular_momentum).norm() / d0.angular_momentum.norm(), 1e-12);
  EXPECT_GT(v_up, 0);  // bounced
}

}  // namespace
}  // namespace mpsfsi
