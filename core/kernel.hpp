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

/// The kernel of a number density n_i = sum_j w(r_ij): the MPS weight (eq. 7), or Wendland's C2 kernel
/// w(r) = (1 - q)^4 (1 + 4 q), q = r / re (Wendland 1995, docs/references.md), which is smooth at r = 0 and
/// at re. The exact projection's pair forces (p_i + p_j) w'(r) e_ij leave the square lattice under pressure
/// without shear stiffness with the MPS weight (columns sliding past each other lower the energy), and
/// with a small positive one with Wendland's (docs/validation.md, ## Fluid).
enum class DensityKernel : std::uint8_t { mps, wendland };

/// w(r) and dw/dr of a kernel, zero outside the support.
struct KernelValue {
  Real w = 0;
  Real dw = 0;
};

inline KernelValue kernel_at(const DensityKernel k, const Real r, const Real re) {
  if (!in_support(r * r, re)) return {};
  if (k == DensityKernel::mps) return {re / r - 1.0, -re / (r * r)};
  const Real q = r / re, a = 1.0 - q, a3 = a * a * a;
  return {a3 * a * (1.0 + 4.0 * q), -20.0 * q * a3 / re};
}

/// Sums of a kernel over the lattice of lattice_constants (square in 2D, simple cubic in 3D), at an interior
/// particle: n0 = sum_j w(r_j), and c = sum_j -w'(r_j) r_j (the scale of the pair forces' gradient: for a linear
/// p, sum_j (p_i + p_j) w'(r_ij) e_ij = -(c / d) grad p; n0 + N0 for the MPS weight).
struct KernelSums {
  Real n0 = 0;
  Real c = 0;
};
KernelSums lattice_sums(DensityKernel k, Real dp, Real re);

}  // namespace mpsfsi
