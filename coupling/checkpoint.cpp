// Checkpoint files: writing (temporary name, rename), reading with its checks and the MPI broadcast,
// the output-file marks and the preparation of a restart's output folder. See checkpoint.hpp.
#include "coupling/checkpoint.hpp"

#include "core/files.hpp"
#include "core/output_lock.hpp"
#include "core/version.hpp"
#include "io/case.hpp"
#include "io/vtk_writer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <regex>
#include <sstream>

namespace mpsfsi {

namespace fs = std::filesystem;

namespace {

constexpr char magic[8] = {'M', 'P', 'S', 'F', 'S', 'I', 'c', 'k'};
constexpr std::uint32_t byte_order_mark = 0x01020304u;
/// magic, byte-order mark, format, file size.
constexpr std::size_t preamble_size = 8 + 4 + 4 + 8;

std::string read_file(const std::string& path, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = fmt::format("cannot read checkpoint '{}': {}", path, std::strerror(errno));
    return {};
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) error = fmt::format("cannot read checkpoint '{}': read error", path);
  return buffer.str();
}

/// Hash of the first `size` bytes of a file, or false if it is shorter or unreadable.
bool hash_prefix(const fs::path& path, const std::uint64_t size, std::uint64_t& hash) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  hash = fnv1a64(nullptr, 0);
  std::vector<char> buf(1 << 16);
  std::uint64_t left = size;
  while (left > 0) {
    const auto n = static_cast<std::streamsize>(std::min<std::uint64_t>(left, buf.size()));
    in.read(buf.data(), n);
    if (in.gcount() != n) return false;
    hash = fnv1a64(buf.data(), static_cast<std::size_t>(n), hash);
    left -= static_cast<std::uint64_t>(n);
  }
  return true;
}

/// The time in a checkpoint's file name checkpoint_<t>.chk (checkpoint_file_name), or none for another name.
std::optional<double> checkpoint_time_of(const std::string& name) {
  const std::string prefix = "checkpoint_", suffix = ".chk";
  if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0)
    return std::nullopt;
  const std::string number = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  char* end = nullptr;
  const double t = std::strtod(number.c_str(), &end);
  if (end == number.c_str() || *end != '\0') return std::nullopt;
  return t;
}

/// The checkpoint of `dir` with the latest time in its name, or "" if none.
std::string latest_in(const std::string& dir) {
  std::string best;
  double best_t = -std::numeric_limits<double>::infinity();
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const auto t = checkpoint_time_of(entry.path().filename().string());
    if (!t || !entry.is_regular_file(ec)) continue;
    if (*t > best_t) {
      best_t = *t;
      best = entry.path().string();
    }
  }
  return best;
}

void write_info(BinaryWriter& w, const CheckpointInfo& info) {
  w.string(info.case_name);
  w.string(info.case_file);
  w.string(info.case_dir);
  w.string(info.resolved_yaml);
  w.f64(info.time);
  w.u64(info.step);
  w.u64(info.n_particles);
  w.i64(info.n_ranks);
  w.u64(info.next_frame);
  w.u64(info.frames.size());
  for (const auto& [t, file] : info.frames) {
    w.f64(t);
    w.string(file);
  }
  w.u64(info.outputs.size());
  for (const auto& m : info.outputs) {
    w.string(m.file);
    w.u64(m.size);
    w.u64(m.hash);
  }
  w.string(info.written_at);
}

