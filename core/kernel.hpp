// The MPS weight function (seed 004 eq. 7) and the lattice constants n0, N0 and lambda
// (eq. 8, 13) that every operator is normalised with.
#pragma once

#include "core/types.hpp"

namespace mpsfsi {

/// Pairs closer than re by less than this relative margin count as outside the support, so that
/// lattice neighbours at exactly r = re (w = 0) are not counted because of round-off.
inline constexpr Real support_margin = 1e-9;

/// True when a pair at squared distance r2 > 0 lies inside the support of radius re.
inline bool in_support(const Real r2, const Real re) { return r2 > 0 && r2 < re * re * (1.0 - support_margin); }

/// Weight w(r) = re/r - 1 for 0 < r < re, else 0 (seed 004 eq. 7).
inline Real weight(const Real r, const Real re) { return in_support(r * r, re) ? re / r - 1.0 : 0.0; }

/// Constants of a perfect lattice of spacing dp (square in 2D, simple cubic in 3D) for an effective
/// radius re, taken at an interior particle: n0 = sum w (eq. 8), N0 = number of neighbours with w > 0, and
/// lambda = sum r^2 w / sum w (eq. 13).
struct LatticeConstants {
  Real dp = 0;
  Real re = 0;
  Real n0 = 0;
  int n_neighbours = 0;
  Real lambda = 0;
};

LatticeConstants lattice_constants(Real dp, Real re);

}  // namespace mpsfsi
