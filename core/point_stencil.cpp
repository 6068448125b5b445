// Point stencils for sources and receivers: Wendland C2 weights with a first-order (moving least
// squares) correction, in MPSFSI_DIM dimensions (basis (1, d): d + 1 unknowns); see
// core/point_stencil.hpp.
#include "core/point_stencil.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <stdexcept>
#include <string>

namespace mpsfsi {

namespace {

/// Moving-least-squares basis p = (1, d / radius): d + 1 entries.
using Basis = Eigen::Matrix<Real, dim + 1, 1>;
using BasisMat = Eigen::Matrix<Real, dim + 1, dim + 1>;

Basis basis(const Vec& d, const Real radius) {
  Basis p;
  p[0] = 1;
  for (int a = 0; a < dim; ++a) p[a + 1] = d[a] / radius;
  return p;
}

/// The candidates within radius of the point, with their kernel weights and offsets d = x - point.
struct InRange {
  std::vector<std::size_t> index;
  std::vector<Real> w;
  std::vector<Vec> d;
};

InRange gather(const std::vector<Vec>& x, const std::vector<std::size_t>& candidates, const Vec& point,
               const Real radius, const char* what) {
  if (!(radius > 0)) throw std::invalid_argument(std::string(what) + ": the radius must be positive");
  InRange r;
  for (const std::size_t k : candidates) {
    const Vec d = x[k] - point;
    const Real w = stencil_weight(d.norm(), radius);
    if (w <= 0) continue;
    r.index.push_back(k);
    r.w.push_back(w);
    r.d.push_back(d);
  }
  return r;
}

/// Throws unless the weighted covariance `c` [m2] of the offsets (normalised by the sum of the weights)
/// is well conditioned: d + 1 or more particles that do not lie on one line (2D) / in one plane (3D).
void check_spread(const Mat& c, const Real radius, const std::size_t n, const char* what) {
  const Real smallest = Eigen::SelfAdjointEigenSolver<Mat>(c).eigenvalues().minCoeff();
  if (n < static_cast<std::size_t>(dim + 1) || !(smallest > 1e-8 * radius * radius))
    throw std::invalid_argument(std::string(what) + (dim == 2 ? ": fewer than three particles that are not on one line"
                                                              : ": fewer than four particles that are not in one plane") +
                                " lie within the radius " + std::to_string(radius) + " m of the point (" +
                                std::to_string(n) + " in range); use a larger radius or a point inside the body");
}

}  // namespace

Real stencil_weight(const Real r, const Real radius) {
  const Real q = r / radius;
  if (!(q < 1)) return 0;
  const Real a = 1 - q;
  return a * a * a * a * (1 + 4 * q);
}

PointStencil interpolation_stencil(const std::vector<Vec>& x, const std::vector<std::size_t>& candidates,
                                   const Vec& point, const Real radius) {
  const InRange r = gather(x, candidates, point, radius, "interpolation stencil");
  // Moving least squares with the basis p = (1, d): phi_k = w_k p(0)^T A^-1 p(d_k), A = sum w p p^T.
  // Offsets are scaled by the radius so that A is of order one.
  BasisMat a = BasisMat::Zero();
  Real sw = 0;
  Vec mean = Vec::Zero();
  for (std::size_t q = 0; q < r.index.size(); ++q) {
    const Basis p = basis(r.d[q], radius);
    a += r.w[q] * p * p.transpose();
    sw += r.w[q];
    mean += r.w[q] * r.d[q];
  }
  Mat c = Mat::Zero();
  if (sw > 0) {
    mean /= sw;
    for (std::size_t q = 0; q < r.index.size(); ++q) c += r.w[q] * (r.d[q] - mean) * (r.d[q] - mean).transpose() / sw;
  }
  check_spread(c, radius, r.index.size(), "interpolation stencil");
  const Basis row = a.ldlt().solve(Basis::Unit(0));  // A^-1 p(0), A symmetric
  PointStencil s;
  s.index = r.index;
  for (std::size_t q = 0; q < r.index.size(); ++q) s.weight.push_back(r.w[q] * row.dot(basis(r.d[q], radius)));
  return s;
}

VectorStencil moment_stencil(const std::vector<Vec>& x, const std::vector<std::size_t>& candidates, const Vec& point,
                             const Real radius) {
  const InRange r = gather(x, candidates, point, radius, "moment stencil");
  Real sw = 0;
  Vec mean = Vec::Zero();
  for (std::size_t q = 0; q < r.index.size(); ++q) {
    sw += r.w[q];
    mean += r.w[q] * r.d[q];
  }
  if (sw > 0) mean /= sw;
  Mat c = Mat::Zero();
  for (std::size_t q = 0; q < r.index.size(); ++q) c += r.w[q] * (r.d[q] - mean) * (r.d[q] - mean).transpose();
  check_spread(sw > 0 ? Mat(c / sw) : c, radius, r.index.size(), "moment stencil");
  const Mat c_inv = c.inverse();
  VectorStencil s;
  s.index = r.index;
  // sum g = C^-1 sum w (d - dbar) = 0; sum d g^T = sum w d (d - dbar)^T C^-1 = C C^-1 = I (C symmetric).
  for (std::size_t q = 0; q < r.index.size(); ++q) s.value.push_back(r.w[q] * (c_inv * (r.d[q] - mean)));
  return s;
}

}  // namespace mpsfsi