CheckpointInfo read_info(BinaryReader& r) {
  CheckpointInfo info;
  info.case_name = r.string("the case name");
  info.case_file = r.string("the case file");
  info.case_dir = r.string("the case folder");
  info.resolved_yaml = r.string("the case");
  info.time = r.f64("the time");
  info.step = r.u64("the step");
  info.n_particles = r.u64("the particle count");
  info.n_ranks = static_cast<int>(r.i64("the rank count"));
  info.next_frame = r.u64("the frame number");
  const std::size_t n_frames = r.u64("the frame count");
  for (std::size_t k = 0; k < n_frames; ++k) {
    const double t = r.f64("a frame time");
    info.frames.emplace_back(t, r.string("a frame file"));
  }
  const std::size_t n = r.u64("the output count");
  if (n > 1000) r.fail("damaged: " + std::to_string(n) + " output files");
  for (std::size_t k = 0; k < n; ++k) {
    OutputMark m;
    m.file = r.string("an output file name");
    m.size = r.u64("an output file size");
    m.hash = r.u64("an output file hash");
    info.outputs.push_back(m);
  }
  info.written_at = r.string("the date");
  return info;
}

/// All checks of a checkpoint's bytes; throws CaseError.
Checkpoint parse(const std::string& path, std::string data) {
  Checkpoint c;
  c.path = path;
  c.data = std::move(data);
  const std::string& d = c.data;
  if (d.size() < sizeof(magic) || std::memcmp(d.data(), magic, sizeof(magic)) != 0)
    throw CaseError(fmt::format("'{}' is not an mpsfsi checkpoint (it does not start with the checkpoint signature)", path));
  if (d.size() < preamble_size)
    throw CaseError(fmt::format("checkpoint '{}' is truncated ({} bytes)", path, d.size()));
  BinaryReader r(d, path);
  r.value<std::uint64_t>("the signature");
  if (r.value<std::uint32_t>("the byte-order mark") != byte_order_mark)
    throw CaseError(fmt::format("checkpoint '{}' was written on a machine with another byte order", path));
  const auto format = r.value<std::uint32_t>("the format");
  if (format != checkpoint_format)
    throw CaseError(fmt::format("checkpoint '{}' has format {}; this mpsfsi ({}) reads format {} only", path, format,
                                code_version(), checkpoint_format));
  const std::uint64_t size = r.u64("the file size");
  if (d.size() < size)
    throw CaseError(fmt::format("checkpoint '{}' is truncated: {} of its {} bytes", path, d.size(), size));
  if (d.size() > size || size < preamble_size + 8)
    throw CaseError(fmt::format("checkpoint '{}' is damaged: {} bytes, its header says {}", path, d.size(), size));
  std::uint64_t stored = 0;
  std::memcpy(&stored, d.data() + size - 8, 8);
  if (fnv1a64(d.data(), size - 8) != stored)
    throw CaseError(fmt::format("checkpoint '{}' is damaged: its checksum does not match its content", path));
  try {
    BinaryReader body(d, path, preamble_size, size - 8);
    c.info.code_version = body.string("the program version");
    if (c.info.code_version != code_version())
      throw CaseError(fmt::format("checkpoint '{}' was written by mpsfsi {}; this is mpsfsi {}: restart with the "
                                  "program that wrote it (another version may hold other state or compute "
                                  "otherwise)",
                                  path, c.info.code_version, code_version()));
    const std::string header = body.string("the header");
    BinaryReader hr(header, path);
    const std::string version = c.info.code_version;
    c.info = read_info(hr);
    c.info.code_version = version;
    const std::uint64_t payload_size = body.u64("the state size");
    c.payload_begin = body.position();
    c.payload_end = c.payload_begin + payload_size;
    if (payload_size != body.remaining())
      throw CaseError(fmt::format("checkpoint '{}' is damaged: the state has {} bytes, {} expected", path,
                                  body.remaining(), payload_size));
  } catch (const StateFormatError& e) {
    throw CaseError(fmt::format("checkpoint {}", e.what()));
  }
  return c;
}

/// MPI_Bcast of a byte string of any length, from rank 0.
void broadcast(std::string& s, MPI_Comm comm) {
  std::uint64_t n = s.size();
  MPI_Bcast(&n, 1, MPI_UINT64_T, 0, comm);
  s.resize(n);
  constexpr std::uint64_t chunk = 1u << 30;
  for (std::uint64_t at = 0; at < n; at += chunk)
    MPI_Bcast(s.data() + at, static_cast<int>(std::min(chunk, n - at)), MPI_CHAR, 0, comm);
}

}  // namespace

