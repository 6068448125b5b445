// Tests of the VTK XML particle output (io/vtk_writer): frames read back with VTK's own reader hold
// every array exactly, the .pvd lists the frames and times, set_fields restricts the extra arrays,
// no temporary files remain, restarts adopt earlier frames, and I/O failures throw.
#include "io/vtk_writer.hpp"

#include <gtest/gtest.h>

#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkVariant.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLDataParser.h>
#include <vtkXMLPUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpsfsi {
namespace {

namespace fs = std::filesystem;

/// A unique scratch directory, removed at the end of the test.
class VtkWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    dir_ = fs::temp_directory_path() /
           ("mpsfsi_test_vtk_" + std::to_string(::getpid()) + "_" + std::to_string(stamp));
    // Not created here: the writer must create it.
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  fs::path dir_;
};

/// Few hundred particles with random values in every core array, 2 extra scalar and 1 vector field.
ParticleSet random_particles(const unsigned seed, const std::size_t n = 357) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> real(-10.0, 10.0);
  std::uniform_int_distribution<int> kind(0, 3);
  std::uniform_int_distribution<int> body(0, std::numeric_limits<std::uint16_t>::max());
  std::uniform_int_distribution<int> material(std::numeric_limits<std::int16_t>::min(),
                                              std::numeric_limits<std::int16_t>::max());
  std::uniform_int_distribution<int> clamped(0, 1);
  std::uniform_int_distribution<long long> gid(std::numeric_limits<long long>::min(),
                                               std::numeric_limits<long long>::max());
  ParticleSet p;
  auto& pressure = p.add_scalar_field("pressure");
  auto& density = p.add_scalar_field("density", 1000.0);
  auto& displacement = p.add_vector_field("displacement");
  for (std::size_t i = 0; i < n; ++i) {
    p.add(Vec(real(rng), real(rng)), Vec(real(rng), real(rng)), static_cast<ParticleKind>(kind(rng)), body(rng),
          material(rng), clamped(rng) != 0);
    p.global_id.back() = gid(rng);
    pressure.back() = real(rng) * 1e5;
    density.back() = 1000.0 + real(rng);
    displacement.back() = Vec(real(rng) * 1e-3, real(rng) * 1e-7);
  }
  // A few awkward values that must survive exactly.
  p.global_id[0] = std::numeric_limits<long long>::max();
  p.global_id[1] = std::numeric_limits<long long>::min();
  p.global_id[2] = (1LL << 53) + 1;  // not representable as a double
  p.position[0] = Vec(0.1 + 0.2, -std::numeric_limits<double>::denorm_min());
  pressure[0] = std::numeric_limits<double>::max();
  return p;
}

vtkSmartPointer<vtkUnstructuredGrid> read_vtu(const std::string& path) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  EXPECT_EQ(reader->GetErrorCode(), 0) << path;
  vtkSmartPointer<vtkUnstructuredGrid> grid = reader->GetOutput();
  return grid;
}

vtkDataArray* get_array(vtkUnstructuredGrid* grid, const char* name, const int components, const int type) {
  vtkDataArray* const a = grid->GetPointData()->GetArray(name);
  EXPECT_NE(a, nullptr) << "missing point array " << name;
  if (a == nullptr) return nullptr;
  EXPECT_EQ(a->GetNumberOfTuples(), grid->GetNumberOfPoints()) << name;
  EXPECT_EQ(a->GetNumberOfComponents(), components) << name;
  if (type >= 0) {
    EXPECT_EQ(a->GetDataType(), type) << name;
  }
  return a;
}

/// Every value of a 3-component double array equals the 2D vectors (z = 0).
void expect_vectors(vtkUnstructuredGrid* grid, const char* name, const std::vector<Vec>& expected) {
  vtkDataArray* const a = get_array(grid, name, 3, VTK_DOUBLE);
  if (a == nullptr) return;
  auto* const d = vtkDoubleArray::SafeDownCast(a);
  ASSERT_NE(d, nullptr) << name;
  ASSERT_EQ(static_cast<std::size_t>(d->GetNumberOfTuples()), expected.size()) << name;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const auto t = static_cast<vtkIdType>(i);
    ASSERT_EQ(d->GetTypedComponent(t, 0), expected[i][0]) << name << " particle " << i;
    ASSERT_EQ(d->GetTypedComponent(t, 1), expected[i][1]) << name << " particle " << i;
    ASSERT_EQ(d->GetTypedComponent(t, 2), 0.0) << name << " particle " << i;
  }
}

