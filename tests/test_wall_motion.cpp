// Unit tests of a wall's own motion (core/wall_motion.hpp): the displacement is the integral of the velocity, the
// velocity reaches its value after the ramp and the wall stays after `stop`; a sine's rate is its derivative; a
// rotation places the wall's points about the carried pivot with v = d' + omega x r.
#include "core/wall_motion.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

using namespace mpsfsi;

namespace {

/// The integral of f over [a, b] by Simpson's rule on n (even) intervals.
template <class F>
Vec simpson(const F& f, const Real a, const Real b, const int n) {
  const Real h = (b - a) / n;
  Vec sum = f(a) + f(b);
  for (int k = 1; k < n; ++k) sum += (k % 2 ? 4.0 : 2.0) * f(a + k * h);
  return sum * h / 3;
}

Vec unit(const int axis) { return Vec::Unit(axis); }

}  // namespace

TEST(WallMotion, ConstantVelocityAfterARamp) {
  WallMotionSpec s;
  s.translation = WallMotionSpec::Translation::velocity;
  s.velocity = 0.2 * unit(dim - 1);
  s.start = 0.1;
  s.ramp = 0.05;
  s.stop = 0.5;
  const WallMotion m(s);
  EXPECT_TRUE(m.moving());
  EXPECT_EQ(m.displacement(0.05), Vec::Zero());
  EXPECT_EQ(m.translation_velocity(0.05), Vec::Zero());
  // The displacement is the integral of the velocity (through the ramp and past it; Simpson's rule on each
  // smooth piece).
  const auto v = [&](const Real u) { return m.translation_velocity(u); };
  for (const Real t : {0.12, 0.15, 0.3, 0.45}) {
    const Vec integral = simpson(v, 0.1, std::min(t, 0.15), 2000) + (t > 0.15 ? simpson(v, 0.15, t, 2000) : Vec::Zero());
    EXPECT_LT((m.displacement(t) - integral).norm(), 1e-12) << "t = " << t;
  }
  EXPECT_LT((m.translation_velocity(0.3) - s.velocity).norm(), 1e-15);
  // After the ramp: V (t - start - ramp / 2); after stop the wall stays.
  EXPECT_NEAR(m.displacement(0.3)[dim - 1], 0.2 * (0.3 - 0.1 - 0.025), 1e-15);
  EXPECT_NEAR(m.displacement(0.5)[dim - 1], 0.2 * (0.5 - 0.1 - 0.025), 1e-15);
  EXPECT_EQ(m.displacement(0.9), m.displacement(0.5));
  EXPECT_EQ(m.translation_velocity(0.6), Vec::Zero());
  // Without rotation a point moves by d.
  const Vec x0 = Vec::Constant(0.3);
  EXPECT_LT((m.place(x0, 0.3) - x0 - m.displacement(0.3)).norm(), 1e-15);
  EXPECT_LT((m.velocity(x0, 0.3) - s.velocity).norm(), 1e-15);
}

TEST(WallMotion, RampedSineAndRotationAreConsistent) {
  WallMotionSpec s;
  s.translation = WallMotionSpec::Translation::sine;
  s.amplitude = 0.05 * unit(0);
  s.period = 1.2;
  s.rotation = WallMotionSpec::Rotation::sine;
  s.pivot = Vec::Constant(0.1);
  s.angle_amplitude = 0.2;
  s.angle_period = 0.8;
  s.ramp = 1.0;
  const WallMotion m(s);
  const Vec x0 = Vec::Constant(0.4);
  const Real h = 1e-6;
  for (const Real t : {0.2, 0.7, 1.3, 2.9}) {
    // The rates are the derivatives (centred differences to h^2).
    EXPECT_LT((m.translation_velocity(t) - (m.displacement(t + h) - m.displacement(t - h)) / (2 * h)).norm(), 1e-8);
    EXPECT_NEAR(m.angular_velocity(t), (m.angle(t + h) - m.angle(t - h)) / (2 * h), 1e-8);
    EXPECT_LT((m.velocity(x0, t) - (m.place(x0, t + h) - m.place(x0, t - h)) / (2 * h)).norm(), 1e-8) << "t = " << t;
    // The distance to the carried pivot is kept.
    EXPECT_NEAR((m.place(x0, t) - s.pivot - m.displacement(t)).norm(), (x0 - s.pivot).norm(), 1e-14);
  }
  // After the ramp the amplitudes are whole: at a quarter period past 1.2 s, d = A.
  EXPECT_NEAR(m.displacement(1.2 + 0.3)[0], 0.05, 1e-15);
  EXPECT_NEAR(m.angle(1.6 + 0.2), 0.2, 1e-15);
  // Before the ramp's end it is smaller.
  EXPECT_LT(std::abs(m.displacement(0.3)[0]), 0.05 * 0.5);
  EXPECT_FALSE(WallMotion().moving());
  EXPECT_EQ(WallMotion().place(x0, 1.0), x0);
}

