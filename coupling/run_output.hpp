// The files a run writes as it goes, on their schedules: the frames (a .vtu piece per rank, the .pvtu and
// the .pvd series), probes.csv (with each frame or every output.probe_interval), receivers.csv, and the run
// log (coupling/run_log.hpp). It also writes the frame of a failed run's last good state and words the
// message of a run stopped because a file could not be written. The run loop (coupling/simulation.cpp)
// decides when a step is due for output; the checkpoints (coupling/checkpoint.hpp) read the series and the
// schedule from here.
#pragma once

#include "core/particles.hpp"
#include "coupling/run_log.hpp"
#include "coupling/simulation.hpp"
#include "io/probes.hpp"
#include "io/receivers.hpp"
#include "io/vtk_writer.hpp"

#include <mpi.h>

#include <functional>
#include <string>

namespace mpsfsi {

/// Whether a restart continues `file` of the output folder (RunSettings::append_files).
bool appends(const RunSettings& settings, const std::string& file);

/// The times of the next frame and of the next row of probes.csv (accumulated: saved in checkpoints, not
/// recomputed, so that a restart writes at the same times bit for bit).
struct OutputSchedule {
  Real next_frame = 0;
  Real next_probe = 0;  ///< with output.probe_interval only
};

class RunOutput {
 public:
  /// Opens the writers and run.jsonl in settings.output_dir (making the folder), each continued when the
  /// restart appends to it; `particles` is the initial scene (the probes' and receivers' references).
  RunOutput(const CaseSpec& spec, const ParticleSet& particles, const RunSettings& settings, MPI_Comm comm);

  RunLog& log() { return log_; }
  const VtkSeriesWriter& series() const { return writer_; }
  ReceiverWriter& receivers() { return receivers_; }
  OutputSchedule& schedule() { return schedule_; }
  /// Seconds spent writing (frames and rows; checkpoints add theirs).
  double& seconds() { return seconds_; }

  /// Checks output.fields against the fields of `particles` (the solvers have registered theirs), throws
  /// CaseError naming an unknown one, and writes only those.
  void select_fields(const ParticleSet& particles);

  /// Rank 0: throws OutputError when the output folder was removed or replaced (core/output_lock.hpp).
  void check_folder() const;

  /// A frame of `particles` at t, with the row of probes.csv that goes with it (without output.probe_interval)
  /// and `on_rank0_after` (the interface table), a collective. A file that cannot be written stops the run on
  /// every rank with OutputError (stopped_by_output's message); the series lists only complete frames.
  void write_frame(const ParticleSet& particles, Real t, std::size_t step, const std::function<void()>& on_rank0_after);
  /// Whether a frame is due at t (the first step at or past each multiple of output.interval).
  bool frame_due(Real t) const { return t >= schedule_.next_frame - eps_; }
  /// The frame due at t was written: the schedule moves to the next output time.
  void frame_written(Real t) { schedule_.next_frame = next_after(schedule_.next_frame, spec_.output.interval, t); }
  /// After a step to t: the receivers' row and the probes' row (output.probe_interval) that are due (a
  /// collective).
  void record_rows(const ParticleSet& particles, Real t);
  /// The rows of the initial state at t: the receivers', and the probes' when they have their own interval
  /// (otherwise the first frame writes them).
  void record_initial_rows(const ParticleSet& particles, Real t);

  /// A failed run: the frame of its last good state at t (every rank's piece), or the last frame when that is
  /// the same state. Returns the frame's path, or why it could not be written.
  std::string write_failure_frame(const ParticleSet& last_good, Real t);

  /// The message of a run stopped at (t, step) because a file could not be written (`what`), naming the
  /// frames that are complete; also logged in run.jsonl.
  std::string stopped_by_output(const std::string& what, Real t, std::size_t step);

  /// Restart: the series continues from the checkpoint's frame numbering (and its frames when the folder's
  /// series is continued), on every rank.
  void continue_series(Real t, std::size_t next_frame);

 private:
  /// The next time after t of a schedule due at `due`: one addition as a rule (bit for bit the accumulated
  /// times), several intervals at once when a step spans more than one.
  Real next_after(Real due, Real interval, Real t) const;

  const CaseSpec& spec_;
  const RunSettings& settings_;
  MPI_Comm comm_;
  int rank_ = 0;
  int n_ranks_ = 1;
  Real eps_ = 0;  ///< times closer than this are equal
  VtkSeriesWriter writer_;
  ProbeWriter probes_;
  ReceiverWriter receivers_;  ///< receivers.csv (rank 0), rows every step or every receivers.interval
  RunLog log_;                ///< the progress line, notes and run.jsonl (the writers above make the folder)
  OutputSchedule schedule_;
  double seconds_ = 0;
};

}  // namespace mpsfsi
