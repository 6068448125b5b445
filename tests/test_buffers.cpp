// Unit tests of core/buffers.hpp: arrays that grow with headroom keep their capacity while the size creeps, and
// give their storage back when the size falls a long way (the first step's pressure system is the widest).
#include "core/buffers.hpp"

#include <gtest/gtest.h>

#include <vector>

using namespace mpsfsi;

TEST(Buffers, GrowsWithHeadroomAndKeepsItsCapacity) {
  std::vector<int> v;
  resize_with_headroom(v, 800);
  EXPECT_EQ(v.size(), 800u);
  EXPECT_EQ(v.capacity(), 900u);
  const int* data = v.data();
  resize_with_headroom(v, 900);  // within the headroom: no reallocation
  EXPECT_EQ(v.data(), data);
  resize_with_headroom(v, 100);  // a smaller size keeps the storage
  EXPECT_EQ(v.data(), data);
  EXPECT_EQ(v.capacity(), 900u);
}

TEST(Buffers, FitGivesBackWhatAFallenSizeDoesNotNeed) {
  std::vector<int> v(800);
  for (int i = 0; i < 800; ++i) v[static_cast<std::size_t>(i)] = i;
  fit_with_headroom(v, 400);  // capacity 800 <= 2 * 450: kept
  EXPECT_EQ(v.capacity(), 800u);
  EXPECT_EQ(v.size(), 400u);
  fit_with_headroom(v, 100);  // 800 > 2 * 112: reallocated to 112, the first 100 entries kept
  EXPECT_EQ(v.size(), 100u);
  EXPECT_EQ(v.capacity(), 112u);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(v[static_cast<std::size_t>(i)], i);
  fit_with_headroom(v, 200);  // growth as resize_with_headroom
  EXPECT_EQ(v.size(), 200u);
  EXPECT_EQ(v.capacity(), 225u);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(v[static_cast<std::size_t>(i)], i);
  EXPECT_EQ(v[150], 0);
}

TEST(Buffers, TrimKeepsTheEntries) {
  std::vector<double> v;
  v.reserve(1000);
  v.assign({1.5, 2.5, 3.5});
  trim_oversized(v);
  EXPECT_EQ(v.capacity(), 3u);
  EXPECT_EQ(v, (std::vector<double>{1.5, 2.5, 3.5}));
  std::vector<double> w(10, 1.0);
  w.reserve(20);  // 20 <= 2 * 11: kept
  trim_oversized(w);
  EXPECT_EQ(w.capacity(), 20u);
}
