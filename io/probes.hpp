// Probes written as CSV, one row per output time: pressure at a point (kernel-averaged), surge-front
// position, water-column height at the back wall, and the displacement of a point of a body (in the
// global frame or in the rotating frame of the tank, seed 004 §5.4 Fig. 12). Heights are along the last
// axis (y in 2D, z in 3D); in 3D the front and the column are the largest over the tank's width.
#pragma once

#include "core/particles.hpp"
#include "core/tank_motion.hpp"
#include "io/case.hpp"

#include <mpi.h>

#include <fstream>
#include <string>
#include <vector>

namespace mpsfsi {

class ProbeWriter {
 public:
  /// Opens `path` and writes the header (append: continues an existing file without a header, for a
  /// restarted run; an empty path: no file, record() does nothing, e.g. on MPI ranks other than 0); the
  /// displacement probes lock onto the particle of their body nearest to the probe position in
  /// `particles` (the initial state).
  ProbeWriter(const CaseSpec& spec, const ParticleSet& particles, const std::string& path, bool append = false);
  bool empty() const { return probes_.empty(); }
  /// Append one row at time t with these values (from evaluate()).
  void record(Real t, const std::vector<Real>& values);
  /// Values of the probes at time t (the tank-frame probes need the tank angle theta(t)), in the order
  /// of the case file (the columns after time), from the owned particles of every rank of `comm` (a
  /// collective).
  std::vector<Real> evaluate(const ParticleSet& particles, Real t, MPI_Comm comm = MPI_COMM_SELF) const;
  /// Column names after "time" (a displacement probe has one per axis: _dx, _dy (, _dz)).
  const std::vector<std::string>& columns() const { return columns_; }

 private:
  struct Probe {
    ProbeSpec spec;
    GlobalId particle = -1;   ///< displacement probes: the tracked particle
    Vec initial = Vec::Zero();
  };
  Real dp_;
  TankMotion tank_;
  std::vector<Probe> probes_;
  std::vector<std::string> columns_;
  std::ofstream out_;
  std::string path_;
};

}  // namespace mpsfsi
