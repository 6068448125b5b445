// Prescribed rigid motion of a wall body (wall_motion.hpp).
#include "core/wall_motion.hpp"

#include "core/ramp.hpp"
#include "core/rotation.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace mpsfsi {

namespace {

/// The integral of ramp_factor over [0, tau]: tau/2 - T sin(pi tau / T) / (2 pi) within the ramp, then T/2 + tau - T.
Real ramp_integral(const Real tau, const Real ramp) {
  if (tau <= 0) return 0;
  if (!(ramp > 0)) return tau;
  if (tau >= ramp) return 0.5 * ramp + (tau - ramp);
  return 0.5 * tau - ramp * std::sin(pi * tau / ramp) / (2 * pi);
}

/// d ramp_factor / d tau.
Real ramp_rate(const Real tau, const Real ramp) {
  if (!(ramp > 0) || tau <= 0 || tau >= ramp) return 0;
  return 0.5 * pi / ramp * std::sin(pi * tau / ramp);
}

/// a r(tau) sin(w tau) and its rate, for an amplitude a (any type) and a period.
template <class T>
std::pair<T, T> ramped_sine(const T& amplitude, const Real period, const Real tau, const Real ramp) {
  const Real w = 2 * pi / period;
  const Real r = ramp_factor(tau, ramp);
  return {amplitude * (r * std::sin(w * tau)), amplitude * (ramp_rate(tau, ramp) * std::sin(w * tau) + r * w * std::cos(w * tau))};
}

}  // namespace

WallMotion::WallMotion(const WallMotionSpec& spec) : s_(spec) {
  if (s_.translation == WallMotionSpec::Translation::table)
    translation_table_ = TableSeries(s_.table_time, s_.table_value, s_.table_half_window);
  if (s_.rotation == WallMotionSpec::Rotation::table) angle_table_ = TableSeries(s_.angle_time, s_.angle_value, s_.angle_half_window);
}

namespace {

/// r(tau) (s(tau) - s(0)) and its rate, s a table's series.
std::pair<Real, Real> ramped_table(const TableSeries& s, const Real tau, const Real ramp) {
  const Real change = s.value(tau) - s.value(0);
  return {ramp_factor(tau, ramp) * change, ramp_rate(tau, ramp) * change + ramp_factor(tau, ramp) * s.rate(tau)};
}

}  // namespace

Real WallMotion::tau(const Real t) const { return std::max(Real(0), std::min(t, s_.stop) - s_.start); }

std::pair<Vec, Vec> WallMotion::translation(const Real t) const {
  const Vec zero = Vec::Zero();
  switch (s_.translation) {
    case WallMotionSpec::Translation::none: return {zero, zero};
    case WallMotionSpec::Translation::velocity:
      return {s_.velocity * ramp_integral(tau(t), s_.ramp), running(t) ? Vec(s_.velocity * ramp_factor(tau(t), s_.ramp)) : zero};
    case WallMotionSpec::Translation::sine: {
      const auto [d, v] = ramped_sine(s_.amplitude, s_.period, tau(t), s_.ramp);
      return {d, running(t) ? v : zero};
    }
    case WallMotionSpec::Translation::table: {
      const auto [d, v] = ramped_table(translation_table_, tau(t), s_.ramp);
      return {d * s_.direction, running(t) ? Vec(v * s_.direction) : zero};
    }
  }
  return {zero, zero};
}

Vec WallMotion::displacement(const Real t) const { return translation(t).first; }

Vec WallMotion::translation_velocity(const Real t) const { return translation(t).second; }

Real WallMotion::angle(const Real t) const {
  switch (s_.rotation) {
    case WallMotionSpec::Rotation::none: return 0;
    case WallMotionSpec::Rotation::sine: return ramped_sine(s_.angle_amplitude, s_.angle_period, tau(t), s_.ramp).first;
    case WallMotionSpec::Rotation::table: return ramped_table(angle_table_, tau(t), s_.ramp).first;
  }
  return 0;
}

Real WallMotion::angular_velocity(const Real t) const {
  if (!running(t)) return 0;
  switch (s_.rotation) {
    case WallMotionSpec::Rotation::none: return 0;
    case WallMotionSpec::Rotation::sine: return ramped_sine(s_.angle_amplitude, s_.angle_period, tau(t), s_.ramp).second;
    case WallMotionSpec::Rotation::table: return ramped_table(angle_table_, tau(t), s_.ramp).second;
  }
  return 0;
}

Mat WallMotion::matrix(const Real t) const {
  if (s_.rotation == WallMotionSpec::Rotation::none) return Mat::Identity();
  return rotation(t).matrix();
}

Rotation WallMotion::rotation(const Real t) const {
#if MPSFSI_DIM == 2
  return Rotation(angle(t));
#else
  return Rotation::about_axis(s_.axis, angle(t));
#endif
}

WallMotionState WallMotion::at(const Real t) const {
  WallMotionState m;
  m.pivot = s_.pivot;
  std::tie(m.displacement, m.velocity) = translation(t);
  if (s_.rotation == WallMotionSpec::Rotation::none) return m;
  m.rotation = matrix(t);
#if MPSFSI_DIM == 2
  m.spin = angular_velocity(t);
#else
  m.spin = angular_velocity(t) * s_.axis;
#endif
  return m;
}

}  // namespace mpsfsi
