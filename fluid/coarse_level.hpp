// The coarse level of the ssor / sgs pressure solve (fluid/eisenstat_system.hpp): CG deflated by one constant
// per group of rows, the coarse matrix E = Z^T A Z factorised apart by rank with a Schur complement on the
// groups next to other ranks'. Internal to the pressure solver; Eigen and MPI only.
#pragma once

#include "core/collectives.hpp"
#include "fluid/pressure_solver.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace mpsfsi::trilinos_detail {

using Scalar = double;
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
/// (m x m, factorised with Eigen's sparse LDL^T apart by rank, factorise()), and this rank's rows of A Z.
/// Deflating the CG by span(Z) removes the smooth error components that a single-level relaxation
/// leaves to many iterations (Tang, Nabben, Vuik & Erlangga 2009), so the iteration count stops growing
/// with the number of rows and with the number of ranks.
struct CoarseLevel {
  int m = 0;                   ///< coarse unknowns over all ranks (0: no coarse level)
  std::vector<int> of_row;     ///< this rank's row -> coarse index, -1 if in no group
  CrsBlock az;                 ///< A Z on this rank's rows (columns: coarse indices, sorted)
  MPI_Comm comm = MPI_COMM_NULL;
  int n_ranks = 1;
  std::vector<int> of_col;  ///< column -> coarse index, -1 if in no group
  mutable std::vector<Scalar> g;
  // The factorisation apart by rank (factorise()).
  int first_own = 0, n_own = 0;  ///< the own groups: coarse indices [first_own, first_own + n_own)
  int n_interior = 0;            ///< own groups coupled to own groups only: the first n_interior of the factor
  std::vector<int> position;     ///< own group (k - first_own) -> its place in the local factor
  std::vector<int> group_at;     ///< place in the local factor -> own group (k - first_own)
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<Scalar>, Eigen::Lower, Eigen::NaturalOrdering<int>> local;  ///< E on the own groups
  std::vector<int> iface;     ///< Gamma: the groups of all ranks coupled to another rank's group, ascending
  std::vector<int> iface_of;  ///< coarse index -> index in iface, or -1
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<Scalar>> schur;  ///< S on Gamma, the same on every rank
  std::vector<int> interior_ptr, interior_index, local_ptr, local_index, schur_ptr, schur_index;  ///< the patterns the orderings were made for
  std::vector<int> interior_perm;  ///< interior group (interior-local) -> its place, AMD on the interior pattern
  Eigen::VectorXd local_d;  ///< D of the local factor
  mutable std::vector<Scalar> y, gamma;

  std::size_t bytes() const {
    return az.bytes() + (of_row.capacity() + of_col.capacity() + iface_of.capacity()) * sizeof(int) +
           (g.capacity() + y.capacity()) * sizeof(Scalar) +
           static_cast<std::size_t>(n_own > 0 ? local.matrixL().nestedExpression().nonZeros() : 0) * (sizeof(Scalar) + sizeof(int));
  }

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

