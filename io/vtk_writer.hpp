// VTK XML output of the particles: one binary, zlib-compressed .vtu (unstructured grid of vertex
// cells) per output time and a .pvd collection listing them with their times, which ParaView opens
// as one time series. Files are written under a temporary name and renamed, so an interrupted run
// never leaves a .pvd that lists a half-written frame.
#pragma once

#include "core/particles.hpp"

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace mpsfsi {

/// Writes one .vtu per output time plus a .pvd series for the run (ParaView opens the .pvd).
class VtkSeriesWriter {
 public:
  /// directory is created if missing (at construction if possible, otherwise at the first write);
  /// files are <directory>/<basename>_<6-digit frame>.vtu and <directory>/<basename>.pvd
  explicit VtkSeriesWriter(std::string directory, std::string basename = "particles");

  /// Only these extra fields are written (empty: all). The core arrays (velocity, kind, body,
  /// material, clamped, global_id) are always written. A listed name that is neither a scalar nor a
  /// vector field of the particles makes write() throw std::invalid_argument.
  void set_fields(std::vector<std::string> fields);

  /// Write a frame at simulated time t; returns the .vtu path. Throws OutputError (core/files.hpp)
  /// naming the path on I/O failure, std::invalid_argument for a non-finite time, arrays whose length differs
  /// from the particle count, or an extra field named like a core array.
  std::string write(const ParticleSet& particles, double time);

  std::size_t n_frames() const { return frames_.size(); }
  /// The series so far: (time, .vtu name relative to the .pvd) per frame.
  const std::vector<std::pair<double, std::string>>& frames() const { return frames_; }
  const std::string& pvd_path() const { return pvd_path_; }
  const std::string& directory() const { return directory_; }

  /// Restart support: adopt existing frames with time <= t from an existing .pvd (so a continued
  /// run appends after them; later frames are dropped from the series and their files are
  /// overwritten by the new frames). The .pvd is rewritten at once to list only the adopted frames.
  /// No .pvd: nothing is adopted and the series starts empty. New frames are numbered from
  /// first_new_frame at least (a restart into a new folder keeps the frame numbers of the original run).
  /// Throws std::runtime_error if the .pvd exists but cannot be read, OutputError if it cannot be rewritten.
  void adopt_existing(double up_to_time, std::size_t first_new_frame = 0);
  /// Number the next frame `frame` (a restart that starts a new series keeps the original numbering).
  void set_next_frame(std::size_t frame) { next_frame_ = frame; }
  std::size_t next_frame() const { return next_frame_; }

 private:
  void write_pvd() const;
  std::string frame_file_name(std::size_t frame) const;

  std::string directory_;
  std::string basename_;
  std::string pvd_path_;
  std::vector<std::string> fields_;
  std::vector<std::pair<double, std::string>> frames_;  ///< (time, .vtu name relative to the .pvd)
  std::size_t next_frame_ = 0;                          ///< number in the next .vtu file name
};

/// Read-side helper for tests and tools: the (time, file) entries of a .pvd, in file order; file
/// names are as written in the .pvd (relative to it). Throws std::runtime_error naming the path if
/// the file cannot be read or an entry is malformed.
std::vector<std::pair<double, std::string>> read_pvd(const std::string& pvd_path);

}  // namespace mpsfsi
