// The distributed linear solve of the pressure Poisson equation (seed 004 eq. 23) behind a small
// interface without Trilinos types. Each rank passes its rows (its particles' pressures, named by their
// global ids) with local column ids that reach other ranks' rows through a list of remote ids, and gets
// the solution of its rows back. The only implementation
// (fluid/pressure_solver_trilinos.cpp) uses Tpetra + Belos with MueLu or Ifpack2.
#pragma once

#include "core/types.hpp"
#include "fluid/fluid_parameters.hpp"

#include <mpi.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace mpsfsi {

class BinaryWriter;
class BinaryReader;

struct PressureSolverSettings {
  KrylovSolver solver = KrylovSolver::cg;
  /// sgs and ssor (symmetric Gauss-Seidel with
  /// relaxation 1 and 1.4) run CG on the split-preconditioned system by Eisenstat's trick (one pass over
  /// the matrix per iteration), on each rank's block.
  Preconditioner preconditioner = Preconditioner::muelu;
  Real tolerance = 1e-8;                  ///< relative residual ||b - Ax|| / ||b||
  int max_iterations = 500;
  /// Full preconditioner setup every N solves (1: every solve). In between, MueLu and ILU are applied as
  /// they were built, on an earlier matrix (still a fixed SPD operator: CG stays correct, only the
  /// iterations grow), and Chebyshev is rebuilt on the new matrix with the last eigenvalue estimate (no
  /// power iterations). Jacobi, SGS and SSOR are always rebuilt (their setup is one pass over the rows).
  int rebuild_every = 1;
  /// With rebuild_every > 1: set up again at the next solve when a solve took more than this factor times
  /// the iterations of the first solve after the last setup (e.g. after the particles were reordered).
  /// 0: off.
  Real rebuild_growth = 1.5;
  /// Expert (benchmarks): extra parameters for the preconditioner's package, by their MueLu / Ifpack2
  /// names, e.g. {"relaxation: sweeps", "2"}, "list/name" for a sublist; values are read as bool, integer,
  /// number or string and override the built-in choices. Keys "belos: NAME" go to Belos ("belos: manager"
  /// picks the Belos solver by name); "sgs: omega" sets the relaxation of sgs / ssor, "sgs: ifpack2" =
  /// true runs sgs / ssor through Ifpack2 RELAXATION instead (three matrix passes per iteration).
  std::map<std::string, std::string> parameters;
};

/// This rank's rows of the system in CRS form. Rows and columns are named by global ids (a particle's
/// global id for its pressure unknown); the rows of all ranks together are the unknowns, each on one rank.
/// Column ids are local: c < row_id.size() is this rank's row c, c >= row_id.size() is the other rank's
/// row remote_id[c - row_id.size()] (owned by rank remote_rank[...]); sorted within each row.
struct LocalRows {
  std::vector<GlobalId> row_id;
  std::vector<GlobalId> remote_id;
  std::vector<int> remote_rank;
  std::vector<std::size_t> row_ptr;   ///< size row_id.size() + 1
  std::vector<LocalIndex> col;
  std::vector<Real> value;
  std::vector<Real> rhs;              ///< size row_id.size()
  /// Coarse groups for the two-level SSOR: the group of each column (this rank's rows, then the remote
  /// columns), a key that names the same group on every rank (the fluid: a cell of a coarse grid over
  /// space, cut by the ranks' regions). A group's rows are on one rank, its owner, and the keys order the
  /// groups by owner first (all of rank r's keys below rank r + 1's). Empty: no coarse level.
  std::vector<std::int64_t> group;
  /// The solve may also stop when ||b - Ax||_2 (over all ranks) is at most this, whatever the relative
  /// tolerance says (0: off). The fluid sets it from fluid.density_tolerance.
  Real absolute_tolerance = 0;
  /// Set by a caller that re-solves with a few rows changed (the projection's active set): the rows, their
  /// columns (pattern), maps and groups are those of the last solve on every rank, and only the rows in
  /// `changed_rows` have new values and right-hand sides. A solver may then update its setup row by row;
  /// it may also ignore the hint and set up anew.
  bool values_only = false;
  std::vector<LocalIndex> changed_rows;

  std::size_t n_rows() const { return row_id.size(); }
};

/// Rank `rank`'s block of a system held whole (no remote columns) when its rows are split into
/// `n_ranks` contiguous blocks (the first n % n_ranks blocks one row longer). Tests and benchmarks.
LocalRows split_system(const LocalRows& whole, int rank, int n_ranks);

struct PressureSolveResult {
  int iterations = 0;
  Real residual = 0;          ///< true relative residual ||b - Ax|| / ||b|| (0 if b = 0)
  Real tolerance = 0;         ///< relative tolerance this solve used: max(settings, absolute / ||b||)
  bool converged = true;
  double t_matrix = 0;        ///< building the distributed matrix [s]
  double t_setup = 0;         ///< preconditioner setup [s]
  double t_solve = 0;         ///< Krylov solve, residual check and gather [s]
};

class PressureSolver {
 public:
  virtual ~PressureSolver() = default;
  /// Solve A x = b. `x` has one entry per row of this rank: in, the initial guess; out, the solution.
  /// Collective over the communicator.
  virtual PressureSolveResult solve(const LocalRows& system, std::vector<Real>& x) = 0;
  /// Bytes held by the matrix and the preconditioner on this rank (estimate).
  virtual std::size_t memory_bytes() const = 0;
  /// Checkpoints: the state carried from one solve to the next (setup counters, eigenvalue estimate and,
  /// for a preconditioner kept between setups (rebuild_every > 1, muelu or ilu), this rank's rows of the
  /// matrix it was set up on, from which load_state's run rebuilds the same preconditioner).
  virtual void save_state(BinaryWriter& out) const = 0;
  /// Restores what save_state wrote; throws StateFormatError when it does not fit these settings. Returns
  /// false when the next solves cannot be bit for bit those of the original run: a kept preconditioner
  /// saved on several ranks is set up anew at the next solve (the solution agrees to the tolerance).
  virtual bool load_state(BinaryReader& in) = 0;
};

/// Throws std::invalid_argument naming the bad setting.
std::unique_ptr<PressureSolver> make_pressure_solver(const PressureSolverSettings& settings, MPI_Comm comm);

}  // namespace mpsfsi