/// Every value of a 1-component integer array equals `expected` (compared as 64-bit integers).
template <class T>
void expect_integers(vtkUnstructuredGrid* grid, const char* name, const std::vector<T>& expected, const int type) {
  vtkDataArray* const a = get_array(grid, name, 1, type);
  if (a == nullptr) return;
  ASSERT_EQ(static_cast<std::size_t>(a->GetNumberOfTuples()), expected.size()) << name;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const long long value = a->GetVariantValue(static_cast<vtkIdType>(i)).ToLongLong();
    ASSERT_EQ(value, static_cast<long long>(expected[i])) << name << " particle " << i;
  }
}

void expect_scalars(vtkUnstructuredGrid* grid, const char* name, const std::vector<double>& expected) {
  vtkDataArray* const a = get_array(grid, name, 1, VTK_DOUBLE);
  if (a == nullptr) return;
  auto* const d = vtkDoubleArray::SafeDownCast(a);
  ASSERT_NE(d, nullptr) << name;
  ASSERT_EQ(static_cast<std::size_t>(d->GetNumberOfTuples()), expected.size()) << name;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    ASSERT_EQ(d->GetValue(static_cast<vtkIdType>(i)), expected[i]) << name << " particle " << i;
  }
}

/// The whole frame equals the particles; `extra` lists the extra fields expected in it.
void expect_frame(const std::string& path, const ParticleSet& p, const double time,
                  const std::vector<std::string>& extra_scalars, const std::vector<std::string>& extra_vectors) {
  const auto grid = read_vtu(path);
  ASSERT_NE(grid, nullptr);
  const auto n = static_cast<vtkIdType>(p.size());
  ASSERT_EQ(grid->GetNumberOfPoints(), n);
  ASSERT_EQ(grid->GetNumberOfCells(), n);

  // Points: 3D, z = 0.
  for (vtkIdType i = 0; i < n; ++i) {
    double x[3];
    grid->GetPoint(i, x);
    ASSERT_EQ(x[0], p.position[static_cast<std::size_t>(i)][0]) << "point " << i;
    ASSERT_EQ(x[1], p.position[static_cast<std::size_t>(i)][1]) << "point " << i;
    ASSERT_EQ(x[2], 0.0) << "point " << i;
  }
  // One vertex cell per particle, cell i = point i.
  for (vtkIdType i = 0; i < n; ++i) {
    ASSERT_EQ(grid->GetCellType(i), VTK_VERTEX) << "cell " << i;
    vtkIdType npts = 0;
    const vtkIdType* pts = nullptr;
    grid->GetCellPoints(i, npts, pts);
    ASSERT_EQ(npts, 1);
    ASSERT_EQ(pts[0], i);
  }

  expect_vectors(grid, "velocity", p.velocity);
  expect_integers(grid, "kind", p.kind, VTK_UNSIGNED_CHAR);
  expect_integers(grid, "body", p.body, VTK_UNSIGNED_SHORT);
  expect_integers(grid, "material", p.material, VTK_SHORT);
  expect_integers(grid, "clamped", p.clamped, VTK_UNSIGNED_CHAR);
  expect_integers(grid, "global_id", p.global_id, -1);
  vtkDataArray* const gid = grid->GetPointData()->GetArray("global_id");
  ASSERT_NE(gid, nullptr);
  EXPECT_EQ(gid->GetDataTypeSize(), 8);
  EXPECT_LT(gid->GetDataTypeMin(), 0.0);
  for (const auto& name : extra_scalars) expect_scalars(grid, name.c_str(), p.scalar_field(name));
  for (const auto& name : extra_vectors) expect_vectors(grid, name.c_str(), p.vector_field(name));
  EXPECT_EQ(grid->GetPointData()->GetNumberOfArrays(),
            static_cast<int>(6 + extra_scalars.size() + extra_vectors.size()));

  vtkDataArray* const tv = grid->GetFieldData()->GetArray("TimeValue");
  ASSERT_NE(tv, nullptr);
  ASSERT_EQ(tv->GetNumberOfTuples(), 1);
  EXPECT_EQ(tv->GetTuple1(0), time);
}

/// No file in `dir` (recursively) ends in ".tmp".
void expect_no_tmp_files(const fs::path& dir) {
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    EXPECT_NE(entry.path().extension(), ".tmp") << entry.path();
  }
}

