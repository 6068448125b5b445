// Checkpoint files (mpsfsi run --checkpoint-every T, --restart FILE): the complete state of a run in one
// binary file, written under a temporary name and renamed into place. Layout (machine byte order):
//   "MPSFSIck"  u32 byte-order mark  u32 format  u64 file size
//   string code version  (code_version(): project version + git revision)
//   string header        (CheckpointInfo: the case as run, time, step, output-file marks, ...)
//   string payload       (the run loop's, the particles', the fluid's, the solid's and the coupling's state,
//                         in named sections; read by RunLoop)
//   u64 FNV-1a checksum of everything before it
// A string is a u64 length and the bytes. Reading checks, in this order, the magic, the byte order, the
// format, the size (truncated?), the checksum (damaged?) and the code version, and throws CaseError
// (exit code 2) naming the file and what is wrong. Under MPI, rank 0 reads the file and broadcasts it.
#pragma once

#include "core/binary_io.hpp"
#include "core/types.hpp"

#include <mpi.h>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace mpsfsi {

/// Bumped whenever the layout of the file or of any state section changes.
inline constexpr std::uint32_t checkpoint_format = 1;

/// The state of one output file of the run folder when the checkpoint was written: its first `size`
/// bytes have the FNV-1a hash `hash`. A restart truncates the file to that size and appends.
struct OutputMark {
  std::string file;  ///< name inside the output folder
  std::uint64_t size = 0;
  std::uint64_t hash = 0;
};

/// What a checkpoint says about itself (everything but the physical state).
struct CheckpointInfo {
  std::string code_version;
  std::string case_name;
  std::string case_file;        ///< the case file as given to the run that wrote it
  std::string case_dir;         ///< absolute folder of that case file (relative paths in the case)
  std::string resolved_yaml;    ///< the case as run (CaseSpec::resolved_yaml)
  Real time = 0;
  std::uint64_t step = 0;
  std::uint64_t n_particles = 0;
  int n_ranks = 1;
  std::uint64_t next_frame = 0; ///< number of the next .vtu frame of the series
  std::vector<std::pair<double, std::string>> frames;  ///< the .pvd series then: (time, file) per frame
  std::vector<OutputMark> outputs;
  std::string written_at;       ///< local date and time of writing (information)
};

struct Checkpoint {
  std::string path;
  CheckpointInfo info;
  std::string data;             ///< the whole file
  std::size_t payload_begin = 0, payload_end = 0;

  /// A reader of the state sections; its messages name the file.
  BinaryReader payload() const { return BinaryReader(data, path, payload_begin, payload_end); }
};

/// Writes the checkpoint file `path` (to path.tmp, then renamed). Throws std::runtime_error naming the
/// file on I/O failure. One rank only.
void write_checkpoint(const std::string& path, const CheckpointInfo& info, const std::string& payload);

/// Reads and checks a checkpoint on rank 0 of `comm` and broadcasts it; collective. `path` may be a
/// folder: then its checkpoint_<time>.chk with the latest time. Throws CaseError naming the file and
/// the problem (not a checkpoint, other format or program version, truncated, damaged).
Checkpoint read_checkpoint(const std::string& path, MPI_Comm comm);

/// The case a checkpoint holds (CheckpointInfo::resolved_yaml), read from its header alone; `path` may be a
/// folder, as for read_checkpoint. Empty when the file is missing or not a readable checkpoint (nothing is
/// checked beyond that: read_checkpoint says what is wrong). One process, no MPI.
std::string peek_checkpoint_case(const std::string& path);
/// File name of the checkpoint at time t: checkpoint_<t to 9 significant digits>.chk.
std::string checkpoint_file_name(Real t);

/// True when `name` is a checkpoint file name (checkpoint_file_name) of a time after t. Compares the names'
/// rounded times: the checkpoint of t itself, whose name may round t up, is not later.
bool is_later_checkpoint(const std::string& name, Real t);

/// Marks of those of `files` that exist in `dir` (size and hash of their whole content now).
std::vector<OutputMark> mark_outputs(const std::string& dir, const std::vector<std::string>& files);

/// What a restart does with its output folder.
struct RestartOutputs {
  bool continuing = false;            ///< the folder is the checkpoint's run: its files continue
  std::vector<std::string> appended;  ///< files truncated to their checkpoint size, to be appended to
  /// Continuing: the frames and checkpoints of the folder's trajectory after the checkpoint, removed (a restart
  /// from an earlier point branches off that trajectory; its later files would mix with the new ones).
  std::vector<std::string> removed;
};

/// Prepares the output folder `dir` of a restart from `info` (one rank; creates it if missing):
/// * missing or empty (but for its lock file): new files (the series numbering continues from the checkpoint's);
/// * the checkpoint's run folder, i.e. its particles.pvd begins with the frames the checkpoint lists and
///   its data files (probes.csv, interface.csv, fragments.csv) begin with what they held then: those files
///   are truncated to their checkpoint size and continued (rows and frames after the checkpoint time are
///   dropped; the caller cuts the .pvd); run.jsonl likewise if it is unchanged up to then, else it is kept
///   whole and continued (it is a log); the frames and checkpoints after the checkpoint's are removed
///   (RestartOutputs::removed);
/// * anything else: CaseError, unless `overwrite`, which starts new files there.
/// `lock` is called once the folder is accepted, before anything in it changes (the output folder's lock,
/// which throws when another run holds it).
RestartOutputs prepare_restart_outputs(const std::string& dir, const CheckpointInfo& info, bool overwrite,
                                       const std::function<void()>& lock = {});

}  // namespace mpsfsi