// A translation table: the wall moves by the table's change since start (it starts where its body is), linearly
// between the rows; its velocity is the centred difference over the half window (the exact slope between rows
// far enough from a row), zero before start and after the table's last row; `stop` freezes it.
TEST(WallMotion, TranslationTableMovesByItsChangeSinceStart) {
  WallMotionSpec s;
  s.translation = WallMotionSpec::Translation::table;
  s.direction = unit(0);
  s.table_time = {0.0, 0.1, 0.3, 0.4};
  s.table_value = {0.02, 0.04, 0.0, 0.0};  // m
  s.table_half_window = 0.01;
  s.start = 0.5;
  const WallMotion m(s);
  EXPECT_EQ(m.displacement(0.2), Vec::Zero());
  EXPECT_EQ(m.displacement(0.5), Vec::Zero());
  EXPECT_NEAR(m.displacement(0.55)[0], 0.01, 1e-15);  // 0.03 - 0.02
  EXPECT_NEAR(m.displacement(0.7)[0], 0.0, 1e-15);     // 0.02 - 0.02
  EXPECT_NEAR(m.displacement(0.8)[0], -0.02, 1e-15);
  EXPECT_EQ(m.displacement(2.0), m.displacement(0.9));  // the table's last value
  EXPECT_EQ(m.displacement(0.55)[1], 0.0);
  EXPECT_NEAR(m.translation_velocity(0.55)[0], 0.2, 1e-12);   // slope 0.02 / 0.1
  EXPECT_NEAR(m.translation_velocity(0.7)[0], -0.2, 1e-12);   // slope -0.04 / 0.2
  EXPECT_NEAR(m.translation_velocity(0.6)[0], 0.0, 1e-12);    // the window over the row at 0.1: (+0.2 - 0.2) / 2
  EXPECT_NEAR(m.translation_velocity(0.605)[0], (0.2 * 0.005 - 0.2 * 0.015) / 0.02, 1e-12);
  EXPECT_EQ(m.translation_velocity(0.45), Vec::Zero());
  EXPECT_EQ(m.translation_velocity(1.5), Vec::Zero());
  // The velocity's integral is the displacement (the window's smoothing at a row keeps the integral; Simpson's
  // rule from just after start, where the velocity is switched on).
  const auto v = [&](const Real u) { return m.translation_velocity(u); };
  const Real a = 0.5 + 1e-9;
  EXPECT_LT((simpson(v, a, 0.95, 9000) - (m.displacement(0.95) - m.displacement(a))).norm(), 1e-7);
  s.stop = 0.65;
  const WallMotion stopped(s);
  EXPECT_EQ(stopped.displacement(0.8), m.displacement(0.65));
  EXPECT_EQ(stopped.translation_velocity(0.8), Vec::Zero());
}

// A rotation table turns the wall about the pivot by the table's change since start, ramped like a sine; a table
// sampled from a sine gives the sine's motion to the interpolation's error.
TEST(WallMotion, RotationTableFollowsASampledSine) {
  WallMotionSpec sine;
  sine.rotation = WallMotionSpec::Rotation::sine;
  sine.pivot = Vec::Constant(0.1);
  sine.angle_amplitude = 0.1;
  sine.angle_period = 1.0;
  sine.ramp = 0.5;
  WallMotionSpec table = sine;
  table.rotation = WallMotionSpec::Rotation::table;
  for (int k = 0; k <= 3000; ++k) {
    table.angle_time.push_back(k * 1e-3);
    table.angle_value.push_back(0.1 * std::sin(2 * pi * k * 1e-3));
  }
  table.angle_half_window = 1e-3;
  const WallMotion a(sine), b(table);
  const Vec x0 = Vec::Constant(0.3);
  for (const Real t : {0.1, 0.37, 0.8, 1.25, 2.6}) {
    EXPECT_NEAR(a.angle(t), b.angle(t), 0.1 * 2e-5) << "t = " << t;  // (2 pi dt)^2 / 8 of the amplitude
    // The centred difference over one row spacing: (h^2 / 6 + dt^2 / 8) |theta'''| of the amplitude's rate.
    EXPECT_NEAR(a.angular_velocity(t), b.angular_velocity(t), 1e-5) << "t = " << t;
    EXPECT_LT((a.place(x0, t) - b.place(x0, t)).norm(), 1e-5);
  }
  EXPECT_EQ(b.angle(0), 0.0);
  EXPECT_EQ(b.angular_velocity(3.5), 0.0);
}
