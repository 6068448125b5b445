// VTK XML output of the particles: builds a vtkUnstructuredGrid of vertex cells (one per particle)
// with the core arrays and the registered extra fields, writes it with vtkXMLUnstructuredGridWriter
// (binary, zlib) under a temporary name, renames it into place, then rewrites the .pvd collection
// the same way. Also reads .pvd files back (read_pvd) for restarts, tests and tools.
#include "io/vtk_writer.hpp"

#include "core/files.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkCommand.h>
#include <vtkDoubleArray.h>
#include <vtkExecutive.h>
#include <vtkFieldData.h>
#include <vtkIdTypeArray.h>
#include <vtkLongLongArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkShortArray.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnsignedShortArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace mpsfsi {

namespace fs = std::filesystem;

namespace {

/// Names of the point arrays that every frame has; extra fields must not reuse them.
const char* const core_array_names[] = {"velocity", "kind", "body", "material", "clamped", "global_id"};

/// Collects the error and warning messages a VTK object reports, instead of printing them. VTK's
/// text "ERROR: In <source>, line <n>\n<Class> (0x...): <message>\n" is reduced to <message>.
class VtkMessageCollector : public vtkCommand {
 public:
  static VtkMessageCollector* New() { return new VtkMessageCollector; }
  void Execute(vtkObject* /*caller*/, unsigned long /*event*/, void* call_data) override {
    if (call_data == nullptr) return;
    std::string message = static_cast<const char*>(call_data);
    if (message.rfind("ERROR: In ", 0) == 0 || message.rfind("Warning: In ", 0) == 0) {
      const std::size_t eol = message.find('\n');
      message = eol == std::string::npos ? std::string() : message.substr(eol + 1);
    }
    const std::size_t object_end = message.find("): ");
    if (object_end != std::string::npos && message.find(" (0x") < object_end) {
      message = message.substr(object_end + 3);
    }
    while (!message.empty() && std::isspace(static_cast<unsigned char>(message.back()))) message.pop_back();
    if (message.empty()) return;
    if (!messages.empty()) messages += "; ";
    messages += message;
  }
  std::string messages;
};

std::string xml_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string xml_unescape(const std::string& s) {
  static const std::pair<const char*, char> entities[] = {
      {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    bool replaced = false;
    if (s[i] == '&') {
      for (const auto& [entity, c] : entities) {
        const std::size_t len = std::strlen(entity);
        if (s.compare(i, len, entity) == 0) {
          out += c;
          i += len;
          replaced = true;
          break;
        }
      }
    }
    if (!replaced) out += s[i++];
  }
  return out;
}

/// Value of attribute `name` inside the text of one XML start tag; false if absent.
bool find_attribute(const std::string& tag, const std::string& name, std::string& value) {
  const std::string key = name + "=";
  for (std::size_t pos = tag.find(key); pos != std::string::npos; pos = tag.find(key, pos + 1)) {
    if (pos == 0 || !std::isspace(static_cast<unsigned char>(tag[pos - 1]))) continue;
    const std::size_t open = pos + key.size();
    if (open >= tag.size() || (tag[open] != '"' && tag[open] != '\'')) return false;
    const std::size_t close = tag.find(tag[open], open + 1);
    if (close == std::string::npos) return false;
    value = xml_unescape(tag.substr(open + 1, close - open - 1));
    return true;
  }
  return false;
}

/// Creates the output directory if missing; throws OutputError naming `target` (the file about to be
/// written) and the directory on failure.
void ensure_directory(const std::string& directory, const std::string& target) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec || !fs::is_directory(directory, ec)) {
    const std::string reason = ec ? ec.message() : "not a directory";
    throw OutputError(
        fmt::format("cannot write '{}': cannot create output directory '{}': {}", target, directory, reason));
  }
}

template <class T>
void check_length(const std::vector<T>& a, const std::size_t n, const std::string& name) {
  if (a.size() != n) {
    throw std::invalid_argument(fmt::format(
        "VTK output: particle array '{}' has {} entries but there are {} particles", name, a.size(), n));
  }
}

/// A named point array of `n` tuples of one component holding values[0, n) converted to the array type.
template <class ArrayT, class T>
vtkSmartPointer<ArrayT> make_scalar_array(const char* name, const std::vector<T>& values, const std::size_t n) {
  auto array = vtkSmartPointer<ArrayT>::New();
  array->SetName(name);
  array->SetNumberOfComponents(1);
  array->SetNumberOfTuples(static_cast<vtkIdType>(n));
  auto* out = array->GetPointer(0);
  for (std::size_t i = 0; i < n; ++i) {
    out[i] = static_cast<typename ArrayT::ValueType>(values[i]);
  }
  return array;
}

