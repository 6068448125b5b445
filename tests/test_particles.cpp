// Unit tests of the particle set (core/particles.hpp): owned and ghost ranges, and the one map from global id
// to local index, which must follow every reorder, removal and checkpoint load.
#include "core/binary_io.hpp"
#include "core/particles.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

using namespace mpsfsi;

namespace {

ParticleSet five_particles() {
  ParticleSet p;
  p.bodies.push_back({"b", ParticleKind::fluid, 0});
  for (int i = 0; i < 5; ++i) p.add(Vec::Constant(i), Vec::Zero(), ParticleKind::fluid, 0, 0);
  return p;
}

void expect_map_consistent(const ParticleSet& p) {
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_EQ(p.local_index(p.global_id[i]), static_cast<LocalIndex>(i));
}

}  // namespace

TEST(ParticleSet, OneRankOwnsEverything) {
  const ParticleSet p = five_particles();
  EXPECT_EQ(p.n_owned(), 5u);
  EXPECT_EQ(p.n_ghost(), 0u);
  EXPECT_EQ(p.size(), 5u);
}

TEST(ParticleSet, LocalIndexFollowsReorderAndRemoval) {
  ParticleSet p = five_particles();
  expect_map_consistent(p);
  EXPECT_EQ(p.local_index(7), -1);
  p.reorder({4, 2, 0, 3, 1});
  EXPECT_EQ(p.local_index(4), 0);
  EXPECT_EQ(p.local_index(1), 4);
  expect_map_consistent(p);
  p.remove_if({0, 1, 0, 0, 1});  // removes global ids 2 and 1
  EXPECT_EQ(p.size(), 3u);
  EXPECT_EQ(p.local_index(2), -1);
  EXPECT_EQ(p.local_index(1), -1);
  EXPECT_EQ(p.local_index(3), 2);
  expect_map_consistent(p);
  p.add(Vec::Zero(), Vec::Zero(), ParticleKind::fluid, 0, 0);  // a new particle gets a new id, not its index
  EXPECT_EQ(p.global_id[3], 5);
  EXPECT_EQ(p.local_index(3), 2);
  expect_map_consistent(p);
}

TEST(ParticleSet, LocalIndexAfterLoadState) {
  ParticleSet p = five_particles();
  p.reorder({1, 0, 2, 3, 4});
  BinaryWriter w;
  p.save_state(w);
  ParticleSet q = five_particles();
  EXPECT_EQ(q.local_index(0), 0);  // builds q's map before the load replaces its arrays
  BinaryReader r(w.bytes(), "test");
  q.load_state(r);
  EXPECT_EQ(q.local_index(0), 1);
  expect_map_consistent(q);
}
