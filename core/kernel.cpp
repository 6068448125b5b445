// Lattice constants of the MPS kernel on a perfect square lattice (seed 004 eq. 8, 13).
#include "core/kernel.hpp"

#include <cmath>
#include <stdexcept>

namespace mpsfsi {

LatticeConstants lattice_constants(const Real dp, const Real re) {
  if (!(dp > 0) || !(re > 0)) throw std::invalid_argument("lattice_constants: dp and re must be positive");
  LatticeConstants c;
  c.dp = dp;
  c.re = re;
  const int m = static_cast<int>(std::ceil(re / dp)) + 1;
  Real sum_w = 0, sum_r2w = 0;
  for (int i = -m; i <= m; ++i) {
    for (int j = -m; j <= m; ++j) {
      if (i == 0 && j == 0) continue;
      const Real r = dp * std::sqrt(Real(i * i + j * j));
      const Real w = weight(r, re);
      if (w <= 0) continue;
      sum_w += w;
      sum_r2w += r * r * w;
      ++c.n_neighbours;
    }
  }
  c.n0 = sum_w;
  c.lambda = sum_r2w / sum_w;
  return c;
}

}  // namespace mpsfsi
