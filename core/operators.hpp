// MPS differential operators over a neighbour list (seed 004 §3): particle number density (eq. 8),
// gradient (eq. 9) and its stable minimum-value variant, divergence (eq. 10), Laplacian (eq. 12) and
// the corrected gradient (eq. 14-15). Each is one loop over the neighbour list; a list built for a
// larger radius may be used with a smaller re (the weight vanishes beyond re). All of them work in
// MPSFSI_DIM dimensions (d = dim); n0 and lambda come from lattice_constants() of the same dimension.
#pragma once

#include "core/neighbours.hpp"
#include "core/types.hpp"

#include <vector>

namespace mpsfsi {

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

/// Corrected gradient (eq. 14-15): exact for linear fields wherever A_i exists; falls back to eq. 9
/// with the particle's own n_i where it does not.
void corrected_gradient(const std::vector<Vec>& x, const NeighbourList& nl, Real re,
                        const std::vector<Real>& phi, std::vector<Vec>& out);

}  // namespace mpsfsi
