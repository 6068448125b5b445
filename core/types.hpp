// Basic types of mpsfsi: the compile-time spatial dimension, scalars, small fixed-size vectors
// and matrices (Eigen), and the index types shared with the distributed pressure solve.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#ifndef MPSFSI_DIM
#define MPSFSI_DIM 2
#endif

namespace mpsfsi {

/// Spatial dimension d of the build (seed 004 uses d in eq. 9-12).
inline constexpr int dim = MPSFSI_DIM;
static_assert(dim == 2, "mpsfsi: only the 2D build is implemented");

using Real = double;

/// pi (C++17 has no std::numbers).
inline constexpr Real pi = 3.14159265358979323846;
using Vec = Eigen::Matrix<Real, dim, 1>;
using Mat = Eigen::Matrix<Real, dim, dim>;

/// Global particle id; same type as Tpetra's GlobalOrdinal in Debian's Trilinos (long long).
using GlobalId = long long;
/// Index of a particle on this rank.
using LocalIndex = std::int32_t;

/// 2D cross product (z component) of two vectors.
inline Real cross(const Vec& a, const Vec& b) { return a[0] * b[1] - a[1] * b[0]; }

}  // namespace mpsfsi
