// The Eisenstat split system of the ssor / sgs pressure solve (fluid/pressure_solver_trilinos.cpp): CG runs on
// S A S^T with one pass over the rank's lower triangle per product, block Jacobi between ranks, deflated by a
// coarse level of particle groups. Internal to the pressure solver: Tpetra appears here and in its one user.
#pragma once

#include "core/buffers.hpp"
#include "core/collectives.hpp"
#include "fluid/pressure_solver.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

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

using Scalar = double;
using Map = Tpetra::Map<>;
using MV = Tpetra::MultiVector<Scalar>;
using OP = Tpetra::Operator<Scalar>;
using LO = Map::local_ordinal_type;
using GO = Map::global_ordinal_type;
using Node = Map::node_type;
using Teuchos::RCP;

/// Rows of a sparse block in CRS form with 32-bit offsets and column ids.
struct CrsBlock {
  std::vector<int> ptr{0};
  std::vector<int> col;
  std::vector<Scalar> val;
  void clear() {
    ptr.assign(1, 0);
    col.clear();
    val.clear();
  }
  std::size_t bytes() const { return ptr.capacity() * sizeof(int) + col.capacity() * sizeof(int) + val.capacity() * sizeof(Scalar); }
  /// sum over row r of val x[col], with four partial sums (a row is a short dot product; one running sum
  /// makes every row wait on the latency of each addition).
  Scalar row_dot(const std::size_t r, const Scalar* x) const {
    int k = ptr[r];
    const int k1 = ptr[r + 1];
    const int* c = col.data();
    const Scalar* v = val.data();
    Scalar s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (; k + 3 < k1; k += 4) {
      s0 += v[k] * x[c[k]];
      s1 += v[k + 1] * x[c[k + 1]];
      s2 += v[k + 2] * x[c[k + 2]];
      s3 += v[k + 3] * x[c[k + 3]];
    }
    for (; k < k1; ++k) s0 += v[k] * x[c[k]];
    return (s0 + s1) + (s2 + s3);
  }
};

/// The coarse level of the two-level SSOR: Z (rows x m) has one column per coarse group of the system
/// (Z_ik = 1 when row i is in group k; rows without off-diagonal entries are in no group), E = Z^T A Z
/// (m x m, the same on every rank, factorised with Eigen's sparse LDL^T), and this rank's rows of A Z.
/// Deflating the CG by span(Z) removes the smooth error components that a single-level relaxation
/// leaves to many iterations (Tang, Nabben, Vuik & Erlangga 2009), so the iteration count stops growing
/// with the number of rows and with the number of ranks.
struct CoarseLevel {
  int m = 0;                   ///< coarse unknowns over all ranks (0: no coarse level)
  std::vector<int> of_row;     ///< this rank's row -> coarse index, -1 if in no group
  CrsBlock az;                 ///< A Z on this rank's rows (columns: coarse indices, sorted)
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<Scalar>> e;
  MPI_Comm comm = MPI_COMM_NULL;
  int n_ranks = 1;
  std::vector<int> of_col;  ///< column -> coarse index, -1 if in no group
  mutable std::vector<Scalar> g;

  std::size_t bytes() const { return az.bytes() + of_row.capacity() * sizeof(int) + g.capacity() * sizeof(Scalar); }

  /// The coarse index of every column of `sys` (of_col) and row (of_row): the groups of all ranks' rows
  /// with more than one entry (identity rows, e.g. the free surface's, are in no group), numbered in key
  /// order. A collective.
  void set_groups(const LocalRows& sys, MPI_Comm c, const int ranks) {
    comm = c;
    n_ranks = ranks;
    const std::size_t n = sys.n_rows(), n_cols = n + sys.remote_id.size();
    const auto coupled = [&](const std::size_t i) { return sys.row_ptr[i + 1] - sys.row_ptr[i] > 1; };
    // Rows come in runs of one group: repeats are skipped before sorting.
    std::vector<std::int64_t> keys;
    for (std::size_t i = 0; i < n; ++i)
      if (coupled(i) && (keys.empty() || keys.back() != sys.group[i])) keys.push_back(sys.group[i]);
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    if (n_ranks > 1) {
      keys = all_gather(comm, keys);
      std::sort(keys.begin(), keys.end());
      keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    }
    m = static_cast<int>(keys.size());
    of_col.assign(n_cols, -1);
    std::int64_t last_key = 0;
    int last = -1;
    for (std::size_t k = 0; k < n_cols && m > 0; ++k) {
      if (k < n && !coupled(k)) continue;
      if (last < 0 || sys.group[k] != last_key) {
        const auto it = std::lower_bound(keys.begin(), keys.end(), sys.group[k]);
        last = it != keys.end() && *it == sys.group[k] ? static_cast<int>(it - keys.begin()) : -1;
        last_key = sys.group[k];
        if (last < 0) continue;
      }
      of_col[k] = last;
    }
    of_row.assign(of_col.begin(), of_col.begin() + static_cast<std::ptrdiff_t>(n));
    az.clear();
    az.col.reserve(4 * n);
    az.val.reserve(4 * n);
    az.ptr.reserve(n + 1);
  }

