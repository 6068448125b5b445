// Trilinos implementation of the pressure solve (seed 004 eq. 23): the only translation unit that
// includes Tpetra, Belos, MueLu and Ifpack2. The row map is made of this rank's row ids (particle global
// ids) and the column map of these and the remote ids, with an Import from the owners the caller names;
// both are kept while the ids do not change. SSOR / SGS run CG on Eisenstat's split system (no Tpetra
// matrix); the other preconditioners get a Tpetra::CrsMatrix made straight from the local CRS arrays
// (Kokkos views + expertStaticFillComplete): Belos CG or GMRES with MueLu (coarse solver RELAXATION: the
// default KLU2 coarse solve is wrong on 2 ranks in this build, see docs/architecture.md, ## Numerical choices)
// or Ifpack2 Chebyshev / ILU(0) (additive Schwarz) / Jacobi / symmetric Gauss-Seidel. A preconditioner may be
// kept for several solves (rebuild_every): it is applied as built on its own, earlier matrix, which stays
// a valid SPD preconditioner of the new one. The true residual is checked after every solve.
#include "fluid/pressure_solver.hpp"

#include "core/binary_io.hpp"
#include "core/buffers.hpp"
#include "core/collectives.hpp"
#include "core/stopwatch.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <BelosLinearProblem.hpp>
#include <BelosSolverFactory.hpp>
#include <BelosTpetraAdapter.hpp>
#include <Ifpack2_Chebyshev.hpp>
#include <Ifpack2_Factory.hpp>
#include <Kokkos_Core.hpp>
#include <MueLu_CreateTpetraPreconditioner.hpp>
#include <Teuchos_DefaultMpiComm.hpp>
#include <Teuchos_ParameterList.hpp>
#include <Tpetra_CrsMatrix.hpp>
#include <Tpetra_Map.hpp>
#include <Tpetra_MultiVector.hpp>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace mpsfsi {

namespace {

using Scalar = double;
using Map = Tpetra::Map<>;
using Matrix = Tpetra::CrsMatrix<Scalar>;
using MV = Tpetra::MultiVector<Scalar>;
using OP = Tpetra::Operator<Scalar>;
using LO = Map::local_ordinal_type;
using GO = Map::global_ordinal_type;
using Node = Map::node_type;
using Teuchos::RCP;
using Teuchos::rcp;

static_assert(std::is_same<GO, GlobalId>::value, "GlobalId must match Tpetra's GlobalOrdinal");

/// Kokkos must be up before the first Tpetra object. MPI belongs to main(); Kokkos (Serial only in this
/// build) is finalized at exit only if we started it, after every solver object is gone.
void ensure_kokkos() {
  if (Kokkos::is_initialized()) return;
  Kokkos::initialize();
  std::atexit([] {
    if (Kokkos::is_initialized()) Kokkos::finalize();
  });
}

/// Sets `key` (a path "list/sublist/name" for sublists) to `text` read as bool, integer, number or string.
void set_parameter(Teuchos::ParameterList& list, const std::string& key, const std::string& text) {
  const auto slash = key.find('/');
  if (slash != std::string::npos) {
    set_parameter(list.sublist(key.substr(0, slash)), key.substr(slash + 1), text);
    return;
  }
  if (text == "true" || text == "false") {
    list.set(key, text == "true");
    return;
  }
  char* end = nullptr;
  const long long i = std::strtoll(text.c_str(), &end, 10);
  if (!text.empty() && *end == '\0') {
    list.set(key, static_cast<int>(i));
    return;
  }
  const double d = std::strtod(text.c_str(), &end);
  if (!text.empty() && *end == '\0') {
    list.set(key, d);
    return;
  }
  list.set(key, text);
}

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

class TrilinosPressureSolver final : public PressureSolver {
 public:
  TrilinosPressureSolver(const PressureSolverSettings& s, MPI_Comm comm) : settings_(s) {
    ensure_kokkos();
    comm_ = rcp(new Teuchos::MpiComm<int>(comm));
    MPI_Comm_dup(comm, &raw_comm_);
    n_ranks_ = comm_->getSize();
    rank_ = comm_->getRank();
    if (name_of(krylov_solver_names(), s.solver) == "?")
      throw std::invalid_argument("fluid.solver: unknown solver " + std::to_string(static_cast<int>(s.solver)) +
                                  " (expected one of: " + join_names(krylov_solver_names()) + ")");
    if (name_of(preconditioner_names(), s.preconditioner) == "?")
      throw std::invalid_argument("fluid.preconditioner: unknown preconditioner " +
                                  std::to_string(static_cast<int>(s.preconditioner)) + " (expected one of: " +
                                  join_names(preconditioner_names()) + ")");
    if (s.preconditioner == Preconditioner::ssor) omega_ = 1.4;  // measured best on the dam break (docs/performance.md)
    rebuild_every_ = std::max(1, s.rebuild_every);
    for (const auto& [key, value] : s.parameters) {
      if (key == "sgs: omega")
        omega_ = std::stod(value);
      else if (key == "sgs: ifpack2")
        sgs_ifpack2_ = value == "true";
      else if (key.rfind("belos: ", 0) == 0)
        set_parameter(belos_params_, key.substr(7), value);
      else
        set_parameter(prec_params_, key, value);
    }
    auto params = rcp(new Teuchos::ParameterList);
    params->set("Convergence Tolerance", s.tolerance);
    params->set("Maximum Iterations", s.max_iterations);
    params->set("Implicit Residual Scaling", std::string("Norm of RHS"));
    if (s.solver == KrylovSolver::gmres) params->set("Explicit Residual Scaling", std::string("Norm of RHS"));
    params->set("Verbosity", 0);
    std::string manager = s.solver == KrylovSolver::cg ? "PSEUDOBLOCK CG" : "PSEUDOBLOCK GMRES";
    if (belos_params_.isParameter("manager")) {  // expert: "belos: manager" = a Belos solver name
      manager = belos_params_.get<std::string>("manager");
      belos_params_.remove("manager");
    }
    params->setParameters(belos_params_);
    Belos::SolverFactory<Scalar, MV, OP> factory;
    belos_ = factory.create(manager, params);
    belos_list_ = params;
    belos_tolerance_ = s.tolerance;
    eisenstat_ = (s.preconditioner == Preconditioner::sgs || s.preconditioner == Preconditioner::ssor) && !sgs_ifpack2_;
  }

