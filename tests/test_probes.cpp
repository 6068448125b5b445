// Unit tests of the probes (io/probes.hpp) that read the free surface: a wave gauge gives the top of the fluid
// within dp of its x (the highest fluid particle there plus dp/2), not walls or the fluid further along, and
// its own height over a dry floor.
#include "io/probes.hpp"

#include "support/spec_builders.hpp"

#include <gtest/gtest.h>

namespace mpsfsi {
namespace {

ProbeSpec gauge(const std::string& name, const Real x, const Real floor) {
  ProbeSpec g;
  g.name = name;
  g.type = ProbeType::wave_gauge;
  g.position = Vec(x, floor);
  return g;
}

TEST(Probes, WaveGaugeReadsTheFluidTopAtItsX) {
  const Real dp = 0.01;
  CaseSpec spec = test::base_case(dp, 10);
  spec.probes = {gauge("a", 0.2, 0), gauge("b", 0.5, 0), gauge("dry", 2.0, -0.05)};
  ParticleSet p;
  p.bodies.push_back({"water", ParticleKind::fluid, 0});
  // A free surface y = 0.1 + 0.05 x (the top particle of each column dp/2 below it), on columns dp apart.
  for (int i = 0; i < 100; ++i) {
    const Real x = (i + 0.5) * dp;
    for (Real y = 0.5 * dp; y < 0.1 + 0.05 * x - 0.5 * dp; y += dp) p.add(Vec(x, y), Vec::Zero(), ParticleKind::fluid, 0, 0);
  }
  // A drop high above x = 0.3 (outside gauge a's strip) and a wall column at x = 0.2 (not fluid).
  p.add(Vec(0.3, 0.5), Vec::Zero(), ParticleKind::fluid, 0, 0);
  for (int j = 0; j < 40; ++j) p.add(Vec(0.2, j * dp), Vec::Zero(), ParticleKind::wall, 0, 0);
  const ProbeWriter probes(spec, p, "");
  const std::vector<Real> v = probes.evaluate(p, 0);
  ASSERT_EQ(v.size(), 3u);
  // Gauge a: the columns within dp of x = 0.2 are x = 0.195 and 0.205; the higher one's top particle.
  Real top_a = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::fluid && std::abs(p.position[i][0] - 0.2) < dp) top_a = std::max(top_a, p.position[i][1]);
  EXPECT_DOUBLE_EQ(v[0], top_a + 0.5 * dp);
  EXPECT_NEAR(v[0], 0.1 + 0.05 * 0.205, dp);
  EXPECT_NEAR(v[1], 0.1 + 0.05 * 0.505, dp);
  EXPECT_GT(v[1], v[0]);
  EXPECT_DOUBLE_EQ(v[2], -0.05);  // no fluid within dp of x = 2: the gauge's own height
}

}  // namespace
}  // namespace mpsfsi
