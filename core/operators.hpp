// MPS differential operators over a neighbour list (seed 004 §3): particle number density (eq. 8),
// gradient (eq. 9) and its stable minimum-value variant, divergence (eq. 10), Laplacian (eq. 12) and
// the corrected gradient (eq. 14-15), in MPSFSI_DIM dimensions (d = dim; n0 and lambda come from
// lattice_constants() of the same dimension).
//
// The operators are per-particle kernels (`*_at(x, nl, re, i, ..., accept)`: one particle i, its
// neighbours in `nl` within re, those that `accept(j)`), apart from the loops that apply them: the
// whole-array functions at the end are the plain loop drivers, and the fluid, the solid and the coupling
// call the same kernels from their own loops with their own choice of neighbours (a fluid's pressure rows,
// a solid's bonds). A list built for a larger radius may be used with a smaller re (w vanishes beyond re).
#pragma once

#include "core/kernel.hpp"
#include "core/neighbours.hpp"
#include "core/types.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <vector>

namespace mpsfsi {

/// Every neighbour counts (the default selection of the kernels).
struct AllNeighbours {
  constexpr bool operator()(std::size_t) const { return true; }
};

/// The pair loop every operator is built on: f(j, r_ij, |r_ij|^2, w_ij) for every neighbour j of particle i
/// listed in row `row` of `nl` inside the support re (w of eq. 7) that `accept(j)`. A list of all particles
/// has row i for particle i (for_each_pair); one of a few particles (build_neighbour_list_of) has its own rows.
template <class Accept, class F>
inline void for_each_pair_in_row(const std::vector<Vec>& x, const NeighbourList& nl, const Real re,
                                 const std::size_t row, const std::size_t i, Accept&& accept, F&& f) {
  assert(re <= nl.radius * (1 + 1e-12));
  const bool test_support = !(nl.support_only && re == nl.radius);
  const Vec xi = x[i];
  for (std::size_t k = nl.begin(row); k < nl.end(row); ++k) {
    const auto j = static_cast<std::size_t>(nl.index[k]);
    if (!accept(j)) continue;
    const Vec rij = x[j] - xi;
    const Real r2 = rij.squaredNorm();
    if (test_support && !in_support(r2, re)) continue;
    f(j, rij, r2, re / std::sqrt(r2) - 1.0);
  }
}

template <class Accept, class F>
inline void for_each_pair(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const std::size_t i,
                          Accept&& accept, F&& f) {
  for_each_pair_in_row(x, nl, re, i, i, accept, f);
}

/// n_i = sum_j w(|r_ij|) (eq. 8), and N_i, the number of neighbours with w > 0 (free surface, seed 004 §4.3).
struct DensityAndCount {
  Real n = 0;
  int count = 0;
};
template <class Accept = AllNeighbours>
inline DensityAndCount number_density_at(const std::vector<Vec>& x, const NeighbourList& nl, const Real re,
                                         const std::size_t i, Accept&& accept = {}) {
  DensityAndCount d;
  for_each_pair(x, nl, re, i, accept, [&](std::size_t, const Vec&, Real, const Real w) {
    d.n += w;
    ++d.count;
  });
  return d;
}

/// The derivative of n_i (eq. 8, with the kernel k) with respect to the position of a neighbour k at
/// r_ik = x_k - x_i inside the support (|r_ik|^2 = r2): dn_i/dx_k = w'(r) r_ik / r (-re r_ik / r^3 for the MPS
/// weight).
inline Vec density_derivative_pair(const Vec& r_ik, const Real r2, const Real re,
                                   const DensityKernel kernel = DensityKernel::mps) {
  const Real r = std::sqrt(r2);
  return (kernel_at(kernel, r, re).dw / r) * r_ik;
}

/// dn_i/dx_i = -sum_k dn_i/dx_k over the neighbours k of i that `accept` (eq. 8 moved with particle i).
template <class Accept = AllNeighbours>
inline Vec density_derivative_self_at(const std::vector<Vec>& x, const NeighbourList& nl, const Real re,
                                      const std::size_t i, Accept&& accept = {},
                                      const DensityKernel kernel = DensityKernel::mps) {
  Vec s = Vec::Zero();
  for_each_pair(x, nl, re, i, accept, [&](std::size_t, const Vec& rij, const Real r2, Real) {
    s -= density_derivative_pair(rij, r2, re, kernel);
  });
  return s;
}

/// The smallest of phi_i and the phi_j of i's neighbours (the reference of the stable gradient).
template <class Accept = AllNeighbours>
inline Real min_value_at(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const std::size_t i,
                         const std::vector<Real>& phi, Accept&& accept = {}) {
  Real m = phi[i];
  for_each_pair(x, nl, re, i, accept, [&](const std::size_t j, const Vec&, Real, Real) { m = std::min(m, phi[j]); });
  return m;
}

/// sum_j (phi_j - phi_ref) r_ij / |r_ij|^2 w_ij: times d/n0 the gradient of eq. 9 (phi_ref = phi_i), or its
/// stable variant with phi_ref = min_value_at (every pair term points the same way for a pressure;
/// Koshizuka & Oka 1996).
template <class Accept = AllNeighbours>
inline Vec gradient_sum_at(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const std::size_t i,
                           const std::vector<Real>& phi, const Real phi_ref, Accept&& accept = {}) {
  Vec g = Vec::Zero();
  for_each_pair(x, nl, re, i, accept, [&](const std::size_t j, const Vec& rij, const Real r2, const Real w) {
    g += (phi[j] - phi_ref) / r2 * w * rij;
  });
  return g;
}

/// sum_j (v_j - v_i) . r_ij / |r_ij|^2 w_ij: times d/n0 the divergence of eq. 10.
template <class Accept = AllNeighbours>
inline Real divergence_sum_at(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const std::size_t i,
                              const std::vector<Vec>& v, Accept&& accept = {}) {
  Real s = 0;
  for_each_pair(x, nl, re, i, accept, [&](const std::size_t j, const Vec& rij, const Real r2, const Real w) {
    s += (v[j] - v[i]).dot(rij) / r2 * w;
  });
  return s;
}

/// sum_j (phi_j - phi_i) w_ij for a scalar or vector field: times 2d / (lambda n0) the Laplacian of eq. 12.
template <class T, class Accept = AllNeighbours>
inline T laplacian_sum_at(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const std::size_t i,
                          const std::vector<T>& phi, Accept&& accept = {}) {
  T s = phi[i] - phi[i];  // zero of T (scalar or vector)
  const T phi_i = phi[i];
  for_each_pair(x, nl, re, i, accept, [&](const std::size_t j, const Vec&, Real, const Real w) { s += (phi[j] - phi_i) * w; });
  return s;
}

/// The corrected gradient of eq. 14-15 at i: A_i^-1 b_i with A_i = sum_j w r_ij r_ij^T / |r_ij|^2 (the
/// corrective matrix, eq. 15, without its 1/n0, which cancels) and b_i = sum_j (phi_j - phi_i) w r_ij / |r_ij|^2.
/// `singular` is the scale-free bound below which A_i counts as singular: det A_i <= singular tr(A_i)^d; then
/// `n_i`, the particle's own number density, is returned with `ok` false and `b` for a fallback to eq. 9.
struct CorrectedGradient {
  Vec gradient = Vec::Zero();  ///< A_i^-1 b_i where ok
  Vec b = Vec::Zero();
  Real n_i = 0;
  bool ok = false;
};
template <class Accept = AllNeighbours>
inline CorrectedGradient corrected_gradient_at(const std::vector<Vec>& x, const NeighbourList& nl, const Real re,
                                               const std::size_t i, const std::vector<Real>& phi, const Real singular,
                                               Accept&& accept = {}) {
  CorrectedGradient c;
  Mat m = Mat::Zero();
  for_each_pair(x, nl, re, i, accept, [&](const std::size_t j, const Vec& rij, const Real r2, const Real w) {
    m += (w / r2) * rij * rij.transpose();
    c.b += (phi[j] - phi[i]) * (w / r2) * rij;
    c.n_i += w;
  });
  if (c.n_i <= 0) return c;  // isolated particle
  const Real det = m.determinant();
  const Real tr = m.trace();
  Real threshold = singular * tr;  // singular tr^d, as ((singular tr) tr) ... so that 2D keeps its rounding
  for (int a = 1; a < dim; ++a) threshold *= tr;
  if (det > threshold) {
    c.gradient = m.inverse() * c.b;
    c.ok = true;
  }
  return c;
}

// Loop drivers: each kernel applied to every particle with every neighbour.

/// n_i = sum_j w(|r_ij|) (eq. 8).
void number_density(const std::vector<Vec>& x, const NeighbourList& nl, Real re, std::vector<Real>& n);
/// Number of neighbours with non-zero weight, N_i (for the free-surface check of seed 004 §4.3).
void neighbour_count(const std::vector<Vec>& x, const NeighbourList& nl, Real re, std::vector<int>& count);

/// grad phi_i = d/n0 sum_j (phi_j - phi_i) r_ij / |r_ij|^2 w (eq. 9).
void gradient(const std::vector<Vec>& x, const NeighbourList& nl, Real re, Real n0,
              const std::vector<Real>& phi, std::vector<Vec>& out);
/// Stable variant: phi_i replaced by the smallest phi among i and its neighbours, so every pair
/// term points the same way for a pressure (Koshizuka & Oka 1996).
void gradient_min(const std::vector<Vec>& x, const NeighbourList& nl, Real re, Real n0,
                  const std::vector<Real>& phi, std::vector<Vec>& out);
/// div v_i = d/n0 sum_j (v_j - v_i) . r_ij / |r_ij|^2 w (eq. 10).
void divergence(const std::vector<Vec>& x, const NeighbourList& nl, Real re, Real n0,
                const std::vector<Vec>& v, std::vector<Real>& out);
/// lap phi_i = 2d/(lambda n0) sum_j (phi_j - phi_i) w (eq. 12).
void laplacian(const std::vector<Vec>& x, const NeighbourList& nl, Real re, Real n0, Real lambda,
               const std::vector<Real>& phi, std::vector<Real>& out);
void laplacian(const std::vector<Vec>& x, const NeighbourList& nl, Real re, Real n0, Real lambda,
               const std::vector<Vec>& v, std::vector<Vec>& out);

/// Singularity bound of the corrected gradient where a caller has no reason for another: det A <= 1e-10 tr^d.
inline constexpr Real corrected_gradient_singular = 1e-10;

/// Corrected gradient (eq. 14-15): exact for linear fields wherever A_i exists; falls back to eq. 9
/// with the particle's own n_i where it does not.
void corrected_gradient(const std::vector<Vec>& x, const NeighbourList& nl, Real re,
                        const std::vector<Real>& phi, std::vector<Vec>& out);

}  // namespace mpsfsi