  ~TrilinosPressureSolver() override {
    // Release every Tpetra object before the communicator goes.
    belos_ = Teuchos::null;
    eis_ = Teuchos::null;
    bh_ = y_ = Teuchos::null;
    muelu_ = Teuchos::null;
    ifpack_ = Teuchos::null;
    A_ = Teuchos::null;
    x_ = b_ = r_ = Teuchos::null;
    importer_ = Teuchos::null;
    col_map_ = Teuchos::null;
    row_map_ = Teuchos::null;
    comm_ = Teuchos::null;
    MPI_Comm_free(&raw_comm_);
  }

  std::size_t memory_bytes() const override {
    std::size_t bytes = 0;
    if (!A_.is_null()) bytes += A_->getNodeNumEntries() * (sizeof(Scalar) + sizeof(LO)) + (A_->getNodeNumRows() + 1) * sizeof(std::size_t);
    if (!x_.is_null()) bytes += 3 * x_->getLocalLength() * sizeof(Scalar);
    bytes += precond_bytes_;
    return bytes;
  }

  void save_state(BinaryWriter& out) const override {
    out.section("pressure_solver");
    out.string(std::string(to_string(settings_.preconditioner)));
    out.u64(solves_since_setup_);
    out.i64(iterations_after_setup_);
    out.boolean(force_setup_);
    out.f64(lambda_max_);
    out.u64(map_rows_);
    out.u64(n_solves_);
    // A kept preconditioner: the matrix it was set up on (one rank: all rows), to build it again on load.
    const bool kept = keeps_setup() && !(settings_.preconditioner == Preconditioner::muelu ? muelu_.is_null() : ifpack_.is_null());
    const bool saved = kept && n_ranks_ == 1;
    out.boolean(kept);
    out.boolean(saved);
    if (!saved) return;
    out.array(setup_sys_.row_id);
    out.array(setup_sys_.row_ptr);
    out.array(setup_sys_.col);
    out.array(setup_sys_.value);
  }

