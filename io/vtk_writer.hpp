// VTK XML output of the particles: one binary, zlib-compressed .vtu (unstructured grid of vertex
// cells) per output time and a .pvd collection listing them with their times, which ParaView opens
// as one time series. A run on several ranks writes one piece per rank (<frame>_<rank>.vtu, the rank's
// owned particles) and a .pvtu that names the pieces; the .pvd lists the .pvtu files. Files are written
// under a temporary name and renamed, and a frame enters the .pvd only once all its pieces are written,
// so an interrupted run never leaves a .pvd that lists a half-written frame.
#pragma once

#include "core/particles.hpp"

#include <cstddef>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace mpsfsi {

/// Writes one .vtu per output time plus a .pvd series for the run (ParaView opens the .pvd).
class VtkSeriesWriter {
 public:
  /// directory is created if missing (at construction if possible, otherwise at the first write);
  /// files are <directory>/<basename>_<6-digit frame>.vtu and <directory>/<basename>.pvd; with n_pieces > 1
  /// this writer writes piece `piece` (<basename>_<frame>_<piece>.vtu) and, as piece 0, the
  /// <basename>_<frame>.pvtu and the .pvd.
  explicit VtkSeriesWriter(std::string directory, std::string basename = "particles", int piece = 0, int n_pieces = 1);

  /// Only these extra fields are written (empty: all but the internal ones, named "_..."). The core arrays (velocity, kind, body,
  /// material, clamped, global_id) are always written. A listed name that is neither a scalar nor a
  /// vector field of the particles makes write() throw std::invalid_argument.
  void set_fields(std::vector<std::string> fields);

  /// Write a frame at simulated time t (one piece: write_piece then commit_frame); returns the .vtu path.
  std::string write(const ParticleSet& particles, double time);
  /// This piece of the frame at time t: the owned particles. Throws OutputError (core/files.hpp) naming
  /// the path on I/O failure, std::invalid_argument for a non-finite time, arrays whose length differs
  /// from the particle count, or an extra field named like a core array. Returns the file's path.
  std::string write_piece(const ParticleSet& particles, double time);
  /// After every piece of the frame is written: piece 0 writes the .pvtu (several pieces) and the .pvd;
  /// every piece moves on to the next frame number. Returns the path the .pvd lists for the frame.
  std::string commit_frame(double time);

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
  std::string piece_file_name(std::size_t frame, int piece) const;

  std::string directory_;
  std::string basename_;
  std::string pvd_path_;
  std::vector<std::string> fields_;
  std::vector<std::pair<double, std::string>> frames_;  ///< (time, .vtu name relative to the .pvd)
  std::size_t next_frame_ = 0;                          ///< number in the next .vtu file name
  /// Point arrays of the last piece: (name, VTK type name, components), for the .pvtu.
  std::vector<std::tuple<std::string, std::string, int>> arrays_;
  int piece_ = 0, n_pieces_ = 1;
};

/// Read-side helper for tests and tools: the (time, file) entries of a .pvd, in file order; file
/// names are as written in the .pvd (relative to it). Throws std::runtime_error naming the path if
/// the file cannot be read or an entry is malformed.
std::vector<std::pair<double, std::string>> read_pvd(const std::string& pvd_path);

}  // namespace mpsfsi
