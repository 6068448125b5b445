// Trilinos implementation of the pressure solve (seed 004 eq. 23): the only translation unit that
// includes Tpetra, Belos, MueLu and Ifpack2 (with fluid/eisenstat_system.hpp, its ssor / sgs system). The row
// map is made of this rank's row ids (particle global ids) and the column map of these and the remote ids (the
// remote ids only for the Eisenstat system, which keeps its own rows apart), with an Import from the owners the
// caller names; both are kept while the ids do not change. SSOR / SGS run CG on Eisenstat's split system (no Tpetra
// matrix); the other preconditioners get a Tpetra::CrsMatrix made straight from the local CRS arrays
// (Kokkos views + expertStaticFillComplete): Belos CG or GMRES with MueLu (coarse solver RELAXATION: the
// default KLU2 coarse solve is wrong on 2 ranks in this build, see docs/architecture.md, ## Numerical choices)
// or Ifpack2 Chebyshev / ILU(0) (additive Schwarz) / Jacobi / symmetric Gauss-Seidel. A preconditioner may be
// kept for several solves (rebuild_every): it is applied as built on its own, earlier matrix, which stays
// a valid SPD preconditioner of the new one. The true residual is checked after every solve.
#include "fluid/pressure_solver.hpp"

#include "fluid/eisenstat_system.hpp"

#include "core/binary_io.hpp"
#include "core/stopwatch.hpp"

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

using namespace trilinos_detail;  // the Tpetra types (Scalar, Map, MV, OP, LO, GO, Node) and the Eisenstat system
using Matrix = Tpetra::CrsMatrix<Scalar>;
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
    if (!importer_.is_null() && (E.t_ghost.is_null() || E.t_ghost->getMap() != col_map_ || E.t_row->getMap() != row_map_)) {
      E.t_row = rcp(new MV(row_map_, 1));
      E.t_ghost = rcp(new MV(col_map_, 1));
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

  /// Row map (this rank's row ids) and vectors, column map (the row ids, then the remote ids; the Eisenstat
  /// system: the remote ids only) and Import, each made anew only when it changed on some rank.
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
      col_ids_.clear();
      if (!eisenstat_) col_ids_ = row_ids_;
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