  bool load_state(BinaryReader& in) override {
    in.expect_section("pressure_solver");
    const std::string prec = in.string("the preconditioner");
    const std::size_t since = in.u64("the solves since the preconditioner setup");
    const int iterations = static_cast<int>(in.i64("the iterations after the setup"));
    const bool force = in.boolean("the setup flag");
    const double lambda = in.f64("the eigenvalue bound");
    const std::size_t rows = in.u64("the row count");
    n_solves_ = in.u64("the solve count");
    const bool kept = in.boolean("the kept-preconditioner flag");
    const bool saved = in.boolean("the setup-matrix flag");
    LocalRows s;
    if (saved) {
      s.row_id = in.array<GlobalId>("the setup matrix rows");
      s.row_ptr = in.array<std::size_t>("the setup matrix rows");
      s.col = in.array<LocalIndex>("the setup matrix columns");
      s.value = in.array<Real>("the setup matrix values", s.col.size());
      if (s.row_ptr.size() != s.n_rows() + 1 || s.row_ptr.back() != s.col.size())
        in.fail("the pressure solver's setup matrix is inconsistent");
      for (const LocalIndex c : s.col)
        if (c < 0 || static_cast<std::size_t>(c) >= s.n_rows()) in.fail("the pressure solver's setup matrix is inconsistent");
    }
    restore_pending_ = false;
    map_rows_ = rows;
    if (prec != to_string(settings_.preconditioner)) {  // a restart that changes the preconditioner: a fresh start
      solves_since_setup_ = 0;
      iterations_after_setup_ = 0;
      force_setup_ = true;
      lambda_max_ = 0;
      return true;  // not the original run, but by the user's choice (reported with the case change)
    }
    solves_since_setup_ = since;
    iterations_after_setup_ = iterations;
    force_setup_ = force;
    lambda_max_ = lambda;
    if (saved) {
      setup_sys_ = std::move(s);
      restore_pending_ = n_ranks_ == 1 && keeps_setup();
    }
    if (kept && !restore_pending_) {
      force_setup_ = true;  // the kept preconditioner cannot be rebuilt here: set up anew
      return false;
    }
    return true;
  }

  PressureSolveResult solve(const LocalRows& sys, std::vector<Real>& x) override {
    PressureSolveResult result;
    auto t0 = Clock::now();
    update_maps(sys);
    if (eisenstat_)
      setup_eisenstat(sys);
    else
      build_matrix(sys);
    // Right-hand side and warm start.
    {
      auto b = b_->getLocalViewHost(Tpetra::Access::OverwriteAll);
      auto xv = x_->getLocalViewHost(Tpetra::Access::OverwriteAll);
      for (std::size_t k = 0; k < sys.n_rows(); ++k) {
        b(k, 0) = sys.rhs[k];
        xv(k, 0) = x[k];
      }
    }
    result.t_matrix = seconds_since(t0);

    t0 = Clock::now();
    Teuchos::Array<Scalar> bnorm(1);
    b_->norm2(bnorm());
    if (bnorm[0] == 0) {  // A x = 0 with A SPD: x = 0
      std::fill(x.begin(), x.end(), 0.0);
      result.t_solve = seconds_since(t0);
      return result;
    }
    // This solve's relative tolerance: the settings', or the absolute one where that is looser (capped at
    // 0.1 so that a nearly zero right-hand side still gets a solve).
    result.tolerance = settings_.tolerance;
    if (sys.absolute_tolerance > 0)
      result.tolerance = std::max(result.tolerance, std::min<Scalar>(0.1, sys.absolute_tolerance / bnorm[0]));
    if (eisenstat_) return solve_eisenstat(sys, x, result, bnorm[0], t0);
    set_belos_tolerance(result.tolerance);
    RCP<OP> prec = setup_preconditioner(sys);
    result.t_setup = seconds_since(t0);

    t0 = Clock::now();
    auto problem = rcp(new Belos::LinearProblem<Scalar, MV, OP>(A_, x_, b_));
    if (!prec.is_null()) {
      if (settings_.solver == KrylovSolver::cg)
        problem->setLeftPrec(prec);
      else
        problem->setRightPrec(prec);
    }
    problem->setProblem();
    belos_->setProblem(problem);
    const Belos::ReturnType ret = belos_->solve();
    result.iterations = belos_->getNumIters();
    if (solves_since_setup_ == 0) iterations_after_setup_ = result.iterations;
    ++solves_since_setup_;
    if (settings_.rebuild_growth > 0 && solves_since_setup_ > 1 &&
        result.iterations > settings_.rebuild_growth * std::max(iterations_after_setup_, 1))
      force_setup_ = true;
    // True residual.
    A_->apply(*x_, *r_);
    r_->update(1.0, *b_, -1.0);
    Teuchos::Array<Scalar> rnorm(1);
    r_->norm2(rnorm());
    result.residual = rnorm[0] / bnorm[0];
    return finish(sys, x, result, ret, t0);
  }