std::string checkpoint_file_name(const Real t) { return fmt::format("checkpoint_{:.9g}.chk", t); }

bool is_later_checkpoint(const std::string& name, const Real t) {
  const auto other = checkpoint_time_of(name);
  return other && *other > *checkpoint_time_of(checkpoint_file_name(t));
}

void write_checkpoint(const std::string& path, const CheckpointInfo& info, const std::string& payload) {
  BinaryWriter header;
  write_info(header, info);
  BinaryWriter w;
  w.bytes().append(magic, sizeof(magic));
  w.value(byte_order_mark);
  w.value(checkpoint_format);
  w.u64(0);  // file size, filled in below
  w.string(code_version());
  w.string(header.bytes());
  w.string(payload);
  std::string& bytes = w.bytes();
  const std::uint64_t size = bytes.size() + 8;
  std::memcpy(bytes.data() + 16, &size, 8);
  const std::uint64_t sum = fnv1a64(bytes.data(), bytes.size());
  w.u64(sum);

  write_file_atomically(path, bytes, "checkpoint");
}

std::string peek_checkpoint_case(const std::string& path) {
  std::error_code ec;
  const std::string file = fs::is_directory(path, ec) ? latest_in(path) : path;
  if (file.empty() || !fs::is_regular_file(file, ec)) return {};  // a FIFO or a device: read_checkpoint says why
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  const auto read_string = [&](std::string& s) {
    std::uint64_t n = 0;
    if (!in.read(reinterpret_cast<char*>(&n), sizeof n) || n > (std::uint64_t{1} << 32)) return false;
    s.resize(n);
    return static_cast<bool>(in.read(s.data(), static_cast<std::streamsize>(n)));
  };
  char preamble[preamble_size];
  std::string version, header;
  if (!in.read(preamble, preamble_size) || std::memcmp(preamble, magic, sizeof(magic)) != 0 || !read_string(version) ||
      !read_string(header))
    return {};
  try {
    BinaryReader r(header, file);
    return read_info(r).resolved_yaml;
  } catch (const std::exception&) {
    return {};
  }
}

Checkpoint read_checkpoint(const std::string& path, MPI_Comm comm) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  std::string chosen = path, data, error;
  if (rank == 0) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      chosen = latest_in(path);
      if (chosen.empty()) error = fmt::format("--restart {}: the folder holds no checkpoint_<time>.chk file", path);
    } else if (!fs::exists(path, ec)) {
      error = fmt::format("--restart {}: no such checkpoint file", path);
    } else if (!fs::is_regular_file(path, ec)) {
      error = fmt::format("--restart {}: not a regular file; expected a checkpoint file (checkpoint_<time>.chk) or a "
                          "folder holding one",
                          path);
    }
    if (error.empty()) data = read_file(chosen, error);
  }
  broadcast(error, comm);
  if (!error.empty()) throw CaseError(error);
  broadcast(chosen, comm);
  broadcast(data, comm);
  return parse(chosen, std::move(data));
}

std::vector<OutputMark> mark_outputs(const std::string& dir, const std::vector<std::string>& files) {
  std::vector<OutputMark> marks;
  for (const auto& f : files) {
    const fs::path p = fs::path(dir) / f;
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) continue;
    OutputMark m;
    m.file = f;
    m.size = fs::file_size(p, ec);
    if (ec || !hash_prefix(p, m.size, m.hash)) continue;
    marks.push_back(m);
  }
  return marks;
}

