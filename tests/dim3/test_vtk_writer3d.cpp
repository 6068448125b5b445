// Tests of the VTK XML particle output in the 3D build (io/vtk_writer.cpp with MPSFSI_DIM=3): a frame read
// back with VTK's reader has the particles' three coordinates and every vector field (velocity, a vector
// field, the angular fields rotation and angular_velocity) with three exact components; so do the pieces
// of a frame written as several pieces (.pvtu).
#include "core/particles.hpp"
#include "io/vtk_writer.hpp"

#include <gtest/gtest.h>

#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPUnstructuredGridReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <string>

namespace mpsfsi {
namespace {

namespace fs = std::filesystem;

class VtkWriter3dTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    dir_ = fs::temp_directory_path() / ("mpsfsi_test_vtk3d_" + std::to_string(::getpid()) + "_" + std::to_string(stamp));
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }
  fs::path dir_;
};

/// Particles with random 3D positions, velocities, a displacement vector field and the solid's angular
/// fields (vectors in 3D).
ParticleSet random_particles(const unsigned seed, const std::size_t n) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> real(-10.0, 10.0);
  const auto random_vec = [&] { return Vec(real(rng), real(rng), real(rng)); };
  ParticleSet p;
  auto& displacement = p.add_vector_field("displacement");
  auto& rotation = add_angular_field(p, "rotation");
  auto& omega = add_angular_field(p, "angular_velocity");
  auto& pressure = p.add_scalar_field("pressure");
  for (std::size_t i = 0; i < n; ++i) {
    p.add(random_vec(), random_vec(), ParticleKind::solid, 0, 0);
    displacement.back() = random_vec() * 1e-3;
    rotation.back() = random_vec() * 1e-2;
    omega.back() = random_vec();
    pressure.back() = real(rng) * 1e5;
  }
  return p;
}

/// Every point and vector array of `grid` equals the particles' values exactly, with three components.
void expect_same(const ParticleSet& p, vtkUnstructuredGrid* grid, const std::size_t first = 0) {
  ASSERT_NE(grid, nullptr);
  const auto n = static_cast<std::size_t>(grid->GetNumberOfPoints());
  ASSERT_LE(first + n, p.size());
  for (std::size_t i = 0; i < n; ++i) {
    double x[3];
    grid->GetPoint(static_cast<vtkIdType>(i), x);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(x[a], p.position[first + i][a]);
  }
  const auto check = [&](const char* name, const std::vector<Vec>& values) {
    SCOPED_TRACE(name);
    vtkDataArray* array = grid->GetPointData()->GetArray(name);
    ASSERT_NE(array, nullptr);
    ASSERT_EQ(array->GetNumberOfComponents(), 3);
    ASSERT_EQ(static_cast<std::size_t>(array->GetNumberOfTuples()), n);
    for (std::size_t i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) EXPECT_EQ(array->GetComponent(static_cast<vtkIdType>(i), a), values[first + i][a]);
  };
  check("velocity", p.velocity);
  check("displacement", p.vector_field("displacement"));
  check("rotation", angular_field(p, "rotation"));  // scalars in 2D, vectors in 3D
  check("angular_velocity", angular_field(p, "angular_velocity"));
  vtkDataArray* pressure = grid->GetPointData()->GetArray("pressure");
  ASSERT_NE(pressure, nullptr);
  EXPECT_EQ(pressure->GetNumberOfComponents(), 1);
}

TEST_F(VtkWriter3dTest, PointsAndVectorFieldsHaveThreeComponents) {
  const ParticleSet p = random_particles(7, 257);
  VtkSeriesWriter writer(dir_.string());
  const std::string path = writer.write(p, 0.25);
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  EXPECT_EQ(static_cast<std::size_t>(reader->GetOutput()->GetNumberOfPoints()), p.size());
  expect_same(p, reader->GetOutput());
}

TEST_F(VtkWriter3dTest, PiecesOfAFrame) {
  // Two writers stand for two ranks: each writes its half as a piece; piece 0 writes the .pvtu.
  const ParticleSet all = random_particles(11, 100);
  ParticleSet halves[2];
  for (int q = 0; q < 2; ++q) {
    halves[q] = random_particles(11, 100);
    std::vector<std::uint8_t> remove(100);
    for (std::size_t i = 0; i < remove.size(); ++i) remove[i] = (i < 50) != (q == 0);
    halves[q].remove_if(remove);
  }
  VtkSeriesWriter w1(dir_.string(), "particles", 1, 2);
  VtkSeriesWriter w0(dir_.string(), "particles", 0, 2);
  w1.write_piece(halves[1], 0.5);
  w0.write_piece(halves[0], 0.5);
  w1.commit_frame(0.5);
  const std::string pvtu = w0.commit_frame(0.5);
  vtkNew<vtkXMLPUnstructuredGridReader> reader;
  reader->SetFileName(pvtu.c_str());
  reader->Update();
  EXPECT_EQ(reader->GetOutput()->GetNumberOfPoints(), 100);
  expect_same(all, reader->GetOutput());
}

}  // namespace
}  // namespace mpsfsi