 private:
  /// End of every solve: converged means Belos converged and the true residual is within the tolerance
  /// (with a factor 10 for the residual's different scaling); the solution goes back to all ranks.
  PressureSolveResult finish(const LocalRows& sys, std::vector<Real>& x, PressureSolveResult& result,
                             const Belos::ReturnType ret, const Clock::time_point t0) {
    result.converged = ret == Belos::Converged && std::isfinite(result.residual) &&
                       result.residual <= 10 * result.tolerance;
    copy_solution(sys, x);
    result.t_solve = seconds_since(t0);
    ++n_solves_;
    return result;
  }

  /// CG on the SGS-preconditioned system by Eisenstat's trick (EisenstatSystem); the true residual of
  /// A x = b decides: if it is above the tolerance, the solve continues from where it stopped with a
  /// tighter tolerance on the transformed residual (at most twice).
  PressureSolveResult solve_eisenstat(const LocalRows& sys, std::vector<Real>& x, PressureSolveResult& result,
                                      const Scalar bnorm, Clock::time_point t0) {
    EisenstatSystem& E = *eis_;
    CoarseLevel& C = E.coarse;
    const std::size_t n = sys.n_rows();
    Scalar tol = result.tolerance;
    {
      auto b = b_->getLocalViewHost(Tpetra::Access::ReadOnly);
      auto x0 = x_->getLocalViewHost(Tpetra::Access::ReadOnly);
      auto bh = bh_->getLocalViewHost(Tpetra::Access::OverwriteAll);
      auto y = y_->getLocalViewHost(Tpetra::Access::OverwriteAll);
      E.t.resize(n);
      const Scalar* rhs = n ? &b(0, 0) : nullptr;
      if (C.m > 0) {  // the deflated right-hand side P bh = S (b - A Z E^-1 Z^T b)
        C.restrict_rows(rhs, C.g);
        C.solve(C.g);
        Scalar norms[2] = {0, 0};
        for (std::size_t i = 0; i < n; ++i) {
          E.t[i] = rhs[i] - C.az.row_dot(i, C.g.data());
          norms[0] += rhs[i] * rhs[i];
          norms[1] += E.t[i] * E.t[i];
        }
        if (n_ranks_ > 1) MPI_Allreduce(MPI_IN_PLACE, norms, 2, MPI_DOUBLE, MPI_SUM, raw_comm_);
        // The same stop on the transformed residual as without the coarse level (it is relative to
        // the norm of the deflated right-hand side).
        if (norms[1] > 0) tol = std::min<Scalar>(0.1, tol * std::sqrt(norms[0] / norms[1]));
        rhs = E.t.data();
      }
      E.z.resize(n);  // (D' + U) x0, for the start y0
      if (n) E.forward_and_upper_times(rhs, &bh(0, 0), &x0(0, 0), E.z.data());
      for (std::size_t i = 0; i < n; ++i) {
        bh(i, 0) *= E.sqrt_dprime[i];
        y(i, 0) = E.z[i] / E.sqrt_dprime[i];
      }
    }
    result.t_setup = seconds_since(t0);

    t0 = Clock::now();
    set_belos_tolerance(tol);
    auto problem = rcp(new Belos::LinearProblem<Scalar, MV, OP>(eis_, y_, bh_));
    problem->setProblem();
    belos_->setProblem(problem);
    Belos::ReturnType ret = Belos::Unconverged;
    for (int round = 0; round < 3; ++round) {
      ret = belos_->solve();
      result.iterations += belos_->getNumIters();
      {  // x = (D' + U)^-1 D'^(1/2) y
        auto y = y_->getLocalViewHost(Tpetra::Access::ReadOnly);
        auto xv = x_->getLocalViewHost(Tpetra::Access::OverwriteAll);
        E.t.resize(n);
        for (std::size_t i = 0; i < n; ++i) E.t[i] = E.sqrt_dprime[i] * y(i, 0);
        if (n) E.backward(E.t.data(), &xv(0, 0));
      }
      {
        auto xv = x_->getLocalViewHost(Tpetra::Access::ReadWrite);
        auto bv = b_->getLocalViewHost(Tpetra::Access::ReadOnly);
        auto rv = r_->getLocalViewHost(Tpetra::Access::OverwriteAll);
        Scalar* x = n ? &xv(0, 0) : nullptr;
        Scalar* r = n ? &rv(0, 0) : nullptr;
        E.residual(n ? &bv(0, 0) : nullptr, x, r);
        if (C.m > 0) {  // the coarse part: x += Z E^-1 Z^T r, r -= A Z E^-1 Z^T r
          C.restrict_rows(r, C.g);
          C.solve(C.g);
          for (std::size_t i = 0; i < n; ++i) {
            if (C.of_row[i] >= 0) x[i] += C.g[static_cast<std::size_t>(C.of_row[i])];
            r[i] -= C.az.row_dot(i, C.g.data());
          }
        }
      }
      Teuchos::Array<Scalar> rnorm(1);
      r_->norm2(rnorm());
      result.residual = rnorm[0] / bnorm;
      if (!(result.residual > result.tolerance) || ret != Belos::Converged || round == 2) break;
      tol *= 0.5 * result.tolerance / result.residual;
      set_belos_tolerance(tol);
      problem->setProblem();  // continue from the current y
    }
    return finish(sys, x, result, ret, t0);
  }

