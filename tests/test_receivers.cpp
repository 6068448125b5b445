// Unit tests of the receivers (io/receivers.hpp; issue 6): the kernel-averaged displacement is exact
// for a linear displacement field at a receiver inside the body, between particles, on the free surface
// and at a corner; receivers.csv has the documented columns and rows (every call, or at the interval);
// a reordered particle set is followed; a receiver without enough particles is a CaseError naming it.
#include "io/receivers.hpp"
#include "io/scene.hpp"
#include "support/spec_builders.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace mpsfsi {
namespace {

CaseSpec block_case() {
  CaseSpec spec = test::base_case(0.1, 10);
  SolidMaterial m;
  m.name = "rock";
  spec.solid_materials.push_back(m);
  spec.bodies.push_back(test::solid_body("ground", "rock", Vec(-1, -1), Vec(1, 0)));
  spec.receivers.radius = 0.2;
  const std::vector<std::pair<std::string, Vec>> points = {
      {"inside", Vec(0.05, -0.45)}, {"between", Vec(0.3, -0.5)}, {"surface", Vec(0.42, 0)}, {"corner", Vec(-1, 0)}};
  for (const auto& [name, x] : points) spec.receivers.points.push_back({name, "ground", x});
  return spec;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(Receivers, ExactForALinearDisplacementField) {
  const CaseSpec spec = block_case();
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  const ReceiverWriter rw(spec, p, "");
  EXPECT_FALSE(rw.empty());
  EXPECT_EQ(rw.columns(), (std::vector<std::string>{"inside_ux", "inside_uy", "between_ux", "between_uy", "surface_ux",
                                                    "surface_uy", "corner_ux", "corner_uy"}));
  // u(x) = a + G x, small.
  const Vec a(1e-6, -2e-6);
  Mat g;
  g << 3e-6, -1e-6, 2e-6, 5e-6;
  for (auto& x : p.position) x += a + g * x;
  const std::vector<Vec> u = rw.evaluate(p);
  ASSERT_EQ(u.size(), spec.receivers.points.size());
  for (std::size_t r = 0; r < u.size(); ++r) {
    const Vec expected = a + g * spec.receivers.points[r].position;
    EXPECT_LT((u[r] - expected).norm(), 1e-12 * expected.norm() + 1e-15) << spec.receivers.points[r].name;
  }
}

TEST(Receivers, FollowsAReorderedParticleSet) {
  const CaseSpec spec = block_case();
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  const ReceiverWriter rw(spec, p, "");
  for (std::size_t i = 0; i < p.size(); ++i) p.position[i][0] += 1e-6 * p.position[i][1];  // shear
  const std::vector<Vec> before = rw.evaluate(p);
  std::vector<LocalIndex> order(p.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<LocalIndex>(order.size() - 1 - k);
  p.reorder(order);
  const std::vector<Vec> after = rw.evaluate(p);
  for (std::size_t r = 0; r < before.size(); ++r) EXPECT_LT((after[r] - before[r]).norm(), 1e-18);
  EXPECT_NEAR(after[0][0], 1e-6 * -0.45, 1e-15);
}

TEST(Receivers, CsvEveryCallOrAtTheInterval) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "mpsfsi_test_receivers";
  fs::create_directories(dir);
  CaseSpec spec = block_case();
  spec.receivers.points.resize(1);
  Scene scene = build_scene(spec);
  {
    ReceiverWriter rw(spec, scene.particles, (dir / "every.csv").string());
    for (int k = 0; k <= 3; ++k) rw.record_if_due(k * 1e-5, scene.particles);
  }
  EXPECT_EQ(read_text((dir / "every.csv").string()),
            "time,inside_ux,inside_uy\n0,0,0\n1e-05,0,0\n2e-05,0,0\n3e-05,0,0\n");
  spec.receivers.interval = 2.5e-5;
  {
    ReceiverWriter rw(spec, scene.particles, (dir / "interval.csv").string());
    for (int k = 0; k <= 10; ++k) rw.record_if_due(k * 1e-5, scene.particles);
  }
  // Rows at the first call, then at the first step at or after 2.5e-5, 5e-5, 7.5e-5, 1e-4.
  EXPECT_EQ(read_text((dir / "interval.csv").string()),
            "time,inside_ux,inside_uy\n0,0,0\n3e-05,0,0\n5e-05,0,0\n8e-05,0,0\n0.0001,0,0\n");
  fs::remove_all(dir);
}

TEST(Receivers, TooFewParticlesNamesTheReceiver) {
  CaseSpec spec = block_case();
  spec.receivers.radius = 0.05;
  Scene scene = build_scene(spec);
  try {
    ReceiverWriter rw(spec, scene.particles, "");
    FAIL() << "no error";
  } catch (const CaseError& e) {
    EXPECT_NE(std::string(e.what()).find("receiver 'inside' at (0.05, -0.45) on body 'ground'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace mpsfsi
