// Prescribed rigid motion of one wall body on its own (a gate that is lifted, a piston or flap wave maker, a
// paddle): a translation d(t) and a rotation theta(t) about a pivot carried by the translation,
//   x(t) = pivot + d(t) + R(theta(t)) (x0 - pivot),      v(t) = d'(t) + theta'(t) e x (x(t) - pivot - d(t)),
// e = e_z in 2D, the rotation axis in 3D. Each part is a formula of tau = min(t, stop) - start (nothing before
// `start`, frozen after `stop`):
//   translation `velocity`: d' = V r(tau), r the smooth ramp of core/ramp.hpp over `ramp` (a constant velocity
//                           after it), d its exact integral;
//   translation `sine`:     d = A r(tau) sin(2 pi tau / T);
//   rotation `sine`:        theta = a r(tau) sin(2 pi tau / T_r);
//   translation `table`:    d = r(tau) (s(tau) - s(0)) e, s a measured displacement along the direction e
//                           (core/tank_motion.hpp TableSeries: linear between the rows, the velocity its centred
//                           difference over a window), table times counted from `start`;
//   rotation `table`:       theta = r(tau) (a(tau) - a(0)), a a measured angle, likewise.
// A table moves the wall by its change since tau = 0, so that the wall starts where its body is.
// The fluid moves each wall body's particles with its motion (fluid/fluid_core.cpp); knows nothing of case files
// (io/case_file.cpp fills WallMotionSpec).
#pragma once

#include "core/rotation.hpp"
#include "core/tank_motion.hpp"
#include "core/types.hpp"

#include <limits>
#include <utility>
#include <vector>

namespace mpsfsi {

struct WallMotionSpec {
  enum class Translation { none, velocity, sine, table };
  enum class Rotation { none, sine, table };
  Translation translation = Translation::none;
  Vec velocity = Vec::Zero();   ///< velocity: the velocity after the ramp [m/s]
  Vec amplitude = Vec::Zero();  ///< sine: the displacement's amplitude [m]
  Real period = 1;              ///< sine: the translation's period [s]
  Vec direction = Vec::UnitX(); ///< table: the translation's direction, normalised
  std::vector<Real> table_time;   ///< translation table: times [s] from `start`, increasing ...
  std::vector<Real> table_value;  ///< ... and the displacement along `direction` [m]
  Real table_half_window = 0.025; ///< translation table: the velocity's centred-difference half window [s]
  Rotation rotation = Rotation::none;
  Vec pivot = Vec::Zero();      ///< the rotation's centre at rest [m]
#if MPSFSI_DIM == 3
  Vec axis = Vec::UnitZ();      ///< 3D: the rotation axis through the pivot, normalised
#endif
  Real angle_amplitude = 0;     ///< rotation sine: amplitude [rad]
  Real angle_period = 1;        ///< rotation sine: period [s]
  std::vector<Real> angle_time;   ///< rotation table: times [s] from `start`, increasing ...
  std::vector<Real> angle_value;  ///< ... and the angle [rad]
  Real angle_half_window = 0.025; ///< rotation table: the angular velocity's centred-difference half window [s]
  Real start = 0;               ///< the motion starts [s]
  Real ramp = 0;                ///< the velocity (velocity) or the amplitudes (sine) rise over this time [s]
  Real stop = std::numeric_limits<Real>::infinity();  ///< the motion stops, the wall stays where it is [s]
  bool moving() const { return translation != Translation::none || rotation != Rotation::none; }
};

/// A wall's motion at one time: what places its points and gives their velocities, computed once for all of them.
struct WallMotionState {
  Vec pivot = Vec::Zero();         ///< the pivot at rest
  Vec displacement = Vec::Zero();  ///< d(t)
  Vec velocity = Vec::Zero();      ///< d'(t)
  Mat rotation = Mat::Identity();  ///< R(theta(t))
  Angular spin = angular_zero();   ///< theta'(t) e
  /// Where the wall point x0 (at rest) is, and its velocity there.
  Vec place(const Vec& x0) const { return pivot + displacement + rotation * (x0 - pivot); }
  Vec velocity_of(const Vec& x0) const { return velocity + cross(spin, Vec(rotation * (x0 - pivot))); }
};

class WallMotion {
 public:
  WallMotion() = default;
  /// Throws std::invalid_argument for a table that TableSeries refuses.
  explicit WallMotion(const WallMotionSpec& spec);
  bool moving() const { return s_.moving(); }
  const WallMotionSpec& spec() const { return s_; }

  /// d(t) and d'(t).
  Vec displacement(Real t) const;
  Vec translation_velocity(Real t) const;
  /// theta(t) [rad] and theta'(t) [rad/s].
  Real angle(Real t) const;
  Real angular_velocity(Real t) const;
  /// R(theta(t)), as a matrix and as a rotation.
  Mat matrix(Real t) const;
  Rotation rotation(Real t) const;
  /// The motion at t.
  WallMotionState at(Real t) const;
  /// Where the wall point x0 (at rest) is at t, and its velocity there (at(t) for one point).
  Vec place(const Vec& x0, const Real t) const { return at(t).place(x0); }
  Vec velocity(const Vec& x0, const Real t) const { return at(t).velocity_of(x0); }

 private:
  /// d(t) and d'(t) together.
  std::pair<Vec, Vec> translation(Real t) const;
  /// tau = min(t, stop) - start, and whether the motion is under way (start < t < stop).
  Real tau(Real t) const;
  bool running(Real t) const { return t > s_.start && t < s_.stop; }
  WallMotionSpec s_;
  TableSeries translation_table_, angle_table_;  ///< the tables, when the motion has them
};

}  // namespace mpsfsi
