// Lattice constants of the MPS kernel on a perfect lattice of spacing dp (seed 004 eq. 8, 13): the square
// lattice in 2D, the simple cubic lattice in 3D; n0 of the other density kernels.
#include "core/kernel.hpp"

#include <cmath>
#include <stdexcept>

namespace mpsfsi {

LatticeConstants lattice_constants(const Real dp, const Real re) {
  if (!(dp > 0) || !(re > 0)) throw std::invalid_argument("lattice_constants: dp and re must be positive");
  LatticeConstants c;
  c.dp = dp;
  c.re = re;
  // Sum over the lattice points dp (i_0, .., i_{d-1}) with |i_a| <= m, the last axis fastest (in 2D:
  // for i, for j), skipping the centre: the square lattice in 2D, the simple cubic lattice in 3D.
  const int m = static_cast<int>(std::ceil(re / dp)) + 1;
  Real sum_w = 0, sum_r2w = 0;
  IVec p = IVec::Constant(-m);
  for (;;) {
    const int i2 = p.squaredNorm();
    if (i2 != 0) {
      const Real r = dp * std::sqrt(Real(i2));
      const Real w = weight(r, re);  // eq. 7
      if (w > 0) {
        sum_w += w;
        sum_r2w += r * r * w;
        ++c.n_neighbours;
      }
    }
    int a = dim - 1;
    for (; a >= 0; --a) {
      if (++p[a] <= m) break;
      p[a] = -m;
    }
    if (a < 0) break;
  }
  c.n0 = sum_w;
  c.lambda = sum_r2w / sum_w;
  return c;
}

KernelSums lattice_sums(const DensityKernel k, const Real dp, const Real re) {
  if (!(dp > 0) || !(re > 0)) throw std::invalid_argument("lattice_sums: dp and re must be positive");
  const int m = static_cast<int>(std::ceil(re / dp)) + 1;
  KernelSums sum;
  IVec p = IVec::Constant(-m);
  for (;;) {
    const int i2 = p.squaredNorm();
    if (i2 != 0) {
      const Real r = dp * std::sqrt(Real(i2));
      const KernelValue kv = kernel_at(k, r, re);
      sum.n0 += kv.w;
      sum.c -= kv.dw * r;
    }
    int a = dim - 1;
    for (; a >= 0; --a) {
      if (++p[a] <= m) break;
      p[a] = -m;
    }
    if (a < 0) break;
  }
  return sum;
}

}  // namespace mpsfsi