  static constexpr int max_groups = 64;  ///< coarse groups one row may meet

  /// A row of A Z: the entries (col, value) summed by the group of their column, sorted by group, into
  /// (row_l, row_v); returns their number.
  int row_by_group(const LocalIndex* col, const Scalar* value, const std::size_t n_entries, int* row_l,
                   Scalar* row_v) const {
    int n_l = 0, cur = -1, cur_l = -1;
    Scalar run = 0;  // the sum of the current run of one group, in a register
    for (std::size_t k = 0; k < n_entries; ++k) {
      const int l = of_col[static_cast<std::size_t>(col[k])];
      if (l == cur_l) {  // columns come in runs of one group: search only on a change
        run += value[k];
        continue;
      }
      if (l < 0) continue;
      if (cur >= 0) row_v[cur] += run;
      cur = 0;
      while (cur < n_l && row_l[cur] != l) ++cur;
      if (cur == n_l) {
        if (n_l == max_groups) throw std::logic_error("pressure solve (ssor): a row meets more than 64 coarse groups");
        row_l[n_l] = l;
        row_v[n_l++] = 0;
      }
      cur_l = l;
      run = value[k];
    }
    if (cur >= 0) row_v[cur] += run;
    for (int q = 1; q < n_l; ++q)  // sorted by group
      for (int s = q; s > 0 && row_l[s - 1] > row_l[s]; --s) {
        std::swap(row_l[s - 1], row_l[s]);
        std::swap(row_v[s - 1], row_v[s]);
      }
    return n_l;
  }

  /// Appends the next row of A Z.
  void add_row(const LocalIndex* col, const Scalar* value, const std::size_t n_entries) {
    int row_l[max_groups];
    Scalar row_v[max_groups];
    const int n_l = row_by_group(col, value, n_entries, row_l, row_v);
    for (int q = 0; q < n_l; ++q) {
      az.col.push_back(row_l[q]);
      az.val.push_back(row_v[q]);
    }
    az.ptr.push_back(static_cast<int>(az.col.size()));
  }

  /// Row i of A Z anew from new values on the same columns (the same groups, so the same entries).
  void set_row(const std::size_t i, const LocalIndex* col, const Scalar* value, const std::size_t n_entries) {
    int row_l[max_groups];
    Scalar row_v[max_groups];
    const int n_l = row_by_group(col, value, n_entries, row_l, row_v);
    assert(n_l == az.ptr[i + 1] - az.ptr[i]);
    for (int q = 0; q < n_l; ++q) {
      assert(az.col[static_cast<std::size_t>(az.ptr[i] + q)] == row_l[q]);
      az.val[static_cast<std::size_t>(az.ptr[i] + q)] = row_v[q];
    }
  }