TEST_F(VtkWriterTest, ThreeFramesRoundTripExactly) {
  VtkSeriesWriter writer(dir_.string());
  EXPECT_EQ(writer.n_frames(), 0u);
  EXPECT_EQ(writer.pvd_path(), (dir_ / "particles.pvd").string());

  const std::vector<double> times = {0.0, 0.1 + 0.2, 1.0 / 3.0};
  std::vector<ParticleSet> frames;
  std::vector<std::string> paths;
  for (std::size_t f = 0; f < times.size(); ++f) {
    frames.push_back(random_particles(static_cast<unsigned>(17 + f), 300 + 29 * f));
    paths.push_back(writer.write(frames.back(), times[f]));
    EXPECT_EQ(writer.n_frames(), f + 1);
  }
  for (std::size_t f = 0; f < times.size(); ++f) {
    const std::string name = "particles_00000" + std::to_string(f) + ".vtu";
    EXPECT_EQ(paths[f], (dir_ / name).string());
    ASSERT_TRUE(fs::exists(paths[f]));
    SCOPED_TRACE(paths[f]);
    expect_frame(paths[f], frames[f], times[f], {"density", "pressure"}, {"displacement"});
  }

  // The .pvd, through read_pvd: times exactly, file names relative to the .pvd.
  ASSERT_TRUE(fs::exists(writer.pvd_path()));
  const auto entries = read_pvd(writer.pvd_path());
  ASSERT_EQ(entries.size(), 3u);
  for (std::size_t f = 0; f < times.size(); ++f) {
    EXPECT_EQ(entries[f].first, times[f]);
    EXPECT_EQ(entries[f].second, "particles_00000" + std::to_string(f) + ".vtu");
  }

  // The .pvd, through VTK's XML parser: a valid Collection with the expected attributes.
  vtkNew<vtkXMLDataParser> parser;
  parser->SetFileName(writer.pvd_path().c_str());
  ASSERT_EQ(parser->Parse(), 1);
  vtkXMLDataElement* const root = parser->GetRootElement();
  ASSERT_NE(root, nullptr);
  EXPECT_STREQ(root->GetAttribute("type"), "Collection");
  vtkXMLDataElement* const collection = root->FindNestedElementWithName("Collection");
  ASSERT_NE(collection, nullptr);
  ASSERT_EQ(collection->GetNumberOfNestedElements(), 3);
  for (int f = 0; f < 3; ++f) {
    vtkXMLDataElement* const ds = collection->GetNestedElement(f);
    EXPECT_STREQ(ds->GetName(), "DataSet");
    EXPECT_EQ(std::stod(ds->GetAttribute("timestep")), times[static_cast<std::size_t>(f)]);
    EXPECT_EQ(std::string(ds->GetAttribute("file")), "particles_00000" + std::to_string(f) + ".vtu");
    EXPECT_STREQ(ds->GetAttribute("part"), "0");
  }

  expect_no_tmp_files(dir_);
}

// Two pieces of a frame (as two ranks write them): each piece holds its owned particles only, the .pvtu
// names both, VTK's parallel reader gives back every particle with its arrays, and the .pvd lists the .pvtu.
TEST_F(VtkWriterTest, PiecesAndParallelFileReadBackAsOneFrame) {
  ParticleSet a = random_particles(3, 120), b = random_particles(4, 80);
  VtkSeriesWriter w0(dir_.string(), "particles", 0, 2), w1(dir_.string(), "particles", 1, 2);
  EXPECT_EQ(w0.write_piece(a, 0.5), (dir_ / "particles_000000_0.vtu").string());
  EXPECT_EQ(w1.write_piece(b, 0.5), (dir_ / "particles_000000_1.vtu").string());
  EXPECT_EQ(w1.commit_frame(0.5), (dir_ / "particles_000000.pvtu").string());
  EXPECT_FALSE(fs::exists(dir_ / "particles_000000.pvtu"));  // piece 0 writes it
  EXPECT_EQ(w0.commit_frame(0.5), (dir_ / "particles_000000.pvtu").string());
  expect_frame((dir_ / "particles_000000_1.vtu").string(), b, 0.5, {"density", "pressure"}, {"displacement"});
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  reader->SetFileName((dir_ / "particles_000000.pvtu").c_str());
  reader->Update();
  vtkUnstructuredGrid* const grid = reader->GetOutput();
  ASSERT_EQ(grid->GetNumberOfPoints(), 200);
  vtkDataArray* const gid = grid->GetPointData()->GetArray("global_id");
  vtkDataArray* const pressure = grid->GetPointData()->GetArray("pressure");
  ASSERT_NE(gid, nullptr);
  ASSERT_NE(pressure, nullptr);
  for (vtkIdType k = 0; k < 200; ++k) {
    const ParticleSet& p = k < 120 ? a : b;
    const auto i = static_cast<std::size_t>(k < 120 ? k : k - 120);
    EXPECT_EQ(gid->GetVariantValue(k).ToLongLong(), p.global_id[i]);
    EXPECT_EQ(pressure->GetTuple1(k), p.scalar_field("pressure")[i]);
    EXPECT_EQ(grid->GetPoint(k)[0], p.position[i][0]);
  }
  const auto entries = read_pvd(w0.pvd_path());
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].second, "particles_000000.pvtu");
  EXPECT_EQ(w1.next_frame(), 1u);
  expect_no_tmp_files(dir_);
}

