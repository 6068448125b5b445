// The Eisenstat split system of the ssor / sgs pressure solve (fluid/pressure_solver_trilinos.cpp): CG runs on
// S A S^T with one pass over the rank's lower triangle per product, block Jacobi between ranks, deflated by a
// coarse level of particle groups. Internal to the pressure solver: Tpetra appears here and in its one user.
#pragma once

#include "core/buffers.hpp"
#include "fluid/coarse_level.hpp"
#include "fluid/pressure_solver.hpp"

#include <Teuchos_RCP.hpp>
#include <Tpetra_Import.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_MultiVector.hpp>
#include <Tpetra_Operator.hpp>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpsfsi::trilinos_detail {

using Map = Tpetra::Map<>;
using MV = Tpetra::MultiVector<Scalar>;
using OP = Tpetra::Operator<Scalar>;
using LO = Map::local_ordinal_type;
using GO = Map::global_ordinal_type;
using Node = Map::node_type;
using Teuchos::RCP;


/// Symmetric Gauss-Seidel / SSOR (relaxation omega) preconditioned system by Eisenstat's trick, on each
/// rank's diagonal block (block Jacobi between ranks, so it stays symmetric). With A = L + D + L^T + O (L
/// the strictly lower part of the rank's block, O the couplings to other ranks' rows) and D' = D / omega,
/// CG runs on the SPD system
///   Ah y = bh,  Ah = S A S^T,  S = D'^(1/2) (D' + L)^-1,  bh = S b,  x = S^T y,
/// and one product with Ah costs one pass over the matrix instead of three (SpMV + forward and backward
/// sweeps): with w = D'^(1/2) v and t = (D' + L^T)^-1 w,
///   Ah v = D'^(1/2) (t + (D' + L)^-1 (w + (D - 2 D') t + O t)).
/// The block is symmetric (eq. 23's pair weights), so only L is stored: the forward sweep reads its rows
/// as dot products, the backward sweep reads them last one first and scatters each finished unknown into
/// the earlier rows (column-oriented L^T). Half the matrix is stored and both sweeps stream through the
/// same arrays. O's columns index the remote ids (LocalRows::remote_id), whose values one Tpetra import brings
/// straight from the owners into `t_ghost`; `other_row` lists the rows it is not empty on. No Tpetra matrix is
/// built on this path.
class EisenstatSystem final : public OP {
 public:
  CrsBlock lower;  ///< L: columns are this rank's row indices
  CrsBlock other;  ///< O: columns index the remote ids
  std::vector<int> other_row;  ///< the rows with couplings to other ranks (O not empty), ascending
  CoarseLevel coarse;
  std::vector<Scalar> diag, inv_dprime, sqrt_dprime, d_minus_2dprime;
  RCP<const Map> row_map;
  RCP<const Tpetra::Import<LO, GO, Node>> importer;  ///< row map -> the remote ids' map; null on one rank
  RCP<MV> t_row, t_ghost;  ///< with importer: the vector to import from (t's storage) and the remote values
  mutable std::vector<Scalar> t, z;
  std::vector<std::size_t> diag_pos_;  ///< set_rows: each row's first entry at or after the diagonal

  RCP<const Map> getDomainMap() const override { return row_map; }
  RCP<const Map> getRangeMap() const override { return row_map; }
  std::size_t size() const { return diag.size(); }
  std::size_t bytes() const {
    return lower.bytes() + other.bytes() + other_row.capacity() * sizeof(int) + coarse.bytes() + 6 * diag.capacity() * sizeof(Scalar);
  }

