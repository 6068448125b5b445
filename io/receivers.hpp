// Receivers (issue 6; seed 000 §3, Lamb's problem): displacement time series of material points of
// solid bodies, written to receivers.csv. Each receiver is tied, in the initial state, to the body's
// particles within ReceiversSpec::radius of its position by linear-exact interpolation weights phi_k
// (core/point_stencil.hpp: Wendland C2 kernel with a moving-least-squares correction, so a receiver
// at the free surface, whose neighbourhood is one-sided, reads the linear extrapolation):
//   u_r(t) = sum_k phi_k (x_k(t) - x_k(0)).
// Columns: time, <name>_ux, <name>_uy (3D: and <name>_uz) for each receiver in the order of the case file [s, m].
// Rows: at t = 0 and then every `interval` of simulated time (every step without an interval).
#pragma once

#include "core/binary_io.hpp"
#include "core/files.hpp"
#include "core/particles.hpp"
#include "io/case.hpp"

#include <mpi.h>

#include <fstream>
#include <string>
#include <vector>

namespace mpsfsi {

class ReceiverWriter {
 public:
  /// Builds the stencils from `particles` (the initial state). With receivers, opens `path` (an empty
  /// path: no file, evaluate() only) and writes the header, or with `append` (a restart continuing the
  /// file) appends to it without one. Throws CaseError when a receiver has too few particles in range.
  ReceiverWriter(const CaseSpec& spec, const ParticleSet& particles, const std::string& path, bool append = false);
  bool empty() const { return receivers_.empty(); }
  /// Append a row at time t if one is due: at the first call, then once the interval has passed since
  /// the last row (every call when the case gives no interval). Every rank of `comm` calls it (the schedule
  /// is the same on all); the rank with the file writes the row.
  void record_if_due(Real t, const ParticleSet& particles, MPI_Comm comm = MPI_COMM_NULL);
  /// Displacement of every receiver now, in the order of the case file: the sums over each rank's owned
  /// particles, added over the ranks of `comm` (MPI_COMM_NULL: this process holds every particle). Collective.
  std::vector<Vec> evaluate(const ParticleSet& particles, MPI_Comm comm = MPI_COMM_NULL) const;
  /// Column names after "time".
  const std::vector<std::string>& columns() const { return columns_; }
  /// Push the rows written so far to the file (before a checkpoint marks the file's size).
  void flush() {
    if (!out_.is_open()) return;
    out_.flush();
    check_written(out_, path_, "receiver table");
  }
  /// Checkpoints: the row schedule (next row time, rows written).
  void save_state(BinaryWriter& w) const;
  void load_state(BinaryReader& r);

 private:
  struct Receiver {
    std::vector<GlobalId> id;            ///< particles of the stencil
    mutable std::vector<LocalIndex> at;  ///< their current local indices if owned here, else -1 (re-resolved)
    std::vector<Vec> x0;                 ///< their initial positions
    std::vector<Real> phi;               ///< interpolation weights
  };
  void resolve(const ParticleSet& particles) const;

  std::vector<Receiver> receivers_;
  std::vector<std::string> columns_;
  std::optional<Real> interval_;
  Real next_ = 0;
  bool started_ = false;
  std::size_t rows_ = 0;
  std::ofstream out_;
  std::string path_;
};

}  // namespace mpsfsi