  /// E = Z^T (A Z) from this rank's rows of A Z, factorised apart by rank (see solve()); with `same_pattern`
  /// (the rows of A Z changed their values only) on the orderings of the last factorisation. A collective.
  ///
  /// A group holds rows of one rank (its owner), so this rank's rows give the rows of E of its own groups.
  /// The own groups split into the interior I (coupled to own groups only) and the interface (coupled to
  /// another rank's group); the interfaces of all ranks form Gamma. With I ordered first, E restricted to the
  /// own groups is factorised here (L D L^T, I by approximate minimum degree), and Gamma's Schur complement
  ///   S = E_GG - sum over ranks of E_GI E_II^-1 E_IG
  /// is assembled from each rank's block (its L_GG D_G L_GG^T) and the couplings between ranks' interfaces,
  /// and factorised on every rank. Only Gamma's system is the same on every rank: the interiors are
  /// factorised and solved where their rows are.
  void factorise(const bool same_pattern = false) {
    const std::size_t n = of_row.size();
    // The own groups: a contiguous range of the coarse indices (keys are ordered by owner first).
    if (!same_pattern) {
      int lo = m, hi = -1;
      for (std::size_t i = 0; i < n; ++i)
        if (of_row[i] >= 0) {
          lo = std::min(lo, of_row[i]);
          hi = std::max(hi, of_row[i]);
        }
      first_own = hi < 0 ? 0 : lo;
      n_own = hi < 0 ? 0 : hi - lo + 1;
    }
    const auto own = [&](const int k) { return k >= first_own && k < first_own + n_own; };
    // The own rows of E (k, l, value), k ascending, l ascending within k.
    std::vector<int> count(static_cast<std::size_t>(n_own) + 1, 0), order(n);
    for (std::size_t i = 0; i < n; ++i)
      if (of_row[i] >= 0) ++count[static_cast<std::size_t>(of_row[i] - first_own) + 1];
    for (std::size_t k = 0; k < static_cast<std::size_t>(n_own); ++k) count[k + 1] += count[k];
    std::vector<int> next(count.begin(), count.end() - 1);
    for (std::size_t i = 0; i < n; ++i)
      if (of_row[i] >= 0) order[static_cast<std::size_t>(next[static_cast<std::size_t>(of_row[i] - first_own)]++)] = static_cast<int>(i);
    std::vector<Scalar> acc(static_cast<std::size_t>(m), 0.0);
    std::vector<char> seen(static_cast<std::size_t>(m), 0);
    std::vector<int> touched, row_k, row_l;
    std::vector<Scalar> row_v;
    for (std::size_t kk = 0; kk < static_cast<std::size_t>(n_own); ++kk) {
      for (int q = count[kk]; q < count[kk + 1]; ++q) {
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
        row_k.push_back(first_own + static_cast<int>(kk));
        row_l.push_back(l);
        row_v.push_back(acc[static_cast<std::size_t>(l)]);
        acc[static_cast<std::size_t>(l)] = 0;
        seen[static_cast<std::size_t>(l)] = 0;
      }
      touched.clear();
    }
    if (!same_pattern) order_groups(row_k, row_l);
    const std::size_t n_iface = iface.size();
    const int n_i = n_interior, n_g = n_own - n_interior;
    // E on the own groups, in the factor's order (the lower triangle of E as numbered globally, mirrored).
    std::vector<Eigen::Triplet<Scalar>> t;
    t.reserve(row_v.size());
    std::vector<Scalar> cross;  // Gamma's couplings between ranks, (iface k, iface l, value), k > l
    for (std::size_t q = 0; q < row_v.size(); ++q) {
      const int k = row_k[q], l = row_l[q];
      if (l > k) continue;
      if (own(l)) {
        const int a = position[static_cast<std::size_t>(k - first_own)], b = position[static_cast<std::size_t>(l - first_own)];
        t.emplace_back(std::max(a, b), std::min(a, b), row_v[q]);
      } else {
        cross.insert(cross.end(), {static_cast<Scalar>(iface_of[static_cast<std::size_t>(k)]),
                                   static_cast<Scalar>(iface_of[static_cast<std::size_t>(l)]), row_v[q]});
      }
    }
    if (n_own > 0) {
      Eigen::SparseMatrix<Scalar> M(n_own, n_own);
      M.setFromTriplets(t.begin(), t.end());
      if (!same_pattern && !has_pattern(M, local_ptr, local_index)) local.analyzePattern(M);
      local.factorize(M);
      if (local.info() != Eigen::Success) throw std::runtime_error("pressure solve (ssor): the coarse matrix is not positive definite");
      local_d = local.vectorD();  // (a copy: Eigen returns D by value)
    }
    if (n_iface == 0) return;
    // This rank's block of S: L_GG D_G L_GG^T (lower triangle), then the couplings, gathered on every rank.
    const auto& L = local.matrixL().nestedExpression();
    Eigen::MatrixXd lg = Eigen::MatrixXd::Identity(n_g, n_g);
    for (int j = n_i; j < n_own; ++j)
      for (Eigen::SparseMatrix<Scalar>::InnerIterator it(L, j); it; ++it)
        if (it.row() > j) lg(it.row() - n_i, j - n_i) = it.value();
    const Eigen::MatrixXd block = lg * local_d.tail(n_g).asDiagonal() * lg.transpose();
    std::vector<Scalar> entries = std::move(cross);
    for (int b = 0; b < n_g; ++b)
      for (int a = b; a < n_g; ++a)
        entries.insert(entries.end(), {static_cast<Scalar>(iface_of[static_cast<std::size_t>(first_own + group_at[static_cast<std::size_t>(n_i + a)])]),
                                       static_cast<Scalar>(iface_of[static_cast<std::size_t>(first_own + group_at[static_cast<std::size_t>(n_i + b)])]),
                                       block(a, b)});
    if (n_ranks > 1) entries = all_gather(comm, entries);
    std::vector<Eigen::Triplet<Scalar>> ts;
    ts.reserve(entries.size() / 3);
    for (std::size_t q = 0; q + 2 < entries.size(); q += 3) {
      const int a = static_cast<int>(entries[q]), b = static_cast<int>(entries[q + 1]);
      ts.emplace_back(std::max(a, b), std::min(a, b), entries[q + 2]);
    }
    Eigen::SparseMatrix<Scalar> S(static_cast<Eigen::Index>(n_iface), static_cast<Eigen::Index>(n_iface));
    S.setFromTriplets(ts.begin(), ts.end());
    if (!same_pattern && !has_pattern(S, schur_ptr, schur_index)) schur.analyzePattern(S);
    schur.factorize(S);
    if (schur.info() != Eigen::Success) throw std::runtime_error("pressure solve (ssor): the coarse matrix is not positive definite");
  }