  /// E = Z^T (A Z) from this rank's rows of A Z and the other ranks', factorised; with `same_pattern` (the
  /// rows of A Z changed their values only) on the ordering of the last factorisation. A collective.
  void factorise(const bool same_pattern = false) {
    const std::size_t n = of_row.size();
    std::vector<Scalar> acc(static_cast<std::size_t>(m), 0.0);
    std::vector<char> seen(static_cast<std::size_t>(m), 0);
    std::vector<int> touched;
    // E = Z^T (A Z): the rows of A Z summed by their own group, as (k, l, value) on every rank.
    std::vector<int> count(static_cast<std::size_t>(m) + 1, 0), order(n);
    for (std::size_t i = 0; i < n; ++i)
      if (of_row[i] >= 0) ++count[static_cast<std::size_t>(of_row[i]) + 1];
    for (std::size_t k = 0; k < static_cast<std::size_t>(m); ++k) count[k + 1] += count[k];
    std::vector<int> next(count.begin(), count.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      if (of_row[i] >= 0) order[static_cast<std::size_t>(next[static_cast<std::size_t>(of_row[i])]++)] = static_cast<int>(i);
    std::vector<Scalar> triplets;
    for (std::size_t k = 0; k < static_cast<std::size_t>(m); ++k) {
      for (int q = count[k]; q < count[k + 1]; ++q) {
        const auto i = static_cast<std::size_t>(order[static_cast<std::size_t>(q)]);
        for (int e = az.ptr[i]; e < az.ptr[i + 1]; ++e) {
          const auto l = static_cast<std::size_t>(az.col[static_cast<std::size_t>(e)]);
          if (!seen[l]) touched.push_back(static_cast<int>(l));
          seen[l] = 1;
          acc[l] += az.val[static_cast<std::size_t>(e)];
        }
      }
      std::sort(touched.begin(), touched.end());
      for (const int l : touched) {
        triplets.insert(triplets.end(), {static_cast<Scalar>(k), static_cast<Scalar>(l), acc[static_cast<std::size_t>(l)]});
        acc[static_cast<std::size_t>(l)] = 0;
        seen[static_cast<std::size_t>(l)] = 0;
      }
      touched.clear();
    }
    if (n_ranks > 1) triplets = all_gather(comm, triplets);
    std::vector<Eigen::Triplet<Scalar>> t;
    t.reserve(triplets.size() / 3);
    for (std::size_t q = 0; q + 2 < triplets.size(); q += 3)
      t.emplace_back(static_cast<int>(triplets[q]), static_cast<int>(triplets[q + 1]), triplets[q + 2]);
    Eigen::SparseMatrix<Scalar> E(m, m);
    E.setFromTriplets(t.begin(), t.end());
    if (!same_pattern) e.analyzePattern(E);
    e.factorize(E);
    if (e.info() != Eigen::Success) throw std::runtime_error("pressure solve (ssor): the coarse matrix is not positive definite");
    g.assign(static_cast<std::size_t>(m), 0.0);
  }

  /// g = E^-1 (the sum over ranks of g), in place. A collective.
  void solve(std::vector<Scalar>& v) const {
    if (n_ranks > 1) MPI_Allreduce(MPI_IN_PLACE, v.data(), m, MPI_DOUBLE, MPI_SUM, comm);
    Eigen::Map<Eigen::VectorXd> x(v.data(), m);
    x = e.solve(x);
  }
  /// v = Z^T u on this rank's rows (to be summed over ranks by solve()).
  void restrict_rows(const Scalar* u, std::vector<Scalar>& v) const {
    v.assign(static_cast<std::size_t>(m), 0.0);
    for (std::size_t i = 0; i < of_row.size(); ++i)
      if (of_row[i] >= 0) v[static_cast<std::size_t>(of_row[i])] += u[i];
  }
};

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
/// same arrays. O holds column-map ids. No Tpetra matrix is built on this path.
class EisenstatSystem final : public OP {
 public:
  CrsBlock lower;  ///< L: columns are this rank's row indices
  CrsBlock other;  ///< O: column-map ids
  CoarseLevel coarse;
  std::vector<Scalar> diag, inv_dprime, sqrt_dprime, d_minus_2dprime;
  RCP<const Map> row_map;
  RCP<const Tpetra::Import<LO, GO, Node>> importer;  // null on one rank
  RCP<MV> t_row, t_col;                              // t on the row and column maps when importer is set
  mutable std::vector<Scalar> t, z;
  std::vector<std::size_t> diag_pos_;  ///< set_rows: each row's first entry at or after the diagonal

  RCP<const Map> getDomainMap() const override { return row_map; }
  RCP<const Map> getRangeMap() const override { return row_map; }
  std::size_t size() const { return diag.size(); }
  std::size_t bytes() const { return lower.bytes() + other.bytes() + coarse.bytes() + 6 * diag.capacity() * sizeof(Scalar); }

  /// Splits this rank's rows and sets up the relaxation. Throws if a row has no positive diagonal.
  void set_rows(const LocalRows& sys, const Scalar omega, MPI_Comm comm, const int n_ranks) {
    coarse.m = 0;
    if (!sys.group.empty()) coarse.set_groups(sys, comm, n_ranks);
    const std::size_t n = sys.n_rows();
    const auto n_own = static_cast<LocalIndex>(n);
    // Each row is sorted: L's columns (c < i), the diagonal, U's (i < c < n), then other ranks' (c >= n).
    lower.ptr.resize(n + 1);
    other.ptr.resize(n + 1);
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
    }
    resize_with_headroom(lower.col, static_cast<std::size_t>(lower.ptr[n]));
    resize_with_headroom(lower.val, lower.col.size());
    resize_with_headroom(other.col, static_cast<std::size_t>(other.ptr[n]));
    resize_with_headroom(other.val, other.col.size());
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
      std::copy_n(&sys.col[k1 - n_other], n_other, &other.col[static_cast<std::size_t>(other.ptr[i])]);
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

  /// The columns of other ranks' rows of `x` (row map) on the column map, or null on one rank.
  const Scalar* import(const Scalar* x) const {
    if (importer.is_null()) return nullptr;
    {
      auto tv = t_row->getLocalViewHost(Tpetra::Access::OverwriteAll);
      for (std::size_t i = 0; i < size(); ++i) tv(i, 0) = x[i];
    }
    t_col->doImport(*t_row, *importer, Tpetra::INSERT);
    return &t_col->getLocalViewHost(Tpetra::Access::ReadOnly)(0, 0);
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
    t.resize(n);
    z.resize(n);
    Scalar* tp = t.data();
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
      if (const Scalar* tc = import(tp))  // s += O t (couplings to the other ranks' rows)
        for (std::size_t i = 0; i < n; ++i) zp[i] += other.row_dot(i, tc);
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
