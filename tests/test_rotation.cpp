// Unit tests of core/rotation.hpp (issue 14, item 4): the plane rotation (RotationT<2>) and the
// quaternion rotation (RotationT<3>) compose, apply and invert consistently with their matrices and
// rotation vectors in every build; the dimension-aware cross product; and the prescribed tank roll of
// core/tank_motion about its pivot in the build's dimension (place, velocity = d place / dt, tank frame).
#include "core/rotation.hpp"
#include "core/tank_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace mpsfsi;

TEST(Rotation, PlaneRotationComposesAppliesAndInverts) {
  using R2 = RotationT<2>;
  using V2 = R2::V;
  const R2 a(0.3), b(-1.1);
  const V2 v(0.7, -0.2);
  EXPECT_LT(((a * b).apply(v) - a.apply(b.apply(v))).norm(), 1e-15);
  EXPECT_LT((a.inverse().apply(a.apply(v)) - v).norm(), 1e-15);
  EXPECT_LT((R2::about_z(pi / 2).apply(V2(1, 0)) - V2(0, 1)).norm(), 1e-15);  // counter-clockwise
  EXPECT_DOUBLE_EQ((a * b).angle(), 0.3 - 1.1);
  EXPECT_DOUBLE_EQ(R2::from_vector(0.4).log(), 0.4);
  EXPECT_LT((a.matrix() * a.matrix().transpose() - R2::M::Identity()).norm(), 1e-15);
}

TEST(Rotation, QuaternionRotationComposesAppliesAndInverts) {
  using R3 = RotationT<3>;
  using V3 = R3::V;
  const R3 a = R3::from_vector(V3(0.3, -0.2, 0.5)), b = R3::about_axis(V3(1, 1, 0), 0.8);
  const V3 v(0.7, -0.2, 1.3);
  EXPECT_LT(((a * b).apply(v) - a.apply(b.apply(v))).norm(), 1e-15);
  EXPECT_LT(((a * b).matrix() - a.matrix() * b.matrix()).norm(), 1e-15);
  EXPECT_LT((a.inverse().apply(a.apply(v)) - v).norm(), 1e-15);
  EXPECT_LT((a.log() - V3(0.3, -0.2, 0.5)).norm(), 1e-15);
  EXPECT_LT((R3::from_vector(V3::Zero()).apply(v) - v).norm(), 0.0 + 1e-300);
  EXPECT_LT((R3::about_z(pi / 2).apply(V3(1, 0, 0)) - V3(0, 1, 0)).norm(), 1e-15);  // right-handed about z
  EXPECT_LT((a.matrix() * a.matrix().transpose() - R3::M::Identity()).norm(), 1e-15);
  // About z it is the plane rotation on (x, y) and leaves z alone.
  const R3::M m = R3::about_z(0.3).matrix();
  EXPECT_LT((m.topLeftCorner<2, 2>() - RotationT<2>(0.3).matrix()).norm(), 1e-15);
  EXPECT_DOUBLE_EQ(m(2, 2), 1.0);
}

TEST(Rotation, CrossProductOfTheBuild) {
  const Vec e0 = Vec::Unit(0), e1 = Vec::Unit(1);
#if MPSFSI_DIM == 2
  EXPECT_EQ(cross(e0, e1), 1.0);  // the z component
#else
  EXPECT_EQ(cross(e0, e1), Vec(Vec::Unit(2)));
#endif
  // omega e_z x r: the velocity of a point rotating about the origin.
  const Vec r = 2.0 * e0;
  EXPECT_LT((cross(about_z(0.5), r) - e1).norm(), 1e-15);
}

// Rigid roll of the tank about its pivot: a quarter turn, the velocity is d place / d theta times omega,
// the tank frame undoes the placement (about z in 3D, the default roll axis).
TEST(Rotation, TankRollAboutThePivot) {
  TankMotionParams q;
  q.type = TankMotionParams::Type::sine_roll;
  q.amplitude = 0.1;
  q.period = 1.0;
  q.pivot = Vec::Zero();
  q.pivot[0] = 0.3;
  const TankMotion m(q);
  Vec x0 = Vec::Zero();
  x0[0] = 0.4;
  Vec expected = q.pivot;
  expected[1] = 0.1;
  EXPECT_LT((m.place(x0, pi / 2) - expected).norm(), 1e-15);
  Vec y0 = Vec::Constant(0.05);
  y0[0] = 0.17;
  const Real th = 0.2, h = 1e-6;
  const Vec dx = (m.place(y0, th + h) - m.place(y0, th - h)) / (2 * h);
  EXPECT_LT((dx - m.velocity_at(m.place(y0, th), 1.0)).norm(), 1e-8);
  EXPECT_LT((m.to_tank_frame(m.place(y0, th), th) - (y0 - q.pivot)).norm(), 1e-15);
}

#if MPSFSI_DIM == 3
// In 3D the roll axis is a parameter: about -e_y the x-z section rolls as the 2D tank in x-y.
TEST(Rotation, TankRollAboutAnAxis) {
  TankMotionParams q;
  q.type = TankMotionParams::Type::sine_roll;
  q.pivot = Vec(0.3, 0.0, 0.0);
  q.axis = Vec(0, -1, 0);
  const TankMotion m(q);
  EXPECT_LT((m.place(Vec(0.4, 0.5, 0.0), pi / 2) - Vec(0.3, 0.5, 0.1)).norm(), 1e-15);
  const Vec y0(0.17, 0.05, 0.02);
  const Real th = 0.2, h = 1e-6;
  const Vec dx = (m.place(y0, th + h) - m.place(y0, th - h)) / (2 * h);
  EXPECT_LT((dx - m.velocity_at(m.place(y0, th), 1.0)).norm(), 1e-8);
}
#endif
