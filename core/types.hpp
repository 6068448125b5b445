// Basic types of mpsfsi: the compile-time spatial dimension, scalars, small fixed-size vectors
// and matrices (Eigen), the index types shared with the distributed pressure solve, and the
// dimension-aware cross product (a scalar in 2D, a vector in 3D).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <type_traits>

#ifndef MPSFSI_DIM
#define MPSFSI_DIM 2
#endif

namespace mpsfsi {

/// Spatial dimension d of the build (seed 004 uses d in eq. 9-12). CMake accepts 2 or 3.
inline constexpr int dim = MPSFSI_DIM;
static_assert(dim == 2 || dim == 3, "mpsfsi: MPSFSI_DIM must be 2 or 3");

using Real = double;

/// pi (C++17 has no std::numbers).
inline constexpr Real pi = 3.14159265358979323846;
using Vec = Eigen::Matrix<Real, dim, 1>;
using Mat = Eigen::Matrix<Real, dim, dim>;
/// Integer cell (lattice) coordinates, one per axis.
using IVec = Eigen::Matrix<int, dim, 1>;

/// Global particle id; same type as Tpetra's GlobalOrdinal in Debian's Trilinos (long long).
using GlobalId = long long;
/// Index of a particle on this rank.
using LocalIndex = std::int32_t;

/// Angular quantities (rotation vector, angular velocity, torque, a x b): the z component (a scalar)
/// in 2D, a vector in 3D.
using Angular = std::conditional_t<dim == 2, Real, Vec>;

/// Components of an angular quantity (1 in 2D, 3 in 3D).
inline constexpr int n_angular = dim == 2 ? 1 : 3;
/// The zero angular quantity (Eigen's fixed-size vectors are not zeroed by value-initialisation), and the
/// components of one as contiguous reals (for packing and reductions).
#if MPSFSI_DIM == 2
inline constexpr Real angular_zero() { return 0; }
inline Real* angular_data(Real& a) { return &a; }
#else
inline Vec angular_zero() { return Vec::Zero(); }
inline Real* angular_data(Vec& a) { return a.data(); }
#endif

/// Cross product a x b: in 2D its z component a_x b_y - a_y b_x (a scalar), in 3D the vector.
#if MPSFSI_DIM == 2
inline Real cross(const Vec& a, const Vec& b) { return a[0] * b[1] - a[1] * b[0]; }
/// 2D only: w e_z x r for a scalar (z) angular quantity w, the in-plane vector w (-r_y, r_x).
/// (In 3D w is a Vec and cross(w, r) above is the same product.)
inline Vec cross(const Real w, const Vec& r) { return w * Vec(-r[1], r[0]); }
#else
inline Vec cross(const Vec& a, const Vec& b) {
  return Vec(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
}
#endif

}  // namespace mpsfsi
