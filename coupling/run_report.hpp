// What a run reports as it goes, through its log (coupling/run_log.hpp): the projection of its cost before
// the first step and after the first steps, the progress line and its run.jsonl event, the ranks'
// distribution, and the summary at the end. The run loop (coupling/simulation.cpp) hands it where the run
// is (RunPosition); this part decides what is said and when.
#pragma once

#include "core/distribution.hpp"
#include "core/stopwatch.hpp"
#include "coupling/coupling_scheme.hpp"
#include "coupling/run_log.hpp"
#include "coupling/simulation.hpp"
#include "fluid/fluid_solver.hpp"

#include <mpi.h>

#include <string>

namespace mpsfsi {

/// Where a run is after its last step, as its reports see it.
struct RunPosition {
  Real t = 0, dt = 0;
  std::size_t step = 0;
  std::string limit = "-";   ///< what limited the last step's dt
  Real t_begin = 0;          ///< time and step at the start of this session (a restart's)
  std::size_t step_begin = 0;
  FluidStepReport fluid;     ///< the last fluid step
  CouplingWindow window;     ///< the last coupled window
};

/// Which participants a run has, and whether its coupling iterates.
struct RunParts {
  bool fluid = false, solid = false, implicit = false;
};

/// A duration as "42s", "3m05s" or "2h07m"; "?" when not finite or negative.
std::string format_duration(double seconds);

class RunReport {
 public:
  RunReport(RunLog& log, const CaseSpec& spec, const RunSettings& settings, RunParts parts, MPI_Comm comm);

  /// Before the first step: the number of steps the run needs at its first dt (and the solid's sub-steps),
  /// with a warning when that cannot finish in any sensible time (a collective).
  void projection(const ParticleSet& particles, Real t);
  /// After the first steps of this session (started at `start`): the projected number of steps and wall time
  /// at the measured rate (rank 0).
  void measured_projection(const RunPosition& at, Clock::time_point start);
  /// The progress line after a step, and every log_every steps (or when `final`) its run.jsonl event; on
  /// several ranks with the distribution's event (a collective then).
  void progress(const RunPosition& at, const RunSummary& summary, const Distribution& distribution,
                std::size_t n_owned, Clock::time_point start, bool final);
  /// The summary's run.jsonl event (rank 0).
  void summary(const RunSummary& summary, const RunPosition& at);

 private:
  /// Several ranks: the owned particles per rank, their imbalance, the time in owners and ghosts, the
  /// partitions so far (run.jsonl, event "distribution"; a collective).
  void distribution(const Distribution& distribution, std::size_t n_owned, std::size_t step);

  RunLog& log_;
  const CaseSpec& spec_;
  const RunSettings& settings_;
  RunParts parts_;
  MPI_Comm comm_;
  int rank_ = 0;
  int n_ranks_ = 1;
  std::size_t logged_step_ = static_cast<std::size_t>(-1);  ///< the last step written to run.jsonl
};

}  // namespace mpsfsi
