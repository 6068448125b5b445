// The loop drivers of the MPS operators (core/operators.hpp): each per-particle kernel applied to every
// particle with all its neighbours (seed 004 eq. 8-15).
#include "core/operators.hpp"

namespace mpsfsi {

void number_density(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, std::vector<Real>& n) {
  n.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) n[i] = number_density_at(x, nl, re, i).n;
}

void neighbour_count(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, std::vector<int>& count) {
  count.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) count[i] = number_density_at(x, nl, re, i).count;
}

void gradient(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
              const std::vector<Real>& phi, std::vector<Vec>& out) {
  out.resize(x.size());
  const Real c = dim / n0;
  for (std::size_t i = 0; i < x.size(); ++i) out[i] = c * gradient_sum_at(x, nl, re, i, phi, phi[i]);
}

void gradient_min(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
                  const std::vector<Real>& phi, std::vector<Vec>& out) {
  out.resize(x.size());
  const Real c = dim / n0;
  for (std::size_t i = 0; i < x.size(); ++i)
    out[i] = c * gradient_sum_at(x, nl, re, i, phi, min_value_at(x, nl, re, i, phi));
}

void divergence(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
                const std::vector<Vec>& v, std::vector<Real>& out) {
  out.resize(x.size());
  const Real c = dim / n0;
  for (std::size_t i = 0; i < x.size(); ++i) out[i] = c * divergence_sum_at(x, nl, re, i, v);
}

void laplacian(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
               const Real lambda, const std::vector<Real>& phi, std::vector<Real>& out) {
  out.resize(x.size());
  const Real c = 2.0 * dim / (lambda * n0);
  for (std::size_t i = 0; i < x.size(); ++i) out[i] = c * laplacian_sum_at(x, nl, re, i, phi);
}

void laplacian(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
               const Real lambda, const std::vector<Vec>& v, std::vector<Vec>& out) {
  out.resize(x.size());
  const Real c = 2.0 * dim / (lambda * n0);
  for (std::size_t i = 0; i < x.size(); ++i) out[i] = c * laplacian_sum_at(x, nl, re, i, v);
}

void corrected_gradient(const std::vector<Vec>& x, const NeighbourList& nl, const Real re,
                        const std::vector<Real>& phi, std::vector<Vec>& out) {
  out.resize(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const CorrectedGradient c = corrected_gradient_at(x, nl, re, i, phi, corrected_gradient_singular);
    if (c.ok)
      out[i] = c.gradient;  // eq. 14 with A from eq. 15
    else if (c.n_i > 0)
      out[i] = (dim / c.n_i) * c.b;  // eq. 9 with the particle's own n_i
    else
      out[i].setZero();  // isolated particle: no gradient
  }
}

}  // namespace mpsfsi