  /// Belos' convergence tolerance for the next solve (parameters passed again only when it changes).
  void set_belos_tolerance(const Scalar tol) {
    if (tol == belos_tolerance_) return;
    belos_tolerance_ = tol;
    belos_list_->set("Convergence Tolerance", tol);
    belos_->setParameters(belos_list_);
  }

  /// The EisenstatSystem of this system's rows (the matrix split into L, D, U and O).
  void setup_eisenstat(const LocalRows& sys) {
    if (eis_.is_null()) eis_ = rcp(new EisenstatSystem);  // kept: its arrays keep their capacity
    if (eis_->row_map != row_map_) {
      eis_->row_map = row_map_;
      bh_ = rcp(new MV(row_map_, 1));
      y_ = rcp(new MV(row_map_, 1));
    }
    EisenstatSystem& E = *eis_;
    E.importer = importer_;
    if (!importer_.is_null() && (E.t_col.is_null() || E.t_col->getMap() != col_map_)) {
      E.t_row = rcp(new MV(row_map_, 1));
      E.t_col = rcp(new MV(col_map_, 1));
    }
    // A re-solve with a few rows changed on the rows and columns of the last setup: those rows only.
    if (sys.values_only && eis_row_map_ == row_map_ && eis_col_map_ == col_map_ && E.size() == sys.n_rows()) {
      E.update_rows(sys, sys.changed_rows, omega_);
      return;
    }
    E.set_rows(sys, omega_, raw_comm_, n_ranks_);
    eis_row_map_ = row_map_;
    eis_col_map_ = col_map_;
    precond_bytes_ = E.bytes();
  }

