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
  }
  return {zero, zero};
}

Vec WallMotion::displacement(const Real t) const { return translation(t).first; }

Vec WallMotion::translation_velocity(const Real t) const { return translation(t).second; }

Real WallMotion::angle(const Real t) const {
  if (s_.rotation == WallMotionSpec::Rotation::none) return 0;
  return ramped_sine(s_.angle_amplitude, s_.angle_period, tau(t), s_.ramp).first;
}

Real WallMotion::angular_velocity(const Real t) const {
  if (s_.rotation == WallMotionSpec::Rotation::none || !running(t)) return 0;
  return ramped_sine(s_.angle_amplitude, s_.angle_period, tau(t), s_.ramp).second;
}

Mat WallMotion::matrix(const Real t) const {
  if (s_.rotation == WallMotionSpec::Rotation::none) return Mat::Identity();
#if MPSFSI_DIM == 2
  return Rotation(angle(t)).matrix();
#else
  return Rotation::about_axis(s_.axis, angle(t)).matrix();
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