/// A 3-component double array from values[0, n), 2D (or 3D) vectors; missing components are 0.
vtkSmartPointer<vtkDoubleArray> make_vector_array(const char* name, const std::vector<Vec>& values, const std::size_t n) {
  auto array = vtkSmartPointer<vtkDoubleArray>::New();
  if (name != nullptr) array->SetName(name);
  array->SetNumberOfComponents(3);
  array->SetNumberOfTuples(static_cast<vtkIdType>(n));
  double* out = array->GetPointer(0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) out[3 * i + static_cast<std::size_t>(c)] = c < dim ? values[i][c] : 0.0;
  }
  return array;
}

}  // namespace

VtkSeriesWriter::VtkSeriesWriter(std::string directory, std::string basename, const int piece, const int n_pieces)
    : directory_(directory.empty() ? std::string(".") : std::move(directory)), basename_(std::move(basename)),
      piece_(piece), n_pieces_(n_pieces) {
  if (n_pieces < 1 || piece < 0 || piece >= n_pieces)
    throw std::invalid_argument(fmt::format("VTK output: piece {} of {} pieces", piece, n_pieces));
  if (basename_.empty() || basename_.find('/') != std::string::npos) {
    throw std::invalid_argument(
        fmt::format("VTK output: basename '{}' must be a non-empty file name without '/'", basename_));
  }
  pvd_path_ = (fs::path(directory_) / (basename_ + ".pvd")).string();
  std::error_code ignored;  // a failure is reported by the first write, which names the file
  fs::create_directories(directory_, ignored);
}

void VtkSeriesWriter::set_fields(std::vector<std::string> fields) {
  std::vector<std::string> unique;
  std::set<std::string> seen;
  for (auto& f : fields)
    if (seen.insert(f).second) unique.push_back(std::move(f));
  fields_ = std::move(unique);
}

std::string VtkSeriesWriter::frame_file_name(const std::size_t frame) const {
  return fmt::format("{}_{:06d}.{}", basename_, frame, n_pieces_ > 1 ? "pvtu" : "vtu");
}

std::string VtkSeriesWriter::piece_file_name(const std::size_t frame, const int piece) const {
  return n_pieces_ > 1 ? fmt::format("{}_{:06d}_{}.vtu", basename_, frame, piece) : frame_file_name(frame);
}

std::string VtkSeriesWriter::write(const ParticleSet& particles, const double time) {
  const std::string path = write_piece(particles, time);
  commit_frame(time);
  return path;
}