  /// After the own rows of E (row_k, row_l) are known: Gamma (every rank's groups coupled to another rank's,
  /// iface, iface_of) and the order of the own groups in the local factor (position, group_at, n_interior):
  /// the interior by approximate minimum degree on its block, then the own interface groups ascending.
  /// A collective.
  void order_groups(const std::vector<int>& row_k, const std::vector<int>& row_l) {
    const auto own = [&](const int k) { return k >= first_own && k < first_own + n_own; };
    // Every group has one owner (LocalRows::group): the ranks' ranges of groups do not overlap.
    std::vector<char> owned(static_cast<std::size_t>(m), 0);
    for (const int k : of_row)
      if (k >= 0) owned[static_cast<std::size_t>(k)] = 1;
    const std::vector<std::int64_t> ranges = all_gather(comm, std::vector<std::int64_t>{first_own, n_own});
    std::int64_t covered = 0;
    for (std::size_t r = 0; r + 1 < ranges.size(); r += 2) covered += ranges[r + 1];
    int split = covered != m || std::count(owned.begin(), owned.end(), 1) != n_own ? 1 : 0;
    if (n_ranks > 1) MPI_Allreduce(MPI_IN_PLACE, &split, 1, MPI_INT, MPI_MAX, comm);  // every rank throws alike
    if (split) throw std::logic_error("pressure solve (ssor): coarse groups must each hold the rows of one rank, ordered by rank");
    std::vector<char> in_iface(static_cast<std::size_t>(m), 0);
    std::vector<std::int64_t> mine;  // the own groups coupled to other ranks', and the groups they meet there
    for (std::size_t q = 0; q < row_k.size(); ++q)
      if (!own(row_l[q])) mine.insert(mine.end(), {row_k[q], row_l[q]});
    const std::vector<std::int64_t> all = n_ranks > 1 ? all_gather(comm, mine) : mine;
    for (const std::int64_t k : all) in_iface[static_cast<std::size_t>(k)] = 1;
    iface.clear();
    iface_of.assign(static_cast<std::size_t>(m), -1);
    for (int k = 0; k < m; ++k)
      if (in_iface[static_cast<std::size_t>(k)]) {
        iface_of[static_cast<std::size_t>(k)] = static_cast<int>(iface.size());
        iface.push_back(k);
      }
    // The interior block's pattern (interior-local indices), ordered by AMD as Eigen's LDL^T would (again only
    // when the pattern changed).
    std::vector<int> interior_of(static_cast<std::size_t>(n_own), -1);
    std::vector<int> interior;
    for (int k = 0; k < n_own; ++k)
      if (!in_iface[static_cast<std::size_t>(first_own + k)]) {
        interior_of[static_cast<std::size_t>(k)] = static_cast<int>(interior.size());
        interior.push_back(k);
      }
    n_interior = static_cast<int>(interior.size());
    std::vector<Eigen::Triplet<Scalar>> t;
    for (std::size_t q = 0; q < row_k.size(); ++q) {
      if (!own(row_l[q]) || row_l[q] > row_k[q]) continue;
      const int a = interior_of[static_cast<std::size_t>(row_k[q] - first_own)], b = interior_of[static_cast<std::size_t>(row_l[q] - first_own)];
      if (a >= 0 && b >= 0) t.emplace_back(a, b, 1.0);
    }
    position.assign(static_cast<std::size_t>(n_own), -1);
    group_at.assign(static_cast<std::size_t>(n_own), -1);
    if (n_interior > 0) {
      Eigen::SparseMatrix<Scalar> lower(n_interior, n_interior), full;
      lower.setFromTriplets(t.begin(), t.end());
      if (!has_pattern(lower, interior_ptr, interior_index)) {
        full = lower.selfadjointView<Eigen::Lower>();
        Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
        Eigen::AMDOrdering<int>()(full, pinv);
        const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm = pinv.inverse();
        interior_perm.assign(perm.indices().data(), perm.indices().data() + n_interior);
      }
      for (int a = 0; a < n_interior; ++a)
        position[static_cast<std::size_t>(interior[static_cast<std::size_t>(a)])] = interior_perm[static_cast<std::size_t>(a)];
    }
    int next = n_interior;
    for (int k = 0; k < n_own; ++k)
      if (in_iface[static_cast<std::size_t>(first_own + k)]) position[static_cast<std::size_t>(k)] = next++;
    for (int k = 0; k < n_own; ++k) group_at[static_cast<std::size_t>(position[static_cast<std::size_t>(k)])] = k;
  }