  /// Row map (this rank's row ids) and vectors, column map (the row ids, then the remote ids) and Import,
  /// each made anew only when it changed on some rank.
  void update_maps(const LocalRows& sys) {
    int changed[2] = {row_map_.is_null() || sys.row_id != row_ids_ ? 1 : 0,
                      sys.remote_id != remote_ids_ ? 1 : 0};
    if (n_ranks_ > 1) MPI_Allreduce(MPI_IN_PLACE, changed, 2, MPI_INT, MPI_MAX, raw_comm_);
    if (changed[0]) {
      row_ids_ = sys.row_id;
      row_map_ = rcp(new Map(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(),
                             Teuchos::ArrayView<const GO>(row_ids_.data(), static_cast<int>(row_ids_.size())), 0, comm_));
      // Chebyshev's bound and the kept preconditioners belong to the old unknowns.
      if (map_rows_ != row_map_->getGlobalNumElements()) lambda_max_ = 0;
      map_rows_ = row_map_->getGlobalNumElements();
      x_ = rcp(new MV(row_map_, 1));
      b_ = rcp(new MV(row_map_, 1));
      r_ = rcp(new MV(row_map_, 1));
      muelu_ = Teuchos::null;
      ifpack_ = Teuchos::null;
    }
    if (n_ranks_ == 1) {
      col_map_ = row_map_;
      importer_ = Teuchos::null;
      return;
    }
    if (changed[0] || changed[1]) {
      remote_ids_ = sys.remote_id;
      col_ids_ = row_ids_;
      col_ids_.insert(col_ids_.end(), remote_ids_.begin(), remote_ids_.end());
      col_map_ = rcp(new Map(Teuchos::OrdinalTraits<Tpetra::global_size_t>::invalid(),
                             Teuchos::ArrayView<const GO>(col_ids_.data(), static_cast<int>(col_ids_.size())), 0, comm_));
      Teuchos::Array<int> remote_pids(sys.remote_rank.begin(), sys.remote_rank.end());
      importer_ = rcp(new Tpetra::Import<LO, GO, Node>(row_map_, col_map_, remote_pids));
    }
  }

  /// The Tpetra matrix of this rank's rows, from the CRS arrays (after update_maps).
  void build_matrix(const LocalRows& sys) {
    A_ = Teuchos::null;  // release the old arrays first
    A_ = crs_matrix(sys, col_map_);
    A_->expertStaticFillComplete(row_map_, row_map_, importer_);
  }

