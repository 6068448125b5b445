// Rigid rotations for the tank motion now and the rigid/elastic solid later (issue 14, item 4).
// RotationT<2> is a scalar angle (counter-clockwise about z); RotationT<3> a unit quaternion with a
// rotation-vector interface. Both offer compose (a * b: first b, then a), apply, inverse, the matrix
// and the rotation vector (log), and exist in every build (they use their own fixed-size types), so
// both are unit tested in the 2D and the 3D build. `Rotation` is the one of the build's dimension.
#pragma once

#include "core/types.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace mpsfsi {

template <int D>
class RotationT;

/// A plane rotation by `angle` [rad], counter-clockwise positive.
template <>
class RotationT<2> {
 public:
  using V = Eigen::Matrix<Real, 2, 1>;
  using M = Eigen::Matrix<Real, 2, 2>;
  /// The rotation vector's type: the angle itself.
  using Vector = Real;

  RotationT() = default;
  explicit RotationT(const Real angle) : angle_(angle) {}
  /// Rotation by theta about the z axis (the only axis in 2D).
  static RotationT about_z(const Real theta) { return RotationT(theta); }
  /// From a rotation vector (in 2D the angle).
  static RotationT from_vector(const Real phi) { return RotationT(phi); }

  Real angle() const { return angle_; }
  /// Rotation vector (the angle; not reduced to (-pi, pi]).
  Real log() const { return angle_; }
  /// R = [cos -sin; sin cos].
  M matrix() const {
    const Real c = std::cos(angle_), s = std::sin(angle_);
    M r;
    r << c, -s, s, c;
    return r;
  }
  V apply(const V& v) const { return matrix() * v; }
  RotationT inverse() const { return RotationT(-angle_); }
  /// Composition: (a * b).apply(v) = a.apply(b.apply(v)); plane rotations commute (angles add).
  RotationT operator*(const RotationT& b) const { return RotationT(angle_ + b.angle_); }

 private:
  Real angle_ = 0;
};

/// A rotation in space, stored as a unit quaternion.
template <>
class RotationT<3> {
 public:
  using V = Eigen::Matrix<Real, 3, 1>;
  using M = Eigen::Matrix<Real, 3, 3>;
  /// The rotation vector's type: axis times angle [rad].
  using Vector = V;

  RotationT() = default;
  explicit RotationT(const Eigen::Quaternion<Real>& q) : q_(q.normalized()) {}
  /// Rotation by theta about the z axis (the tank roll axis in 3D).
  static RotationT about_z(const Real theta) { return RotationT(Eigen::Quaternion<Real>(Eigen::AngleAxis<Real>(theta, V::UnitZ()))); }
  /// Rotation by theta about the unit vector `axis` (right-handed).
  static RotationT about_axis(const V& axis, const Real theta) {
    return RotationT(Eigen::Quaternion<Real>(Eigen::AngleAxis<Real>(theta, axis.normalized())));
  }
  /// From a rotation vector phi: angle |phi| about phi / |phi| (the identity for phi = 0).
  static RotationT from_vector(const V& phi) {
    const Real a = phi.norm();
    if (!(a > 0)) return RotationT();
    return RotationT(Eigen::Quaternion<Real>(Eigen::AngleAxis<Real>(a, phi / a)));
  }

  const Eigen::Quaternion<Real>& quaternion() const { return q_; }
  /// Rotation vector: axis times angle, angle in [0, pi].
  V log() const {
    const Eigen::AngleAxis<Real> aa(q_);  // Eigen returns the angle in [0, pi]
    return aa.angle() * aa.axis();
  }
  M matrix() const { return q_.toRotationMatrix(); }
  V apply(const V& v) const { return q_ * v; }
  RotationT inverse() const { return RotationT(q_.conjugate()); }
  /// Composition: (a * b).apply(v) = a.apply(b.apply(v)).
  RotationT operator*(const RotationT& b) const { return RotationT(q_ * b.q_); }

 private:
  Eigen::Quaternion<Real> q_ = Eigen::Quaternion<Real>::Identity();
};

/// The rotation type of the build's dimension.
using Rotation = RotationT<dim>;

/// Angular quantity omega e_z of a rotation about the z axis at rate omega: omega in 2D, (0, 0, omega)
/// in 3D.
#if MPSFSI_DIM == 2
inline Real about_z(const Real omega) { return omega; }
#else
inline Vec about_z(const Real omega) { return Vec(0, 0, omega); }
#endif

}  // namespace mpsfsi