  /// Whether A (compressed) has the pattern (ptr, index); if not, (ptr, index) become A's.
  static bool has_pattern(const Eigen::SparseMatrix<Scalar>& A, std::vector<int>& ptr, std::vector<int>& index) {
    const auto n = static_cast<std::size_t>(A.outerSize());
    if (ptr.size() == n + 1 && index.size() == static_cast<std::size_t>(A.nonZeros()) &&
        std::equal(ptr.begin(), ptr.end(), A.outerIndexPtr()) && std::equal(index.begin(), index.end(), A.innerIndexPtr()))
      return true;
    ptr.assign(A.outerIndexPtr(), A.outerIndexPtr() + n + 1);
    index.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
    return false;
  }

  /// v = E^-1 (the sum over ranks of v), in place, on the own groups and Gamma (the other ranks' interior
  /// groups are left at 0; no row of this rank meets them). Forward elimination of the own interior, one
  /// reduction of Gamma's right-hand side, Gamma's solve, back substitution of the own interior. A collective.
  void solve(std::vector<Scalar>& v) const {
    using Column = Eigen::SparseMatrix<Scalar>::InnerIterator;
    const Eigen::SparseMatrix<Scalar>* L = n_own > 0 ? &local.matrixL().nestedExpression() : nullptr;
    const Scalar* d = local_d.data();
    y.resize(static_cast<std::size_t>(n_own));
    for (int k = 0; k < n_own; ++k) y[static_cast<std::size_t>(position[static_cast<std::size_t>(k)])] = v[static_cast<std::size_t>(first_own + k)];
    for (int j = 0; j < n_interior; ++j) {  // L_II z_I = v_I; v_G -= L_GI z_I
      const Scalar zj = y[static_cast<std::size_t>(j)];
      for (Column it(*L, j); it; ++it) y[static_cast<std::size_t>(it.row())] -= it.value() * zj;
    }
    if (!iface.empty()) {
      gamma.resize(iface.size());
      for (std::size_t q = 0; q < iface.size(); ++q) {
        const int k = iface[q];
        gamma[q] = k >= first_own && k < first_own + n_own ? y[static_cast<std::size_t>(position[static_cast<std::size_t>(k - first_own)])]
                                                             : v[static_cast<std::size_t>(k)];
      }
      if (n_ranks > 1) MPI_Allreduce(MPI_IN_PLACE, gamma.data(), static_cast<int>(gamma.size()), MPI_DOUBLE, MPI_SUM, comm);
      Eigen::Map<Eigen::VectorXd> x(gamma.data(), static_cast<Eigen::Index>(gamma.size()));
      x = schur.solve(x);
      for (int a = n_interior; a < n_own; ++a)
        y[static_cast<std::size_t>(a)] = gamma[static_cast<std::size_t>(iface_of[static_cast<std::size_t>(first_own + group_at[static_cast<std::size_t>(a)])])];
    }
    for (int j = n_interior - 1; j >= 0; --j) {  // L_II^T x_I = D_I^-1 z_I - L_GI^T x_G
      Scalar xj = y[static_cast<std::size_t>(j)] / d[j];
      for (Column it(*L, j); it; ++it) xj -= it.value() * y[static_cast<std::size_t>(it.row())];
      y[static_cast<std::size_t>(j)] = xj;
    }
    std::fill(v.begin(), v.end(), 0.0);
    for (int k = 0; k < n_own; ++k) v[static_cast<std::size_t>(first_own + k)] = y[static_cast<std::size_t>(position[static_cast<std::size_t>(k)])];
    for (std::size_t q = 0; q < iface.size(); ++q) v[static_cast<std::size_t>(iface[q])] = gamma[q];
  }
  /// v = Z^T u on this rank's rows (to be summed over ranks by solve()).
  void restrict_rows(const Scalar* u, std::vector<Scalar>& v) const {
    v.assign(static_cast<std::size_t>(m), 0.0);
    for (std::size_t i = 0; i < of_row.size(); ++i)
      if (of_row[i] >= 0) v[static_cast<std::size_t>(of_row[i])] += u[i];
  }
};

}  // namespace mpsfsi::trilinos_detail
