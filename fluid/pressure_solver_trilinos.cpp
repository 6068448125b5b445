// Trilinos implementation of the pressure solve (seed 004 eq. 23): the only translation unit that
// includes Tpetra, Belos, MueLu and Ifpack2. The row map is made of this rank's row ids (particle global
// ids) and the column map of these and the remote ids, with an Import from the owners the caller names;
// both are kept while the ids do not change. SSOR / SGS run CG on Eisenstat's split system (no Tpetra
// matrix); the other preconditioners get a Tpetra::CrsMatrix made straight from the local CRS arrays
// (Kokkos views + expertStaticFillComplete): Belos CG or GMRES with MueLu (coarse solver RELAXATION: the
// default KLU2 coarse solve is wrong on 2 ranks in this build, see shared/notes/trilinos-on-debian.md) or
// Ifpack2 Chebyshev / ILU(0) (additive Schwarz) / Jacobi / symmetric Gauss-Seidel. A preconditioner may be
// kept for several solves (rebuild_every): it is applied as built on its own, earlier matrix, which stays
// a valid SPD preconditioner of the new one. The true residual is checked after every solve.
#include "fluid/pressure_solver.hpp"

#include "core/binary_io.hpp"

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

using Clock = std::chrono::steady_clock;
double seconds_since(const Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

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

/// Symmetric Gauss-Seidel / SSOR (relaxation omega) preconditioned system by Eisenstat's trick, on each
/// rank's diagonal block (block Jacobi between ranks, so it stays symmetric). With A = L + D + U + O (L, U
/// the strictly lower / upper parts of the rank's block, O the couplings to other ranks' rows) and
/// D' = D / omega, CG runs on the SPD system
///   Ah y = bh,  Ah = S A S^T,  S = D'^(1/2) (D' + L)^-1,  bh = S b,  x = S^T y,
/// and one product with Ah costs one pass over the matrix instead of three (SpMV + forward and backward
/// sweeps): with w = D'^(1/2) v and t = (D' + U)^-1 w,
///   Ah v = D'^(1/2) (t + (D' + L)^-1 (w + (D - 2 D') t + O t)).
/// The system holds A itself, split: L with its rows in order, U with its rows last one first, so that
/// each sweep streams through its own half of the matrix in increasing addresses, and O with column-map
/// ids. No Tpetra matrix is built on this path.
class EisenstatSystem final : public OP {
 public:
  CrsBlock lower;      ///< L: columns are this rank's row indices
  CrsBlock upper_rev;  ///< U: block row r is matrix row n - 1 - r; columns are this rank's row indices
  CrsBlock other;      ///< O: column-map ids
  std::vector<Scalar> diag, inv_dprime, sqrt_dprime, d_minus_2dprime;
  RCP<const Map> row_map;
  RCP<const Tpetra::Import<LO, GO, Node>> importer;  // null on one rank
  RCP<MV> t_row, t_col;                              // t on the row and column maps when importer is set
  mutable std::vector<Scalar> t, z;

  RCP<const Map> getDomainMap() const override { return row_map; }
  RCP<const Map> getRangeMap() const override { return row_map; }
  std::size_t size() const { return diag.size(); }
  std::size_t bytes() const {
    return lower.bytes() + upper_rev.bytes() + other.bytes() + 6 * diag.capacity() * sizeof(Scalar);
  }

  /// Splits this rank's rows and sets up the relaxation. Throws if a row has no positive diagonal.
  void set_rows(const LocalRows& sys, const Scalar omega) {
    const std::size_t n = sys.n_rows();
    const auto n_own = static_cast<LocalIndex>(n);
    lower.clear();
    upper_rev.clear();
    other.clear();
    diag.assign(n, 0.0);
    std::vector<int>& upper_count = upper_rev.ptr;  // counts first, offsets after
    upper_count.assign(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const auto me = static_cast<LocalIndex>(i);
      for (std::size_t k = sys.row_ptr[i]; k < sys.row_ptr[i + 1]; ++k) {
        const LocalIndex c = sys.col[k];
        if (c == me) {
          diag[i] += sys.value[k];
        } else if (c >= n_own) {
          other.col.push_back(c);
          other.val.push_back(sys.value[k]);
        } else if (c < me) {
          lower.col.push_back(c);
          lower.val.push_back(sys.value[k]);
        } else {
          ++upper_count[n - i];
        }
      }
      lower.ptr.push_back(static_cast<int>(lower.col.size()));
      other.ptr.push_back(static_cast<int>(other.col.size()));
      if (!(diag[i] > 0))
        throw std::runtime_error("pressure solve (sgs): the row of global id " + std::to_string(sys.row_id[i]) +
                                 " has no positive diagonal");
    }
    for (std::size_t r = 0; r < n; ++r) upper_count[r + 1] += upper_count[r];
    upper_rev.col.resize(static_cast<std::size_t>(upper_count[n]));
    upper_rev.val.resize(upper_rev.col.size());
    for (std::size_t i = 0; i < n; ++i) {
      const auto me = static_cast<LocalIndex>(i);
      auto out = static_cast<std::size_t>(upper_rev.ptr[n - 1 - i]);
      for (std::size_t k = sys.row_ptr[i]; k < sys.row_ptr[i + 1]; ++k) {
        const LocalIndex c = sys.col[k];
        if (c > me && c < n_own) {
          upper_rev.col[out] = c;
          upper_rev.val[out++] = sys.value[k];
        }
      }
    }
    inv_dprime.resize(n);
    sqrt_dprime.resize(n);
    d_minus_2dprime.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const Scalar dprime = diag[i] / omega;
      inv_dprime[i] = 1.0 / dprime;
      sqrt_dprime[i] = std::sqrt(dprime);
      d_minus_2dprime[i] = diag[i] - 2 * dprime;
    }
  }

  /// (D' + U)^-1 w, backward (out may be w).
  void backward(const Scalar* w, Scalar* out) const {
    const std::size_t n = size();
    for (std::size_t r = 0; r < n; ++r) {
      const std::size_t i = n - 1 - r;
      out[i] = (w[i] - upper_rev.row_dot(r, out)) * inv_dprime[i];
    }
  }
  /// (D' + L)^-1 s, forward (out may be s).
  void forward(const Scalar* s, Scalar* out) const {
    const std::size_t n = size();
    for (std::size_t i = 0; i < n; ++i) out[i] = (s[i] - lower.row_dot(i, out)) * inv_dprime[i];
  }
  /// (D' + U) x, this rank's block only.
  Scalar upper_times(const std::size_t i, const Scalar* x) const {
    return x[i] / inv_dprime[i] + upper_rev.row_dot(size() - 1 - i, x);
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
    for (std::size_t i = 0; i < n; ++i) {
      Scalar ax = diag[i] * x[i] + lower.row_dot(i, x) + upper_rev.row_dot(n - 1 - i, x);
      if (xc) ax += other.row_dot(i, xc);
      r[i] = b[i] - ax;
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
        // Backward sweep t = (D' + U)^-1 w with w = D'^(1/2) v, fused with s = w + (D - 2 D') t in z.
        for (std::size_t r = 0; r < n; ++r) {
          const std::size_t i = n - 1 - r;
          const Scalar w = sqrt_dprime[i] * v[i];
          tp[i] = (w - upper_rev.row_dot(r, tp)) * inv_dprime[i];
          zp[i] = w + d_minus_2dprime[i] * tp[i];
        }
      }
      if (const Scalar* tc = import(tp))  // s += O t (couplings to the other ranks' rows)
        for (std::size_t i = 0; i < n; ++i) zp[i] += other.row_dot(i, tc);
      // Forward sweep in place z = (D' + L)^-1 s (row i reads s_i before writing it, and finished rows
      // j < i), fused with Y = alpha D'^(1/2) (t + z) + beta Y.
      auto yv = Y.getLocalViewHost(Tpetra::Access::ReadWrite);
      for (std::size_t i = 0; i < n; ++i) {
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
    set_belos_tolerance(result.tolerance);
    if (eisenstat_) return solve_eisenstat(sys, x, result, bnorm[0], t0);
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
    const std::size_t n = sys.n_rows();
    {
      auto b = b_->getLocalViewHost(Tpetra::Access::ReadOnly);
      auto x0 = x_->getLocalViewHost(Tpetra::Access::ReadOnly);
      auto bh = bh_->getLocalViewHost(Tpetra::Access::OverwriteAll);
      auto y = y_->getLocalViewHost(Tpetra::Access::OverwriteAll);
      E.forward(&b(0, 0), &bh(0, 0));
      for (std::size_t i = 0; i < n; ++i) {
        bh(i, 0) *= E.sqrt_dprime[i];
        y(i, 0) = E.upper_times(i, &x0(0, 0)) / E.sqrt_dprime[i];
      }
    }
    result.t_setup = seconds_since(t0);

    t0 = Clock::now();
    auto problem = rcp(new Belos::LinearProblem<Scalar, MV, OP>(eis_, y_, bh_));
    problem->setProblem();
    belos_->setProblem(problem);
    Scalar tol = result.tolerance;
    Belos::ReturnType ret = Belos::Unconverged;
    for (int round = 0; round < 3; ++round) {
      ret = belos_->solve();
      result.iterations += belos_->getNumIters();
      {  // x = (D' + U)^-1 D'^(1/2) y
        auto y = y_->getLocalViewHost(Tpetra::Access::ReadOnly);
        auto xv = x_->getLocalViewHost(Tpetra::Access::OverwriteAll);
        E.t.resize(n);
        for (std::size_t i = 0; i < n; ++i) E.t[i] = E.sqrt_dprime[i] * y(i, 0);
        E.backward(E.t.data(), &xv(0, 0));
      }
      {
        auto xv = x_->getLocalViewHost(Tpetra::Access::ReadOnly);
        auto bv = b_->getLocalViewHost(Tpetra::Access::ReadOnly);
        auto rv = r_->getLocalViewHost(Tpetra::Access::OverwriteAll);
        if (n) E.residual(&bv(0, 0), &xv(0, 0), &rv(0, 0));
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
    if (eis_.is_null() || eis_->row_map != row_map_) {
      eis_ = rcp(new EisenstatSystem);
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
    E.set_rows(sys, omega_);
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
    const std::size_t n_own = sys.n_rows();
    const std::size_t nnz = sys.col.size();
    using RowPtr = Matrix::local_graph_device_type::row_map_type::non_const_type;
    using Entries = Matrix::local_graph_device_type::entries_type::non_const_type;
    using Values = Matrix::local_matrix_device_type::values_type;
    RowPtr ptr(Kokkos::ViewAllocateWithoutInitializing("ptr"), n_own + 1);
    Entries ind(Kokkos::ViewAllocateWithoutInitializing("ind"), nnz);
    Values val(Kokkos::ViewAllocateWithoutInitializing("val"), nnz);
    for (std::size_t k = 0; k <= n_own; ++k) ptr(k) = sys.row_ptr[k];
    for (std::size_t k = 0; k < nnz; ++k) ind(k) = sys.col[k];
    for (std::size_t k = 0; k < nnz; ++k) val(k) = sys.value[k];
    A_ = Teuchos::null;  // release the old arrays first
    A_ = rcp(new Matrix(row_map_, col_map_, ptr, ind, val));
    A_->expertStaticFillComplete(row_map_, row_map_, importer_);
  }

  /// A preconditioner (muelu, ilu) kept as built between setups, which a checkpoint saves by its matrix.
  bool keeps_setup() const {
    return rebuild_every_ > 1 && (settings_.preconditioner == Preconditioner::muelu || settings_.preconditioner == Preconditioner::ilu);
  }

  /// The matrix of `sys` on one rank (the setup matrix a restart rebuilds a kept preconditioner from).
  RCP<Matrix> serial_matrix(const LocalRows& sys) const {
    using RowPtr = Matrix::local_graph_device_type::row_map_type::non_const_type;
    using Entries = Matrix::local_graph_device_type::entries_type::non_const_type;
    using Values = Matrix::local_matrix_device_type::values_type;
    const std::size_t n = sys.n_rows(), nnz = sys.col.size();
    RowPtr ptr(Kokkos::ViewAllocateWithoutInitializing("ptr"), n + 1);
    Entries ind(Kokkos::ViewAllocateWithoutInitializing("ind"), nnz);
    Values val(Kokkos::ViewAllocateWithoutInitializing("val"), nnz);
    for (std::size_t k = 0; k <= n; ++k) ptr(k) = sys.row_ptr[k];
    for (std::size_t k = 0; k < nnz; ++k) ind(k) = sys.col[k];
    for (std::size_t k = 0; k < nnz; ++k) val(k) = sys.value[k];
    auto A = rcp(new Matrix(row_map_, row_map_, ptr, ind, val));
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