/// The files of `dir` that belong to a trajectory after the checkpoint `info`: frames numbered from its next
/// frame on (particles_<n>.vtu/.pvtu and their pieces particles_<n>_<rank>.vtu) and checkpoints of later times.
/// Removes them and returns their names (sorted).
static std::vector<std::string> remove_later_outputs(const std::string& dir, const CheckpointInfo& info) {
  static const std::regex frame(R"(particles_(\d+)(_\d+)?\.p?vtu)");
  std::vector<std::string> removed;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    std::smatch m;
    const bool later = std::regex_match(name, m, frame) ? std::stoull(m[1].str()) >= info.next_frame
                                                        : is_later_checkpoint(name, info.time);
    if (!later || !entry.is_regular_file(ec)) continue;
    fs::remove(entry.path(), ec);
    if (ec) throw std::runtime_error(fmt::format("cannot remove '{}': {}", entry.path().string(), ec.message()));
    removed.push_back(name);
  }
  std::sort(removed.begin(), removed.end());
  return removed;
}

RestartOutputs prepare_restart_outputs(const std::string& dir, const CheckpointInfo& info, const bool overwrite,
                                       const std::function<void()>& lock) {
  RestartOutputs r;
  std::error_code ec;
  const auto accept = [&] {
    if (lock) lock();
  };
  if (!fs::exists(dir, ec) || holds_only_lock(dir)) {
    fs::create_directories(dir, ec);
    if (ec) throw std::runtime_error(fmt::format("cannot create the output folder '{}': {}", dir, ec.message()));
    accept();
    return r;
  }
  if (!fs::is_directory(dir, ec)) throw CaseError(fmt::format("--output {}: not a folder", dir));
  // The checkpoint's run folder: the series and the data files as they were, up to the checkpoint.
  std::string mismatch;
  int evidence = 0;
  const auto same_prefix = [&](const OutputMark& m) {
    const fs::path p = fs::path(dir) / m.file;
    std::uint64_t hash = 0;
    if (!fs::is_regular_file(p, ec)) return std::string("it has no ") + m.file;
    if (fs::file_size(p, ec) < m.size) return m.file + " is shorter than when the checkpoint was written";
    if (!hash_prefix(p, m.size, hash) || hash != m.hash) return m.file + " differs from the one the checkpoint was written with";
    return std::string();
  };
  for (const auto& m : info.outputs) {
    if (m.file == "run.jsonl" || !mismatch.empty()) continue;
    mismatch = same_prefix(m);
    ++evidence;
  }
  const fs::path pvd = fs::path(dir) / "particles.pvd";
  if (mismatch.empty() && !info.frames.empty()) {
    ++evidence;
    if (!fs::is_regular_file(pvd, ec)) {
      mismatch = "it has no particles.pvd";
    } else {
      std::vector<std::pair<double, std::string>> entries;
      try {
        entries = read_pvd(pvd.string());
      } catch (const std::exception& e) {
        mismatch = e.what();
      }
      if (mismatch.empty() && (entries.size() < info.frames.size() ||
                               !std::equal(info.frames.begin(), info.frames.end(), entries.begin())))
        mismatch = "its particles.pvd lists other frames up to the checkpoint time than the checkpoint's run";
    }
  }
  if (mismatch.empty() && evidence == 0) mismatch = "it holds none of the run's output files";
  if (!mismatch.empty()) {
    if (overwrite) {
      accept();
      return r;
    }
    throw CaseError(fmt::format(
        "--output {}: the folder is not empty and is not the run that wrote the checkpoint at t = {:.6g} s ({}); "
        "choose another (or an empty) folder, or pass --overwrite to start new output files there from the "
        "checkpoint",
        dir, info.time, mismatch));
  }
  accept();
  for (const auto& m : info.outputs) {
    const fs::path p = fs::path(dir) / m.file;
    if (m.file == "run.jsonl") {  // a log: cut where the checkpoint was written if unchanged, else kept whole
      if (!fs::is_regular_file(p, ec)) continue;
      if (same_prefix(m).empty()) fs::resize_file(p, m.size, ec);
    } else {
      fs::resize_file(p, m.size, ec);
    }
    if (ec) throw std::runtime_error(fmt::format("cannot truncate '{}': {}", p.string(), ec.message()));
    r.appended.push_back(m.file);
  }
  r.continuing = true;
  r.removed = remove_later_outputs(dir, info);
  return r;
}

}  // namespace mpsfsi
