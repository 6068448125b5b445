// Unit tests of the particle set (core/particles.hpp): owned and ghost ranges, the one map from global id
// to local index, which must follow every reorder, removal and checkpoint load, and packing for transfers.
#include "core/binary_io.hpp"
#include "core/particles.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
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

TEST(ParticleSet, PackUnpackCarriesEveryArrayAndGhostsStayLast) {
  ParticleSet p = five_particles();
  auto& s = p.add_scalar_field("s", 0);
  auto& v = p.add_vector_field("v");
  for (std::size_t i = 0; i < p.size(); ++i) {
    s[i] = 10.0 + static_cast<Real>(i);
    v[i] = Vec::Constant(-static_cast<Real>(i));
    p.velocity[i] = Vec::Constant(0.5 * static_cast<Real>(i));
    p.kind[i] = ParticleKind::solid;
    p.clamped[i] = static_cast<std::uint8_t>(i % 2);
  }
  std::vector<char> buf;
  p.pack({3, 1}, buf);
  EXPECT_EQ(buf.size(), 2 * p.packed_size());

  ParticleSet q;
  q.bodies = p.bodies;
  q.add_scalar_field("s", 0);
  q.add_vector_field("v");
  EXPECT_EQ(q.field_layout(), p.field_layout());
  q.unpack_owned(buf.data(), 1);  // particle 3 as owned
  q.unpack_ghosts(buf.data() + q.packed_size(), 1);  // particle 1 as a ghost
  ASSERT_EQ(q.size(), 2u);
  EXPECT_EQ(q.n_owned(), 1u);
  EXPECT_EQ(q.n_ghost(), 1u);
  EXPECT_EQ(q.global_id[0], 3);
  EXPECT_EQ(q.global_id[1], 1);
  EXPECT_EQ(q.local_index(1), 1);
  EXPECT_EQ(q.position[0], p.position[3]);
  EXPECT_EQ(q.velocity[1], p.velocity[1]);
  EXPECT_EQ(q.kind[0], ParticleKind::solid);
  EXPECT_EQ(q.clamped[0], 1);
  EXPECT_EQ(q.clamped[1], 1);
  EXPECT_EQ(q.scalar_field("s")[0], 13.0);
  EXPECT_EQ(q.vector_field("v")[1], Vec::Constant(-1.0));

  auto arr = q.real_array("v");
  EXPECT_EQ(arr.components, dim);
  EXPECT_EQ(arr.data[dim], -1.0);
  EXPECT_THROW(q.real_array("nonexistent"), std::out_of_range);

  q.drop_ghosts();
  EXPECT_EQ(q.size(), 1u);
  EXPECT_EQ(q.n_ghost(), 0u);
  EXPECT_EQ(q.local_index(1), -1);
  EXPECT_EQ(q.local_index(3), 0);
  EXPECT_EQ(q.scalar_field("s").size(), 1u);
}