TEST_F(VtkWriterTest, SetFieldsRestrictsExtraArrays) {
  const ParticleSet p = random_particles(5);
  VtkSeriesWriter writer(dir_.string(), "restricted");
  writer.set_fields({"pressure"});
  const std::string only_pressure = writer.write(p, 0.5);
  expect_frame(only_pressure, p, 0.5, {"pressure"}, {});

  writer.set_fields({"displacement", "pressure", "displacement"});
  const std::string two = writer.write(p, 0.75);
  expect_frame(two, p, 0.75, {"pressure"}, {"displacement"});

  writer.set_fields({});
  const std::string all = writer.write(p, 1.0);
  expect_frame(all, p, 1.0, {"density", "pressure"}, {"displacement"});

  EXPECT_EQ(writer.pvd_path(), (dir_ / "restricted.pvd").string());
  EXPECT_EQ(read_pvd(writer.pvd_path()).size(), 3u);

  writer.set_fields({"no_such_field"});
  EXPECT_THROW(writer.write(p, 2.0), std::invalid_argument);
  EXPECT_EQ(writer.n_frames(), 3u);
  expect_no_tmp_files(dir_);
}

TEST_F(VtkWriterTest, EmptyParticleSet) {
  ParticleSet p;
  p.add_scalar_field("pressure");
  VtkSeriesWriter writer(dir_.string());
  const std::string path = writer.write(p, 0.0);
  expect_frame(path, p, 0.0, {"pressure"}, {});
}

TEST_F(VtkWriterTest, MismatchedArrayLengthIsRejectedBeforeWriting) {
  ParticleSet p = random_particles(9, 10);
  p.scalar_field("pressure").pop_back();
  VtkSeriesWriter writer(dir_.string());
  EXPECT_THROW(writer.write(p, 0.0), std::invalid_argument);
  EXPECT_THROW(writer.write(random_particles(9, 10), std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
  EXPECT_EQ(writer.n_frames(), 0u);
  EXPECT_FALSE(fs::exists(writer.pvd_path()));
}

TEST_F(VtkWriterTest, AdoptExistingFramesOnRestart) {
  const ParticleSet p = random_particles(3, 50);
  {
    VtkSeriesWriter writer(dir_.string());
    for (const double t : {0.0, 0.5, 1.0, 1.5}) writer.write(p, t);
  }
  VtkSeriesWriter restarted(dir_.string());
  restarted.adopt_existing(0.5);
  EXPECT_EQ(restarted.n_frames(), 2u);
  ASSERT_EQ(read_pvd(restarted.pvd_path()).size(), 2u);

  const std::string path = restarted.write(p, 0.75);
  EXPECT_EQ(path, (dir_ / "particles_000002.vtu").string());
  const auto entries = read_pvd(restarted.pvd_path());
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_EQ(entries[0].first, 0.0);
  EXPECT_EQ(entries[1].first, 0.5);
  EXPECT_EQ(entries[2].first, 0.75);
  EXPECT_EQ(entries[2].second, "particles_000002.vtu");
  expect_frame(path, p, 0.75, {"density", "pressure"}, {"displacement"});

  // No .pvd yet: nothing to adopt.
  VtkSeriesWriter fresh((dir_ / "other").string());
  fresh.adopt_existing(10.0);
  EXPECT_EQ(fresh.n_frames(), 0u);
  expect_no_tmp_files(dir_);
}

TEST_F(VtkWriterTest, UnwritableDirectoryThrowsNamingThePath) {
  const ParticleSet p = random_particles(1, 20);
  VtkSeriesWriter writer("/proc/nonexistent/vtk");
  try {
    writer.write(p, 0.0);
    FAIL() << "write into /proc/nonexistent did not throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/nonexistent"), std::string::npos) << e.what();
  }
  EXPECT_EQ(writer.n_frames(), 0u);
  EXPECT_THROW(read_pvd("/proc/nonexistent/particles.pvd"), std::runtime_error);
}

TEST_F(VtkWriterTest, WriterFailureInsideExistingDirectoryThrows) {
  // The directory exists but a directory sits where the .vtu temporary file would go, so VTK's
  // writer itself fails to open its output.
  fs::create_directories(dir_ / "particles_000000.vtu.tmp");
  VtkSeriesWriter writer(dir_.string());
  try {
    writer.write(random_particles(2, 20), 0.0);
    FAIL() << "write onto a directory did not throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((dir_ / "particles_000000.vtu").string()), std::string::npos) << e.what();
  }
  EXPECT_EQ(writer.n_frames(), 0u);
  EXPECT_FALSE(fs::exists(writer.pvd_path()));
}

}  // namespace
}  // namespace mpsfsi