std::string VtkSeriesWriter::write_piece(const ParticleSet& particles, const double time) {
  const std::string file_name = piece_file_name(next_frame_, piece_);
  const std::string path = (fs::path(directory_) / file_name).string();
  if (!std::isfinite(time)) {
    throw std::invalid_argument(fmt::format("VTK output '{}': time {} is not finite", path, time));
  }

  // Check every array before touching the disk; the owned particles are written (ghosts are another
  // piece's).
  const std::size_t n_all = particles.size(), n = particles.n_owned();
  check_length(particles.velocity, n_all, "velocity");
  check_length(particles.kind, n_all, "kind");
  check_length(particles.body, n_all, "body");
  check_length(particles.material, n_all, "material");
  check_length(particles.clamped, n_all, "clamped");
  check_length(particles.global_id, n_all, "global_id");

  std::vector<std::pair<std::string, const std::vector<Real>*>> scalars;
  std::vector<std::pair<std::string, const std::vector<Vec>*>> vectors;
  if (fields_.empty()) {
    // Internal fields (names starting with '_') only when asked for by name.
    for (const auto& [name, values] : particles.scalar_fields())
      if (name[0] != '_') scalars.emplace_back(name, &values);
    for (const auto& [name, values] : particles.vector_fields())
      if (name[0] != '_') vectors.emplace_back(name, &values);
  } else {
    for (const auto& name : fields_) {
      const bool is_scalar = particles.has_scalar_field(name);
      const bool is_vector = particles.has_vector_field(name);
      if (is_scalar) scalars.emplace_back(name, &particles.scalar_field(name));
      if (is_vector) vectors.emplace_back(name, &particles.vector_field(name));
      if (!is_scalar && !is_vector) {
        std::vector<std::string> known;
        for (const auto& kv : particles.scalar_fields()) known.push_back(kv.first);
        for (const auto& kv : particles.vector_fields()) known.push_back(kv.first);
        throw std::invalid_argument(fmt::format("VTK output '{}': requested field '{}' is not a particle field "
                                                "(fields: {})",
                                                path, name, fmt::join(known, ", ")));
      }
    }
  }
  std::set<std::string> used(std::begin(core_array_names), std::end(core_array_names));
  for (const auto& [name, values] : scalars) {
    if (!used.insert(name).second) {
      throw std::invalid_argument(fmt::format("VTK output '{}': two point arrays named '{}'", path, name));
    }
    check_length(*values, n_all, name);
  }
  for (const auto& [name, values] : vectors) {
    if (!used.insert(name).second) {
      throw std::invalid_argument(fmt::format("VTK output '{}': two point arrays named '{}'", path, name));
    }
    check_length(*values, n_all, name);
  }

  // Grid: 3D points (z = 0 in 2D) and one vertex cell per particle.
  const auto nv = static_cast<vtkIdType>(n);
  vtkNew<vtkPoints> points;
  points->SetData(make_vector_array(nullptr, particles.position, n));
  vtkNew<vtkIdTypeArray> offsets;
  offsets->SetNumberOfTuples(nv + 1);
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfTuples(nv);
  for (vtkIdType i = 0; i < nv; ++i) {
    offsets->SetValue(i, i);
    connectivity->SetValue(i, i);
  }
  offsets->SetValue(nv, nv);
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->SetCells(VTK_VERTEX, cells);

  vtkPointData* const pd = grid->GetPointData();
  pd->AddArray(make_vector_array("velocity", particles.velocity, n));
  pd->AddArray(make_scalar_array<vtkUnsignedCharArray>("kind", particles.kind, n));
  pd->AddArray(make_scalar_array<vtkUnsignedShortArray>("body", particles.body, n));
  pd->AddArray(make_scalar_array<vtkShortArray>("material", particles.material, n));
  pd->AddArray(make_scalar_array<vtkUnsignedCharArray>("clamped", particles.clamped, n));
  pd->AddArray(make_scalar_array<vtkLongLongArray>("global_id", particles.global_id, n));
  for (const auto& [name, values] : scalars) pd->AddArray(make_scalar_array<vtkDoubleArray>(name.c_str(), *values, n));
  for (const auto& [name, values] : vectors) pd->AddArray(make_vector_array(name.c_str(), *values, n));
  arrays_ = {{"velocity", "Float64", 3}, {"kind", "UInt8", 1},     {"body", "UInt16", 1},
             {"material", "Int16", 1},   {"clamped", "UInt8", 1},  {"global_id", "Int64", 1}};
  for (const auto& [name, values] : scalars) arrays_.emplace_back(name, "Float64", 1);
  for (const auto& [name, values] : vectors) arrays_.emplace_back(name, "Float64", 3);

  vtkNew<vtkDoubleArray> time_value;
  time_value->SetName("TimeValue");
  time_value->SetNumberOfTuples(1);
  time_value->SetValue(0, time);
  grid->GetFieldData()->AddArray(time_value);

  // VTK writes into memory (its error path on a full disk is not safe); the file is written by
  // write_file_atomically, which checks every write and leaves no temporary file behind.
  ensure_directory(directory_, path);
  vtkNew<VtkMessageCollector> messages;
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->AddObserver(vtkCommand::ErrorEvent, messages);
  writer->AddObserver(vtkCommand::WarningEvent, messages);
  vtkNew<VtkMessageCollector> pipeline_messages;  // only silences the pipeline's "returned failure" dump
  writer->GetExecutive()->AddObserver(vtkCommand::ErrorEvent, pipeline_messages);
  writer->WriteToOutputStringOn();
  writer->SetInputData(grid);
  writer->SetDataModeToBinary();
  writer->SetCompressorTypeToZLib();
  writer->SetHeaderTypeToUInt64();  // no 4 GiB limit on an array
  const int ok = writer->Write();
  if (ok != 1 || writer->GetErrorCode() != 0) {
    const std::string reason = messages->messages.empty() ? std::string("vtkXMLUnstructuredGridWriter failed")
                                                          : messages->messages;
    throw OutputError(fmt::format("cannot write VTK frame '{}': {}", path, reason));
  }
  write_file_atomically(path, writer->GetOutputString(), "VTK frame");
  return path;
}

