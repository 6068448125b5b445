// MPS differential operators (seed 004 eq. 8-15), one neighbour-list loop each; dimension-generic
// (d = dim in eq. 9, 10, 12; A_i of eq. 15 is d x d).
#include "core/operators.hpp"

#include "core/kernel.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cassert>
#include <cmath>

namespace mpsfsi {

namespace {
/// Call f(j, r_ij, |r_ij|^2, w_ij) for every neighbour j of i with non-zero weight.
template <class F>
inline void for_each_pair(const std::vector<Vec>& x, const NeighbourList& nl, const Real re,
                          const std::size_t i, F&& f) {
  assert(re <= nl.radius * (1 + 1e-12));
  const Vec xi = x[i];
  for (std::size_t k = nl.begin(i); k < nl.end(i); ++k) {
    const auto j = static_cast<std::size_t>(nl.index[k]);
    const Vec rij = x[j] - xi;
    const Real r2 = rij.squaredNorm();
    if (!in_support(r2, re)) continue;
    f(j, rij, r2, re / std::sqrt(r2) - 1.0);
  }
}
}  // namespace

void number_density(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, std::vector<Real>& n) {
  n.assign(x.size(), 0.0);
  for (std::size_t i = 0; i < x.size(); ++i)
    for_each_pair(x, nl, re, i, [&](std::size_t, const Vec&, Real, Real w) { n[i] += w; });
}

void neighbour_count(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, std::vector<int>& count) {
  count.assign(x.size(), 0);
  for (std::size_t i = 0; i < x.size(); ++i)
    for_each_pair(x, nl, re, i, [&](std::size_t, const Vec&, Real, Real) { ++count[i]; });
}

void gradient(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
              const std::vector<Real>& phi, std::vector<Vec>& out) {
  out.assign(x.size(), Vec::Zero());
  const Real c = dim / n0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    Vec g = Vec::Zero();
    for_each_pair(x, nl, re, i, [&](std::size_t j, const Vec& rij, Real r2, Real w) {
      g += (phi[j] - phi[i]) / r2 * w * rij;
    });
    out[i] = c * g;
  }
}

void gradient_min(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
                  const std::vector<Real>& phi, std::vector<Vec>& out) {
  out.assign(x.size(), Vec::Zero());
  const Real c = dim / n0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    Real phi_min = phi[i];
    for_each_pair(x, nl, re, i, [&](std::size_t j, const Vec&, Real, Real) { phi_min = std::min(phi_min, phi[j]); });
    Vec g = Vec::Zero();
    for_each_pair(x, nl, re, i, [&](std::size_t j, const Vec& rij, Real r2, Real w) {
      g += (phi[j] - phi_min) / r2 * w * rij;
    });
    out[i] = c * g;
  }
}

void divergence(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
                const std::vector<Vec>& v, std::vector<Real>& out) {
  out.assign(x.size(), 0.0);
  const Real c = dim / n0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    Real s = 0;
    for_each_pair(x, nl, re, i, [&](std::size_t j, const Vec& rij, Real r2, Real w) {
      s += (v[j] - v[i]).dot(rij) / r2 * w;
    });
    out[i] = c * s;
  }
}

void laplacian(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
               const Real lambda, const std::vector<Real>& phi, std::vector<Real>& out) {
  out.assign(x.size(), 0.0);
  const Real c = 2.0 * dim / (lambda * n0);
  for (std::size_t i = 0; i < x.size(); ++i) {
    Real s = 0;
    for_each_pair(x, nl, re, i, [&](std::size_t j, const Vec&, Real, Real w) { s += (phi[j] - phi[i]) * w; });
    out[i] = c * s;
  }
}

void laplacian(const std::vector<Vec>& x, const NeighbourList& nl, const Real re, const Real n0,
               const Real lambda, const std::vector<Vec>& v, std::vector<Vec>& out) {
  out.assign(x.size(), Vec::Zero());
  const Real c = 2.0 * dim / (lambda * n0);
  for (std::size_t i = 0; i < x.size(); ++i) {
    Vec s = Vec::Zero();
    for_each_pair(x, nl, re, i, [&](std::size_t j, const Vec&, Real, Real w) { s += (v[j] - v[i]) * w; });
    out[i] = c * s;
  }
}

void corrected_gradient(const std::vector<Vec>& x, const NeighbourList& nl, const Real re,
                        const std::vector<Real>& phi, std::vector<Vec>& out) {
  out.assign(x.size(), Vec::Zero());
  for (std::size_t i = 0; i < x.size(); ++i) {
    Mat m = Mat::Zero();
    Vec b = Vec::Zero();
    Real n_i = 0;
    for_each_pair(x, nl, re, i, [&](std::size_t j, const Vec& rij, Real r2, Real w) {
      m += (w / r2) * rij * rij.transpose();
      b += (phi[j] - phi[i]) * (w / r2) * rij;
      n_i += w;
    });
    if (n_i <= 0) continue;  // isolated particle: no gradient
    const Real det = m.determinant();
    const Real tr = m.trace();
    // det > 1e-10 tr^d: det / tr^d is a scale-free measure of how well A_i is conditioned
    // (evaluated as ((1e-10 tr) tr) .. so that 2D keeps its rounding).
    Real threshold = 1e-10 * tr;
    for (int a = 1; a < dim; ++a) threshold *= tr;
    if (det > threshold)
      out[i] = m.inverse() * b;  // eq. 14 with A from eq. 15
    else
      out[i] = (dim / n_i) * b;  // eq. 9 with the particle's own n_i
  }
}

}  // namespace mpsfsi
