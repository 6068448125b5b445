// The run loop (preCICE-style participant loop): per step the driver takes the fluid's stable dt,
// advances the fluid, advances the solid by N sub-steps of dt/N, checks the state, and writes frames
// and probes at the output interval. It also reports progress (an updating line on a terminal, plain
// lines otherwise), writes a JSON-lines run log, and stops with a diagnosis (and the last good frame)
// when the state becomes invalid. It writes checkpoints of the complete state and continues a run from one
// (coupling/checkpoint.hpp). Only this folder sees both the fluid and the solid.
#pragma once

#include "core/particles.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <mpi.h>

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpsfsi {

struct Checkpoint;
class OutputLock;

struct RunSettings {
  std::string output_dir;
  bool quiet = false;
  int log_every = 100;          ///< steps between plain log lines (when stdout is not a terminal)
  /// Simulated seconds between checkpoints (checkpoint_<t>.chk in output_dir, at the end of the first step
  /// reaching each multiple of it, and at the end of the run); 0: none.
  Real checkpoint_every = 0;
  int checkpoint_keep = 0;      ///< keep only the newest N checkpoints this run wrote; 0: all
  /// Stop after this many steps of this run (a frame of the state then reached is written); 0: at time.end.
  std::size_t max_steps = 0;
  /// Continue from this checkpoint (coupling/checkpoint.hpp) instead of the initial state. The scene must
  /// be the case's initial scene: the reference data (bonds, initial densities, wall and probe
  /// references) are rebuilt from it before the state is loaded.
  const Checkpoint* restart = nullptr;
  /// Restart: output files of output_dir to continue (truncated to their checkpoint size by
  /// prepare_restart_outputs); the others are started anew. The .pvd series is continued when
  /// continue_series, else started anew with the checkpoint's frame numbering.
  std::vector<std::string> append_files;
  bool continue_series = false;
  /// Rank 0: the lock of output_dir (core/output_lock.hpp); the run stops (OutputError) when the folder was
  /// removed or replaced. nullptr on the other ranks and in tests that do not lock.
  const OutputLock* output_lock = nullptr;
};

struct RunSummary {
  std::size_t n_steps = 0;
  Real end_time = 0;
  double wall_seconds = 0;
  double t_fluid = 0, t_solid = 0, t_output = 0;
  double t_coupling = 0;        ///< interface: surface flags, eq. 50 loads (coupled runs)
  std::size_t n_removed = 0;    ///< fluid particles removed because they left the domain
  std::size_t n_put_back = 0;   ///< fluid particles put back out of a wall, summed over the steps
  long peak_memory_kib = 0;     ///< peak resident memory of the largest process
  int n_ranks = 1;
  std::size_t owned_min = 0, owned_max = 0;  ///< owned particles of the least and most loaded rank at the end
  double t_halo = 0;            ///< owners, ghosts, their refreshes and partitions (the slowest rank) [s]
  int n_partitions = 0;
  int last_subcycles = 1;
  std::size_t n_subcycles_raised = 0;  ///< steps where the requested subcycles were raised to the solid limit
  Real last_solid_dt = 0;
  /// The steps of this run by the limit that set their dt (fluid_stable_dt's names, "end time", ...), and the
  /// smallest dt of the steps that a limit set (not the end time), with its limit and the time it started at.
  std::map<std::string, std::size_t> steps_by_limit;
  Real dt_min = 0, t_of_dt_min = 0;
  std::string limit_of_dt_min;
  std::string pvd_path;
  /// The implicit coupling (this session's steps): iterations in all and at most per step, steps, and steps that
  /// did not converge in coupling.implicit.max_iterations.
  std::size_t coupling_iterations = 0, coupling_windows = 0, n_unconverged = 0;
  int coupling_iterations_max = 0;
  /// The signal (SIGINT, SIGTERM) that stopped the run at the end of a step; 0 if it ran to its end.
  int interrupted_by = 0;
};

/// A run went unstable or left the admissible state; the message is the diagnosis.
class RunFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What a run needs from time t on at its first time step: printed by `check` and at the start of `run`.
struct RunProjection {
  Real dt = 0;                  ///< the first step: fluid step, or the solid's step in a solid-only run [s]
  std::string limit;            ///< what limits it ("cfl", "viscous", "solid stability", ...)
  double n_steps = 0;           ///< steps to the end time at that dt
  int subcycles = 1;            ///< solid sub-steps per fluid step (coupled runs)
  double n_solid_steps = 0;     ///< solid steps in all (sub-steps of a coupled run)
  double particle_steps = 0;    ///< all particles x fluid steps + solid particles x solid steps: the work
  /// More work than any sensible run: above 1e12 particle-steps (weeks on one core at the measured ~1.4 us
  /// per particle and step, docs/performance.md), or above 1e8 steps.
  bool absurd = false;
  /// "projection: ..." and, when absurd, a second line "warning: ...".
  std::string text() const;
};

/// The projection of a case from time t at the current state of `particles` (the first dt of the fluid's
/// limits, fluid_stable_dt, and of the solid's, dt_factor dp / c_p).
RunProjection project_run(const CaseSpec& spec, const ParticleSet& particles, Real t = 0, MPI_Comm comm = MPI_COMM_SELF);

/// Run a case to its end time. Throws RunFailure (after writing the last good frame) when the
/// state becomes invalid.
RunSummary run_case(const CaseSpec& spec, Scene scene, const RunSettings& settings, MPI_Comm comm);

/// Sub-steps per fluid step: the smallest N with dt_fluid / N <= dt_solid (auto, requested <= 0), or the
/// case's value raised to that when it would exceed dt_solid (coupling/fsi_interface.hpp choose_subcycles).
int resolve_subcycles(int requested, Real dt_fluid, Real dt_solid);

/// Text of a run summary (wall time, steps, split by phase, peak memory).
std::string format_summary(const RunSummary& s);

}  // namespace mpsfsi