std::string VtkSeriesWriter::commit_frame(const double time) {
  const std::string file_name = frame_file_name(next_frame_);
  if (piece_ == 0) {
    if (n_pieces_ > 1) {
      // The parallel file: the pieces' array layout and their file names (relative to it).
      std::string text =
          "<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
          "  <PUnstructuredGrid GhostLevel=\"0\">\n"
          "    <PPointData>\n";
      for (const auto& [name, type, components] : arrays_)
        text += fmt::format("      <PDataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\"/>\n", type,
                            xml_escape(name), components);
      text += "    </PPointData>\n    <PPoints>\n      <PDataArray type=\"Float64\" NumberOfComponents=\"3\"/>\n"
              "    </PPoints>\n";
      for (int q = 0; q < n_pieces_; ++q)
        text += fmt::format("    <Piece Source=\"{}\"/>\n", xml_escape(piece_file_name(next_frame_, q)));
      text += "  </PUnstructuredGrid>\n</VTKFile>\n";
      write_file_atomically((fs::path(directory_) / file_name).string(), text, "VTK frame");
    }
    frames_.emplace_back(time, file_name);
    try {
      write_pvd();
    } catch (...) {
      frames_.pop_back();
      throw;
    }
  } else {
    frames_.emplace_back(time, file_name);
  }
  ++next_frame_;
  return (fs::path(directory_) / file_name).string();
}

void VtkSeriesWriter::write_pvd() const {
  ensure_directory(directory_, pvd_path_);
  std::string text =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const auto& [time, file] : frames_) {
    text += fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", time,
                        xml_escape(file));
  }
  text += "  </Collection>\n</VTKFile>\n";

  write_file_atomically(pvd_path_, text, "series file");
}

void VtkSeriesWriter::adopt_existing(const double up_to_time, const std::size_t first_new_frame) {
  if (std::isnan(up_to_time)) {
    throw std::invalid_argument(fmt::format("VTK output '{}': restart time is NaN", pvd_path_));
  }
  frames_.clear();
  next_frame_ = first_new_frame;
  std::error_code ec;
  if (!fs::exists(pvd_path_, ec)) return;

  const std::string prefix = basename_ + "_";
  const std::string suffix = n_pieces_ > 1 ? ".pvtu" : ".vtu";
  for (auto& [time, file] : read_pvd(pvd_path_)) {
    if (!(time <= up_to_time)) continue;
    // Never reuse the number of an adopted frame's file for a new frame.
    if (file.size() > prefix.size() + suffix.size() && file.compare(0, prefix.size(), prefix) == 0 &&
        file.compare(file.size() - suffix.size(), suffix.size(), suffix) == 0) {
      const char* const first = file.data() + prefix.size();
      const char* const last = file.data() + file.size() - suffix.size();
      std::size_t number = 0;
      const auto [end, err] = std::from_chars(first, last, number);
      if (err == std::errc() && end == last) next_frame_ = std::max(next_frame_, number + 1);
    }
    frames_.emplace_back(time, std::move(file));
  }
  next_frame_ = std::max(next_frame_, frames_.size());
  write_pvd();
}

std::vector<std::pair<double, std::string>> read_pvd(const std::string& pvd_path) {
  std::ifstream in(pvd_path, std::ios::binary);
  if (!in) {
    throw std::runtime_error(fmt::format("cannot read '{}': {}", pvd_path, std::strerror(errno)));
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  if (text.find("<VTKFile") == std::string::npos || text.find("Collection") == std::string::npos) {
    throw std::runtime_error(fmt::format("'{}' is not a VTK collection (.pvd) file", pvd_path));
  }

  std::vector<std::pair<double, std::string>> entries;
  const std::string open_tag = "<DataSet";
  for (std::size_t pos = text.find(open_tag); pos != std::string::npos; pos = text.find(open_tag, pos + 1)) {
    const std::size_t end = text.find('>', pos);
    if (end == std::string::npos) {
      throw std::runtime_error(fmt::format("'{}': unterminated <DataSet> element", pvd_path));
    }
    const std::string tag = text.substr(pos, end - pos);
    std::string time_text;
    std::string file;
    if (!find_attribute(tag, "timestep", time_text) || !find_attribute(tag, "file", file)) {
      throw std::runtime_error(
          fmt::format("'{}': <DataSet> element without timestep or file attribute: {}>", pvd_path, tag));
    }
    double time = 0;
    const char* const first = time_text.data();
    const char* const last = first + time_text.size();
    const auto [parsed_end, err] = std::from_chars(first, last, time);
    if (err != std::errc() || parsed_end != last) {
      throw std::runtime_error(fmt::format("'{}': bad timestep \"{}\"", pvd_path, time_text));
    }
    entries.emplace_back(time, std::move(file));
  }
  return entries;
}

}  // namespace mpsfsi