  /// A Tpetra matrix of `sys`'s rows on the row map and `columns`, without the entries off the diagonal
  /// that hold an exact zero (a caller's padding, LocalRows::values_only): they would change the graph that
  /// MueLu's aggregation and the incomplete factorisation see, not the operator.
  RCP<Matrix> crs_matrix(const LocalRows& sys, const RCP<const Map>& columns) const {
    using RowPtr = Matrix::local_graph_device_type::row_map_type::non_const_type;
    using Entries = Matrix::local_graph_device_type::entries_type::non_const_type;
    using Values = Matrix::local_matrix_device_type::values_type;
    const std::size_t n = sys.n_rows();
    const auto kept = [&](const std::size_t i, const std::size_t k) {
      return sys.value[k] != 0 || sys.col[k] == static_cast<LocalIndex>(i);
    };
    std::size_t nnz = 0;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = sys.row_ptr[i]; k < sys.row_ptr[i + 1]; ++k) nnz += kept(i, k);
    RowPtr ptr(Kokkos::ViewAllocateWithoutInitializing("ptr"), n + 1);
    Entries ind(Kokkos::ViewAllocateWithoutInitializing("ind"), nnz);
    Values val(Kokkos::ViewAllocateWithoutInitializing("val"), nnz);
    std::size_t e = 0;
    ptr(0) = 0;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t k = sys.row_ptr[i]; k < sys.row_ptr[i + 1]; ++k)
        if (kept(i, k)) {
          ind(e) = sys.col[k];
          val(e++) = sys.value[k];
        }
      ptr(i + 1) = e;
    }
    return rcp(new Matrix(row_map_, columns, ptr, ind, val));
  }

  /// A preconditioner (muelu, ilu) kept as built between setups, which a checkpoint saves by its matrix.
  bool keeps_setup() const {
    return rebuild_every_ > 1 && (settings_.preconditioner == Preconditioner::muelu || settings_.preconditioner == Preconditioner::ilu);
  }

  /// The matrix of `sys` on one rank (the setup matrix a restart rebuilds a kept preconditioner from).
  RCP<Matrix> serial_matrix(const LocalRows& sys) const {
    auto A = crs_matrix(sys, row_map_);
    A->expertStaticFillComplete(row_map_, row_map_);
    return A;
  }

  RCP<MueLu::TpetraOperator<Scalar, LO, GO, Node>> make_muelu(const RCP<Matrix>& A) const {
    Teuchos::ParameterList params;
    params.set("verbosity", std::string("none"));
    params.set("multigrid algorithm", std::string("sa"));
    params.set("coarse: type", std::string("RELAXATION"));
    params.set("coarse: max size", 64);
    // MueLu 13.2's phase-1 aggregation (AggregationPhase1Algorithm::BuildAggregates) sizes its scratch
    // list by the longest matrix row and writes one past it when an aggregate reaches that size
    // (valgrind: "Invalid write of size 4 ... 0 bytes after a block"; heap corruption on 2 ranks).
    // Capping the aggregate size well below the row length (~45 at re = 4 l0) keeps it in bounds;
    // 2D smoothed aggregation builds aggregates of about 9-25 nodes anyway.
    params.set("aggregation: max agg size", 24);
    params.set("smoother: type", std::string("CHEBYSHEV"));
    params.setParameters(prec_params_);
    RCP<OP> A_op = A;
    return MueLu::CreateTpetraPreconditioner(A_op, params);
  }

  /// The preconditioner for this solve: a full setup when due, else the kept one (right after a restart
  /// rebuilt, identically, from the matrix it was set up on).
  RCP<OP> setup_preconditioner(const LocalRows& sys) {
    const Preconditioner p = settings_.preconditioner;
    if (p == Preconditioner::none) return Teuchos::null;
    // A restart rebuilds the kept preconditioner unless the row count changed since its setup (the
    // original run dropped it then, as build_matrix does).
    const bool restore = restore_pending_ && setup_sys_.row_id == sys.row_id;
    restore_pending_ = false;
    // Chebyshev keeps only its eigenvalue bound (reset with the row map).
    const bool missing = p == Preconditioner::muelu ? muelu_.is_null() : p == Preconditioner::chebyshev ? !(lambda_max_ > 0) : ifpack_.is_null();
    const bool due = force_setup_ || solves_since_setup_ >= static_cast<std::size_t>(rebuild_every_) ||
                     (missing && !restore);
    // The power iterations of Chebyshev (also MueLu's smoother) start from Tpetra's randomize(), which
    // seeds from std::rand(): reseed, so that a setup depends on the matrix only, not on how many setups
    // came before (a restarted run then reproduces the uninterrupted one bit for bit).
    std::srand(1);
    if (due && keeps_setup()) setup_sys_ = sys;  // saved by a checkpoint to rebuild the kept preconditioner
    if (p == Preconditioner::muelu) {
      if (due) {
        muelu_ = make_muelu(A_);
        mark_setup();
      } else if (restore) {
        muelu_ = make_muelu(serial_matrix(setup_sys_));
      }
      precond_bytes_ = 2 * A_->getNodeNumEntries() * (sizeof(Scalar) + sizeof(LO));  // rough: P, R, coarse A
      return muelu_;
    }
    // Jacobi and SGS: always on the new matrix. Chebyshev: on the new matrix, with the kept eigenvalue
    // estimate between full setups. ILU(0): kept as built.
    if (p == Preconditioner::ilu && !due && !restore) return ifpack_;
    const RCP<Matrix> A = p == Preconditioner::ilu && !due ? serial_matrix(setup_sys_) : A_;
    Teuchos::ParameterList params;
    std::string type;
    if (p == Preconditioner::jacobi || p == Preconditioner::sgs || p == Preconditioner::ssor) {  // sgs / ssor here only with "sgs: ifpack2" = true
      type = "RELAXATION";
      params.set("relaxation: type", std::string(p == Preconditioner::jacobi ? "Jacobi" : "Symmetric Gauss-Seidel"));
      params.set("relaxation: sweeps", 1);
      if (p != Preconditioner::jacobi) params.set("relaxation: damping factor", omega_);
    } else if (p == Preconditioner::chebyshev) {
      type = "CHEBYSHEV";
      params.set("chebyshev: degree", 3);
      if (!due && lambda_max_ > 0) {  // no power iterations: the last estimate
        params.set("chebyshev: max eigenvalue", lambda_max_);
        params.set("chebyshev: assume matrix unchanged", true);
      }
    } else {  // ilu: ILU(0) on each rank's block (additive Schwarz, no overlap)
      type = "SCHWARZ";
      params.set("schwarz: overlap level", 0);
      params.set("schwarz: use reordering", false);
      params.set("inner preconditioner name", std::string("RILUK"));
      Teuchos::ParameterList inner;
      inner.set("fact: iluk level-of-fill", 0);
      params.set("inner preconditioner parameters", inner);
    }
    params.setParameters(prec_params_);
    Ifpack2::Factory factory;
    ifpack_ = factory.create<Tpetra::RowMatrix<Scalar>>(type, A);
    ifpack_->setParameters(params);
    ifpack_->initialize();
    ifpack_->compute();
    if (p == Preconditioner::chebyshev && (due || lambda_max_ <= 0)) {
      using Cheb = Ifpack2::Chebyshev<Tpetra::RowMatrix<Scalar>>;
      if (const auto* cheb = dynamic_cast<const Cheb*>(ifpack_.get())) lambda_max_ = cheb->getLambdaMaxForApply();
    }
    if (due) mark_setup();
    precond_bytes_ = p == Preconditioner::ilu ? A_->getNodeNumEntries() * (sizeof(Scalar) + sizeof(LO)) : 2 * x_->getLocalLength() * sizeof(Scalar);
    return ifpack_;
  }

  void mark_setup() {
    solves_since_setup_ = 0;
    force_setup_ = false;
  }

  void copy_solution(const LocalRows& sys, std::vector<Real>& x) const {
    auto xv = x_->getLocalViewHost(Tpetra::Access::ReadOnly);
    x.resize(sys.n_rows());
    for (std::size_t k = 0; k < sys.n_rows(); ++k) x[k] = xv(k, 0);
  }

  PressureSolverSettings settings_;
  RCP<const Teuchos::Comm<int>> comm_;
  MPI_Comm raw_comm_ = MPI_COMM_NULL;
  int n_ranks_ = 1, rank_ = 0;
  RCP<const Map> row_map_;
  RCP<Matrix> A_;
  RCP<MV> x_, b_, r_;
  RCP<Belos::SolverManager<Scalar, MV, OP>> belos_;
  RCP<MueLu::TpetraOperator<Scalar, LO, GO, Node>> muelu_;
  RCP<Ifpack2::Preconditioner<Scalar, LO, GO, Node>> ifpack_;
  std::size_t n_solves_ = 0;
  bool eisenstat_ = false, sgs_ifpack2_ = false;
  double omega_ = 1.0;
  RCP<EisenstatSystem> eis_;
  RCP<const Map> eis_row_map_, eis_col_map_;  ///< the maps of the EisenstatSystem's last set_rows
  RCP<MV> bh_, y_;
  RCP<Teuchos::ParameterList> belos_list_;
  Scalar belos_tolerance_ = 0;  ///< the tolerance belos_ was last given
  int rebuild_every_ = 1;
  std::size_t solves_since_setup_ = 0;
  int iterations_after_setup_ = 0;
  bool force_setup_ = false;
  double lambda_max_ = 0;  ///< Chebyshev: the eigenvalue bound of the last full setup
  std::size_t map_rows_ = 0;  ///< rows of the last system
  LocalRows setup_sys_;    ///< kept preconditioners (keeps_setup()): the rows of the matrix of the last setup
  bool restore_pending_ = false;  ///< after load_state: rebuild the kept preconditioner from setup_sys_
  Teuchos::ParameterList prec_params_, belos_params_;
  RCP<const Map> col_map_;
  RCP<const Tpetra::Import<LO, GO, Node>> importer_;
  std::vector<GO> row_ids_, remote_ids_, col_ids_;  ///< the ids the maps were made of
  std::size_t precond_bytes_ = 0;
};

}  // namespace

std::unique_ptr<PressureSolver> make_pressure_solver(const PressureSolverSettings& settings, MPI_Comm comm) {
  return std::make_unique<TrilinosPressureSolver>(settings, comm);
}

}  // namespace mpsfsi