  /// Splits this rank's rows and sets up the relaxation. Throws if a row has no positive diagonal.
  void set_rows(const LocalRows& sys, const Scalar omega, MPI_Comm comm, const int n_ranks) {
    coarse.m = 0;
    if (!sys.group.empty()) coarse.set_groups(sys, comm, n_ranks);
    const std::size_t n = sys.n_rows();
    const auto n_own = static_cast<LocalIndex>(n);
    // Each row is sorted: L's columns (c < i), the diagonal, U's (i < c < n), then other ranks' (c >= n).
    lower.ptr.resize(n + 1);
    other.ptr.resize(n + 1);
    other_row.clear();
    std::vector<std::size_t>& diag_at = diag_pos_;
    diag_at.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const LocalIndex* b = sys.col.data() + sys.row_ptr[i];
      const LocalIndex* e = sys.col.data() + sys.row_ptr[i + 1];
      assert(std::is_sorted(b, e));
      const LocalIndex* d = std::lower_bound(b, e, static_cast<LocalIndex>(i));
      const LocalIndex* o = std::lower_bound(d, e, n_own);
      diag_at[i] = static_cast<std::size_t>(d - sys.col.data());
      lower.ptr[i + 1] = lower.ptr[i] + static_cast<int>(d - b);
      other.ptr[i + 1] = other.ptr[i] + static_cast<int>(e - o);
      if (o != e) other_row.push_back(static_cast<int>(i));
    }
    fit_with_headroom(lower.col, static_cast<std::size_t>(lower.ptr[n]));
    fit_with_headroom(lower.val, lower.col.size());
    fit_with_headroom(other.col, static_cast<std::size_t>(other.ptr[n]));
    fit_with_headroom(other.val, other.col.size());
    diag.resize(n);
    inv_dprime.resize(n);
    sqrt_dprime.resize(n);
    d_minus_2dprime.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k0 = sys.row_ptr[i], k1 = sys.row_ptr[i + 1];
      if (coarse.m > 0) coarse.add_row(&sys.col[k0], &sys.value[k0], k1 - k0);
      const std::size_t n_lower = static_cast<std::size_t>(lower.ptr[i + 1] - lower.ptr[i]);
      const std::size_t n_other = static_cast<std::size_t>(other.ptr[i + 1] - other.ptr[i]);
      std::copy_n(&sys.col[k0], n_lower, &lower.col[static_cast<std::size_t>(lower.ptr[i])]);
      for (std::size_t q = 0; q < n_other; ++q)  // remote column c >= n_own is remote id c - n_own
        other.col[static_cast<std::size_t>(other.ptr[i]) + q] = sys.col[k1 - n_other + q] - n_own;
      set_row_values(sys, i, omega);
    }
    if (coarse.m > 0) coarse.factorise();
  }

  /// After set_rows on a system with the same rows and columns: the values of `rows` from `sys` (the
  /// relaxation's and the coarse level's; the coarse matrix is factorised anew). A collective.
  void update_rows(const LocalRows& sys, const std::vector<LocalIndex>& rows, const Scalar omega) {
    for (const LocalIndex r : rows) {
      const auto i = static_cast<std::size_t>(r);
      const std::size_t k0 = sys.row_ptr[i], k1 = sys.row_ptr[i + 1];
      if (coarse.m > 0) coarse.set_row(i, &sys.col[k0], &sys.value[k0], k1 - k0);
      set_row_values(sys, i, omega);
    }
    if (coarse.m > 0) coarse.factorise(true);
  }

  /// Row i's values in L, O and D, and its relaxation. Throws if it has no positive diagonal.
  void set_row_values(const LocalRows& sys, const std::size_t i, const Scalar omega) {
    const std::size_t k0 = sys.row_ptr[i], k1 = sys.row_ptr[i + 1];
    const std::size_t n_lower = static_cast<std::size_t>(lower.ptr[i + 1] - lower.ptr[i]);
    const std::size_t n_other = static_cast<std::size_t>(other.ptr[i + 1] - other.ptr[i]);
    std::copy_n(&sys.value[k0], n_lower, &lower.val[static_cast<std::size_t>(lower.ptr[i])]);
    std::copy_n(&sys.value[k1 - n_other], n_other, &other.val[static_cast<std::size_t>(other.ptr[i])]);
    diag[i] = 0;
    for (std::size_t k = diag_pos_[i]; k < k1 && sys.col[k] == static_cast<LocalIndex>(i); ++k) diag[i] += sys.value[k];
    if (!(diag[i] > 0))
      throw std::runtime_error("pressure solve (sgs): the row of global id " + std::to_string(sys.row_id[i]) +
                               " has no positive diagonal");
    const Scalar dprime = diag[i] / omega;
    inv_dprime[i] = 1.0 / dprime;
    sqrt_dprime[i] = std::sqrt(dprime);
    d_minus_2dprime[i] = diag[i] - 2 * dprime;
  }

  /// acc[j] -= L_ij x_i over the entries of row i of L (the column of L^T: row j of L^T x gets L_ij x_i).
  void scatter_lower(const std::size_t i, const Scalar xi, Scalar* acc) const {
    const int* c = lower.col.data();
    const Scalar* v = lower.val.data();
    for (int k = lower.ptr[i]; k < lower.ptr[i + 1]; ++k) acc[c[k]] -= v[k] * xi;
  }

  /// (D' + L^T)^-1 w, backward (out may be w).
  void backward(const Scalar* w, Scalar* out) const {
    const std::size_t n = size();
    if (out != w) std::copy(w, w + n, out);
    for (std::size_t r = 0; r < n; ++r) {
      const std::size_t i = n - 1 - r;
      out[i] *= inv_dprime[i];
      scatter_lower(i, out[i], out);
    }
  }
  /// One pass over L: fwd = (D' + L)^-1 s (forward sweep, fwd may be s) and up = (D' + L^T) x (row i of
  /// L scatters x_i into the earlier rows, which were set before).
  void forward_and_upper_times(const Scalar* s, Scalar* fwd, const Scalar* x, Scalar* up) const {
    const std::size_t n = size();
    for (std::size_t i = 0; i < n; ++i) {
      fwd[i] = (s[i] - lower.row_dot(i, fwd)) * inv_dprime[i];
      up[i] = x[i] / inv_dprime[i];
      scatter_lower(i, -x[i], up);
    }
  }

  /// Where apply() keeps t: in t_row when there is an importer (to be imported from without a copy).
  Scalar* t_storage() const {
    if (importer.is_null()) {
      t.resize(size());
      return t.data();
    }
    assert(t_row->getLocalLength() == size());
    return size() ? &t_row->getLocalViewHost(Tpetra::Access::ReadWrite)(0, 0) : nullptr;
  }

  /// The values at the remote ids of t_row (their owners' rows), or null on one rank. A collective.
  const Scalar* import_t_row() const {
    if (importer.is_null()) return nullptr;
    t_ghost->doImport(*t_row, *importer, Tpetra::INSERT);
    return t_ghost->getLocalLength() ? &t_ghost->getLocalViewHost(Tpetra::Access::ReadOnly)(0, 0) : nullptr;
  }

  /// The values at the remote ids of `x` (row map), or null on one rank. A collective.
  const Scalar* import(const Scalar* x) const {
    if (importer.is_null()) return nullptr;
    {
      auto tv = t_row->getLocalViewHost(Tpetra::Access::OverwriteAll);
      for (std::size_t i = 0; i < size(); ++i) tv(i, 0) = x[i];
    }
    return import_t_row();
  }

  /// r = b - A x (collective when the rows are split over ranks).
  void residual(const Scalar* b, const Scalar* x, Scalar* r) const {
    const std::size_t n = size();
    const Scalar* xc = import(x);
    std::copy(b, b + n, r);
    for (std::size_t i = 0; i < n; ++i) {
      Scalar ax = diag[i] * x[i] + lower.row_dot(i, x);
      if (xc) ax += other.row_dot(i, xc);
      r[i] -= ax;
      scatter_lower(i, x[i], r);  // the L^T x part
    }
  }

  void apply(const MV& X, MV& Y, Teuchos::ETransp /*mode*/ = Teuchos::NO_TRANS,
             Scalar alpha = Teuchos::ScalarTraits<Scalar>::one(),
             Scalar beta = Teuchos::ScalarTraits<Scalar>::zero()) const override {
    const std::size_t n = size();
    z.resize(n);
    Scalar* tp = t_storage();
    Scalar* zp = z.data();
    for (std::size_t c = 0; c < X.getNumVectors(); ++c) {
      {
        auto xv = X.getLocalViewHost(Tpetra::Access::ReadOnly);
        const Scalar* v = n ? &xv(0, c) : nullptr;
        // Backward sweep t = (D' + L^T)^-1 w with w = D'^(1/2) v (t starts as w and receives the scattered
        // rows), fused with s = w + (D - 2 D') t in z.
        for (std::size_t i = 0; i < n; ++i) tp[i] = sqrt_dprime[i] * v[i];
        const bool two_level = coarse.m > 0;
        if (two_level) coarse.g.assign(static_cast<std::size_t>(coarse.m), 0.0);
        Scalar* g = coarse.g.data();
        for (std::size_t r = 0; r < n; ++r) {
          const std::size_t i = n - 1 - r;
          const Scalar w = sqrt_dprime[i] * v[i];
          tp[i] *= inv_dprime[i];
          zp[i] = w + d_minus_2dprime[i] * tp[i];
          scatter_lower(i, tp[i], tp);
          if (two_level)  // g = (A Z)^T t
            for (int k = coarse.az.ptr[i]; k < coarse.az.ptr[i + 1]; ++k) g[coarse.az.col[k]] += coarse.az.val[k] * tp[i];
        }
      }
      if (const Scalar* tc = import_t_row())  // s += O t (couplings to the other ranks' rows)
        for (const int i : other_row) zp[i] += other.row_dot(static_cast<std::size_t>(i), tc);
      // Deflation: s -= A Z E^-1 Z^T A t (with the forward sweep below: P Ah v, P = I - Ah Zh E^-1 Zh^T,
      // Zh = S^-T Z).
      const Scalar* cg = nullptr;
      if (coarse.m > 0) {
        coarse.solve(coarse.g);
        cg = coarse.g.data();
      }
      // Forward sweep in place z = (D' + L)^-1 s (row i reads s_i before writing it, and finished rows
      // j < i), fused with Y = alpha D'^(1/2) (t + z) + beta Y.
      auto yv = Y.getLocalViewHost(Tpetra::Access::ReadWrite);
      for (std::size_t i = 0; i < n; ++i) {
        if (cg) zp[i] -= coarse.az.row_dot(i, cg);
        zp[i] = (zp[i] - lower.row_dot(i, zp)) * inv_dprime[i];
        const Scalar r = alpha * sqrt_dprime[i] * (tp[i] + zp[i]);
        yv(i, c) = beta == Scalar(0) ? r : beta * yv(i, c) + r;
      }
    }
  }
};

}  // namespace mpsfsi::trilinos_detail
