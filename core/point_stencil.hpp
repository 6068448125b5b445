// Stencils that tie a point (a seismic source, a receiver) to the particles around it (issue 6,
// seed 000 §3). The particles within `radius` of the point are weighted by a smooth compact kernel
// (Wendland C2, w(q) = (1 - q)^4 (1 + 4 q), q = r / radius), and the weights are corrected to first
// order (moving least squares) so that the stencil is exact for linear fields wherever the point is:
// inside the lattice, between particles, or at a free surface where the neighbourhood is one-sided.
//
//  * interpolation_stencil: phi_k with sum phi_k = 1 and sum phi_k d_k = 0 (d_k = x_k - point).
//    A receiver reads u(point) = sum phi_k u_k (exact for linear u); a point force F is spread as
//    F_k = phi_k F (net force F, no moment about the point).
//  * moment_stencil: vectors g_k = w_k C^-1 (d_k - dbar), dbar = sum w d / sum w,
//    C = sum w (d - dbar)(d - dbar)^T, so that sum g_k = 0 and sum d_k g_k^T = I: forces M g_k are the
//    discrete equivalent of the body force -M grad(delta) of an isotropic line moment M delta_ij
//    (an explosive line source of moment M [N m / m]): no net force, moment tensor M I, no torque.
#pragma once

#include "core/types.hpp"

#include <cstddef>
#include <vector>

namespace mpsfsi {

/// Wendland C2 kernel (unnormalised): (1 - q)^4 (1 + 4 q) for q = r / radius < 1, else 0.
Real stencil_weight(Real r, Real radius);

/// Particles of a stencil (indices into the positions it was built from) and their scalar weights.
struct PointStencil {
  std::vector<std::size_t> index;
  std::vector<Real> weight;
};

/// Vector stencil: particle indices and per-particle force vectors.
struct VectorStencil {
  std::vector<std::size_t> index;
  std::vector<Vec> value;
};

/// Linear-exact interpolation weights at `point` over the particles `candidates` (indices into x)
/// that lie within `radius`. Throws std::invalid_argument when fewer than three non-collinear (2D) /
/// four non-coplanar (3D) particles are in range (the linear fit is then undetermined).
PointStencil interpolation_stencil(const std::vector<Vec>& x, const std::vector<std::size_t>& candidates,
                                   const Vec& point, Real radius);

/// Force pattern of a unit isotropic moment at `point` (see above). Same range rules and errors.
VectorStencil moment_stencil(const std::vector<Vec>& x, const std::vector<std::size_t>& candidates, const Vec& point,
                             Real radius);

}  // namespace mpsfsi
