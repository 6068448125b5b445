// Tests of the distribution of particles over MPI ranks (core/distribution.hpp), run on 1, 2, 3 and 4 ranks:
// ownership after distribute_replicated / migrate / partition (every particle on exactly one rank, with all its
// arrays), regions that tile space, ghosts that give the same number density as one rank holding everything,
// exchange_ghosts (also of one kind of particle) and reverse_sum against independently computed values, and the
// imbalance measure.
#include "core/distribution.hpp"
#include "core/neighbours.hpp"
#include "core/operators.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

using namespace mpsfsi;

namespace {

constexpr Real dp = 0.01;
const MPI_Comm world = MPI_COMM_WORLD;

int world_size() {
  int n = 1;
  MPI_Comm_size(world, &n);
  return n;
}

/// A uniform number in [0, 1) from a key (the same on every rank).
Real u01(std::uint64_t key) {
  key += 0x9e3779b97f4a7c15ULL;
  key = (key ^ (key >> 30)) * 0xbf58476d1ce4e5b9ULL;
  key = (key ^ (key >> 27)) * 0x94d049bb133111ebULL;
  key ^= key >> 31;
  return static_cast<Real>(key >> 11) * 0x1.0p-53;
}
Vec random_vec(const std::uint64_t key) {
  Vec v;
  for (int a = 0; a < dim; ++a) v[a] = u01(key * 7 + static_cast<std::uint64_t>(a)) - 0.5;
  return v;
}

Real f_scalar(const GlobalId g) { return 0.5 * static_cast<Real>(g) + 1.0; }
Vec f_vector(const GlobalId g) { return Vec::Constant(-static_cast<Real>(g)); }

/// A lattice block (60 x 40 in 2D) with spacing dp and a small jitter, built identically on every rank, with a
/// scalar and a vector field and per-particle values that are functions of the global id.
ParticleSet lattice(const Real jitter = 0.05) {
  const int n_axis[3] = {60, 40, 10};
  int total = 1;
  for (int a = 0; a < dim; ++a) total *= n_axis[a];
  ParticleSet p;
  p.bodies.push_back({"water", ParticleKind::fluid, 0});
  p.bodies.push_back({"wall", ParticleKind::wall, -1});
  auto& s = p.add_scalar_field("pressure");
  auto& v = p.add_vector_field("force");
  p.add_scalar_field("count");
  for (int k = 0; k < total; ++k) {
    Vec x;
    int rest = k;
    for (int a = 0; a < dim; ++a) {
      x[a] = dp * (rest % n_axis[a]);
      rest /= n_axis[a];
    }
    x += jitter * dp * random_vec(static_cast<std::uint64_t>(k));
    const bool wall = k % 7 == 0;
    p.add(x, Vec::Constant(0.25 * k), wall ? ParticleKind::wall : ParticleKind::fluid, wall ? 1 : 0, wall ? -1 : 0,
          k % 5 == 0);
    s.back() = f_scalar(k);
    v.back() = f_vector(k);
  }
  return p;
}

std::vector<GlobalId> all_gather(const std::vector<GlobalId>& mine) {
  const int P = world_size();
  int n = static_cast<int>(mine.size());
  std::vector<int> counts(P), displ(P);
  MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, world);
  int total = 0;
  for (int q = 0; q < P; ++q) {
    displ[q] = total;
    total += counts[q];
  }
  std::vector<GlobalId> out(static_cast<std::size_t>(total));
  MPI_Allgatherv(mine.data(), n, MPI_LONG_LONG, out.data(), counts.data(), displ.data(), MPI_LONG_LONG, world);
  return out;
}

std::vector<GlobalId> owned_ids(const ParticleSet& p) {
  return std::vector<GlobalId>(p.global_id.begin(), p.global_id.begin() + static_cast<std::ptrdiff_t>(p.n_owned()));
}

/// Every global id 0..n-1 owned by exactly one rank; every owned particle in this rank's region; every array
/// still the function of the global id it was built with (positions excepted).
void expect_owned_once(const Distribution& d, const ParticleSet& p, const std::size_t n_total) {
  auto ids = all_gather(owned_ids(p));
  std::sort(ids.begin(), ids.end());
  std::vector<GlobalId> expected(n_total);
  std::iota(expected.begin(), expected.end(), GlobalId{0});
  EXPECT_EQ(ids, expected);
  EXPECT_EQ(p.n_ghost(), 0u);
  std::size_t wrong_owner = 0, wrong_field = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    const GlobalId g = p.global_id[i];
    wrong_owner += d.owner_of(p.position[i]) != d.rank();
    const bool wall = g % 7 == 0;
    wrong_field += p.scalar_field("pressure")[i] != f_scalar(g) || p.vector_field("force")[i] != f_vector(g) ||
                   p.velocity[i] != Vec::Constant(0.25 * static_cast<Real>(g)) ||
                   p.kind[i] != (wall ? ParticleKind::wall : ParticleKind::fluid) || p.body[i] != (wall ? 1 : 0) ||
                   p.material[i] != (wall ? -1 : 0) || p.clamped[i] != (g % 5 == 0 ? 1 : 0) ||
                   p.local_index(g) != static_cast<LocalIndex>(i);
  }
  EXPECT_EQ(wrong_owner, 0u);
  EXPECT_EQ(wrong_field, 0u);
}

/// How many regions contain x (every point must be in exactly one).
int n_containing(const Distribution& d, const Vec& x) {
  int n = 0;
  for (const auto& b : d.regions()) n += b.contains(x);
  return n;
}

class DistributionMethod : public ::testing::TestWithParam<PartitionMethod> {};

DistributionSettings settings(const PartitionMethod m, const Real halo = 0) {
  DistributionSettings s;
  s.method = m;
  s.halo_width = halo;
  return s;
}

}  // namespace

TEST_P(DistributionMethod, ReplicatedThenMigrateKeepsEveryParticleOnceWithItsFields) {
  Distribution d(world, settings(GetParam()));
  ParticleSet p = lattice();
  const std::size_t n = p.size();
  d.distribute_replicated(p);
  EXPECT_EQ(d.regions().size(), static_cast<std::size_t>(world_size()));
  expect_owned_once(d, p, n);
  for (int round = 0; round < 4; ++round) {
    // Displacements up to 10 dp (round 3: up to half the block), so particles cross several regions.
    const Real amplitude = round == 3 ? 0.3 : 0.1;
    for (std::size_t i = 0; i < p.n_owned(); ++i)
      p.position[i] += amplitude * random_vec(static_cast<std::uint64_t>(p.global_id[i]) * 31 + round);
    d.migrate(p);
    expect_owned_once(d, p, n);
  }
  // Particles only move when the regions say so: a second migrate sends nothing.
  d.migrate(p);
  EXPECT_EQ(d.stats().n_migrated_out, 0u);
}

TEST_P(DistributionMethod, RegionsTileSpace) {
  Distribution d(world, settings(GetParam()));
  ParticleSet p = lattice();
  d.distribute_replicated(p);
  const auto& regions = d.regions();
  // Coordinates to try on each axis: random ones far outside and inside the block, and every finite face.
  std::vector<std::vector<Real>> coords(dim);
  for (int a = 0; a < dim; ++a) {
    for (int k = 0; k < 40; ++k) coords[a].push_back((u01(1000 + 40 * a + k) - 0.5) * (k < 20 ? 1e3 : 1.0));
    for (const auto& b : regions) {
      if (std::isfinite(b.lo[a])) coords[a].push_back(b.lo[a]);
      if (std::isfinite(b.hi[a])) coords[a].push_back(b.hi[a]);
    }
  }
  std::size_t n_points = 0, bad = 0;
  const auto check = [&](const Vec& x) {
    ++n_points;
    const int n = n_containing(d, x);
    const int o = d.owner_of(x);
    bad += n != 1 || o < 0 || o >= world_size() || !regions[static_cast<std::size_t>(o)].contains(x);
  };
  // Every combination of the candidate coordinates of axes 0 and 1 (others random): face crossings included.
  for (const Real c0 : coords[0])
    for (const Real c1 : coords[1]) {
      Vec x = 0.5 * random_vec(static_cast<std::uint64_t>(n_points));
      x[0] = c0;
      x[1] = c1;
      check(x);
    }
  for (int k = 0; k < 2000; ++k) check(Vec(1e6 * random_vec(50000 + k)));
  check(Vec::Constant(std::numeric_limits<Real>::max()));
  check(Vec::Constant(-std::numeric_limits<Real>::max()));
  EXPECT_EQ(bad, 0u) << "of " << n_points << " points";
  // Box::distance: 0 inside, the Euclidean gap outside.
  for (const auto& b : regions)
    if (b.lo.allFinite()) {
      EXPECT_EQ(b.distance(b.lo), 0.0);
    }
}

TEST_P(DistributionMethod, FewOrNoParticles) {
  for (const int n_particles : {0, 1, 3}) {
    Distribution d(world, settings(GetParam(), 2 * dp));
    ParticleSet full = lattice();
    std::vector<std::uint8_t> remove(full.size(), 1);
    for (int k = 0; k < n_particles; ++k) remove[static_cast<std::size_t>(k * 37)] = 0;
    full.remove_if(remove);
    ParticleSet p = full;
    d.distribute_replicated(p);
    auto ids = all_gather(owned_ids(p));
    EXPECT_EQ(ids.size(), static_cast<std::size_t>(n_particles));
    std::sort(ids.begin(), ids.end());
    EXPECT_TRUE(std::adjacent_find(ids.begin(), ids.end()) == ids.end());
    for (std::size_t i = 0; i < p.n_owned(); ++i) EXPECT_EQ(d.owner_of(p.position[i]), d.rank());
    for (int k = 0; k < 200; ++k) EXPECT_EQ(n_containing(d, Vec(10 * random_vec(k))), 1);
    d.build_ghosts(p);
    d.migrate(p);
    EXPECT_EQ(all_gather(owned_ids(p)).size(), static_cast<std::size_t>(n_particles));
  }
}

TEST_P(DistributionMethod, PartitionFromOneRankHoldingEverything) {
  Distribution d(world, settings(GetParam()));
  ParticleSet p = lattice();
  const std::size_t n = p.size();
  if (d.rank() != 0) {
    std::vector<std::uint8_t> all(p.size(), 1);
    p.remove_if(all);
  }
  d.partition(p);
  expect_owned_once(d, p, n);
  EXPECT_LT(d.imbalance(p), 0.05);
}

TEST_P(DistributionMethod, GhostsGiveTheOneRankNumberDensity) {
  const Real re = 2.1 * dp;
  Distribution d(world, settings(GetParam(), re));
  const ParticleSet full = lattice(0.2);
  ParticleSet p = full;
  d.distribute_replicated(p);
  d.build_ghosts(p);
  // Each ghost's owner is another rank, whose region holds it.
  for (std::size_t k = 0; k < p.n_ghost(); ++k) {
    EXPECT_NE(d.ghost_owner(k), d.rank());
    EXPECT_EQ(d.ghost_owner(k), d.owner_of(p.position[p.n_owned() + k]));
  }
  if (world_size() == 1) {
    EXPECT_EQ(p.n_ghost(), 0u);
  }

  // The ghosts are exactly the other ranks' particles within re of this rank's region, each once.
  std::vector<GlobalId> expected, got;
  for (std::size_t i = 0; i < full.size(); ++i)
    if (d.owner_of(full.position[i]) != d.rank() && d.regions()[d.rank()].distance(full.position[i]) <= re)
      expected.push_back(full.global_id[i]);
  for (std::size_t i = p.n_owned(); i < p.size(); ++i) {
    got.push_back(p.global_id[i]);
    EXPECT_EQ(p.local_index(p.global_id[i]), static_cast<LocalIndex>(i));
    EXPECT_EQ(p.position[i], full.position[static_cast<std::size_t>(p.global_id[i])]);
  }
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, expected);

  // Number density over owned + ghosts equals the one-rank value at every owned particle.
  NeighbourList nl_full, nl;
  build_neighbour_list(full.position, re, nl_full);
  build_neighbour_list(p.position, re, nl);
  std::size_t bad = 0;
  Real worst = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    const auto gi = static_cast<std::size_t>(p.global_id[i]);
    const auto mine = number_density_at(p.position, nl, re, i, AllNeighbours{});
    const auto ref = number_density_at(full.position, nl_full, re, gi, AllNeighbours{});
    const Real rel = std::abs(mine.n - ref.n) / ref.n;
    worst = std::max(worst, rel);
    bad += rel > 1e-12 || mine.count != ref.count;
  }
  EXPECT_EQ(bad, 0u) << "worst relative difference " << worst;
}

TEST_P(DistributionMethod, ExchangeGhostsAndReverseSum) {
  Distribution d(world, settings(GetParam(), 2.1 * dp));
  ParticleSet p = lattice();
  d.distribute_replicated(p);
  d.build_ghosts(p);
  auto& pressure = p.scalar_field("pressure");
  auto& force = p.vector_field("force");
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    pressure[i] = 3.0 * static_cast<Real>(p.global_id[i]) + 0.125;
    force[i] = Vec::Constant(std::sqrt(static_cast<Real>(p.global_id[i])));
    p.velocity[i] = Vec::Constant(-1.5 * static_cast<Real>(p.global_id[i]));
  }
  for (std::size_t i = p.n_owned(); i < p.size(); ++i) {
    pressure[i] = -1;
    force[i] = Vec::Constant(-1);
  }
  const std::size_t bytes_before = d.stats().halo_bytes;
  d.exchange_ghosts(p, {"pressure", "force", "velocity"});
  std::size_t bad = 0;
  for (std::size_t i = p.n_owned(); i < p.size(); ++i) {
    const auto g = static_cast<Real>(p.global_id[i]);
    bad += pressure[i] != 3.0 * g + 0.125 || force[i] != Vec::Constant(std::sqrt(g)) ||
           p.velocity[i] != Vec::Constant(-1.5 * g);
  }
  EXPECT_EQ(bad, 0u);
  if (p.n_ghost() > 0) {
    EXPECT_GT(d.stats().halo_bytes, bytes_before);
  }
  EXPECT_THROW(d.exchange_ghosts(p, {"pressure", "no_such_field"}), std::out_of_range);

  // Only the wall ghosts: the fluid ghosts keep their values.
  for (std::size_t i = 0; i < p.n_owned(); ++i) pressure[i] = -2.0 * static_cast<Real>(p.global_id[i]);
  d.exchange_ghosts(p, {"pressure"}, ParticleKind::wall);
  bad = 0;
  std::size_t n_wall_ghosts = 0;
  for (std::size_t i = p.n_owned(); i < p.size(); ++i) {
    const auto g = static_cast<Real>(p.global_id[i]);
    const bool wall = p.kind[i] == ParticleKind::wall;
    n_wall_ghosts += wall;
    bad += pressure[i] != (wall ? -2.0 * g : 3.0 * g + 0.125);
  }
  EXPECT_EQ(bad, 0u);
  if (world_size() > 1) {
    unsigned long long local[2] = {n_wall_ghosts, p.n_ghost() - n_wall_ghosts};
    MPI_Allreduce(MPI_IN_PLACE, local, 2, MPI_UNSIGNED_LONG_LONG, MPI_SUM, world);
    EXPECT_GT(local[0], 0u);  // both kinds among the ghosts: the test is not vacuous
    EXPECT_GT(local[1], 0u);
  }

  // reverse_sum: 1 at every particle held (owned and ghost); owners end with 1 + the number of ranks holding
  // them as ghosts, counted from all ranks' ghost ids.
  auto& count = p.scalar_field("count");
  std::fill(count.begin(), count.end(), 1.0);
  std::vector<GlobalId> ghosts(p.global_id.begin() + static_cast<std::ptrdiff_t>(p.n_owned()), p.global_id.end());
  std::map<GlobalId, int> times_ghost;
  for (const GlobalId g : all_gather(ghosts)) ++times_ghost[g];
  d.reverse_sum(p, {"count"});
  bad = 0;
  std::size_t held_elsewhere = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    const auto it = times_ghost.find(p.global_id[i]);
    const int k = it == times_ghost.end() ? 0 : it->second;
    held_elsewhere += k > 0;
    bad += count[i] != 1.0 + k;
  }
  for (std::size_t i = p.n_owned(); i < p.size(); ++i) bad += count[i] != 0.0;
  EXPECT_EQ(bad, 0u);
  if (world_size() > 1) {
    unsigned long long local = held_elsewhere, total = 0;
    MPI_Allreduce(&local, &total, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, world);
    EXPECT_GT(total, 0u);  // the test above is not vacuous
  }
}

TEST_P(DistributionMethod, ImbalanceAndRepartition) {
  Distribution d(world, settings(GetParam()));
  ParticleSet p = lattice();
  const std::size_t n = p.size();
  d.distribute_replicated(p);

  // The definition, computed here from every rank's gathered work.
  const auto counts = [&](const Real local) {
    std::vector<Real> all(static_cast<std::size_t>(world_size()));
    MPI_Allgather(&local, 1, MPI_DOUBLE, all.data(), 1, MPI_DOUBLE, world);
    const Real total = std::accumulate(all.begin(), all.end(), 0.0);
    return total == 0 ? 0.0 : *std::max_element(all.begin(), all.end()) / (total / world_size()) - 1;
  };
  EXPECT_DOUBLE_EQ(d.imbalance(p), counts(static_cast<Real>(p.n_owned())));
  std::vector<Real> w(p.n_owned());
  Real local_w = 0;
  for (std::size_t i = 0; i < w.size(); ++i) local_w += (w[i] = 1.0 + static_cast<Real>(p.global_id[i] % 3));
  EXPECT_DOUBLE_EQ(d.imbalance(p, w), counts(local_w));
  {
    // Rank r holding r + 1 units of work out of P (P + 1) / 2: imbalance 2 P / (P + 1) - 1.
    ParticleSet q = lattice();
    std::vector<std::uint8_t> remove(q.size(), 1);
    for (int k = 0; k <= d.rank(); ++k) remove[static_cast<std::size_t>(k)] = 0;
    q.remove_if(remove);
    const Real P = world_size();
    EXPECT_NEAR(d.imbalance(q), 2 * P / (P + 1) - 1, 1e-14);
    std::vector<std::uint8_t> none(q.size(), 1);
    q.remove_if(none);
    EXPECT_EQ(d.imbalance(q), 0.0);
  }

  // Everything squeezed into a corner: after migrate one or a few ranks hold it all; partition rebalances.
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    p.position[i] = Vec::Constant(-1.0) + 0.05 * (random_vec(static_cast<std::uint64_t>(p.global_id[i]) + 99) +
                                                  Vec::Constant(0.5));
  d.migrate(p);
  expect_owned_once(d, p, n);
  const int before = d.stats().n_partitions;
  d.partition(p);
  EXPECT_EQ(d.stats().n_partitions, before + 1);
  expect_owned_once(d, p, n);
  EXPECT_LT(d.imbalance(p), 0.05);

  // Weighted: the weighted work is balanced.
  std::vector<Real> wp(p.n_owned());
  for (std::size_t i = 0; i < wp.size(); ++i) wp[i] = 1.0 + static_cast<Real>(p.global_id[i] % 3);
  d.partition(p, wp);
  expect_owned_once(d, p, n);
  wp.resize(p.n_owned());
  for (std::size_t i = 0; i < wp.size(); ++i) wp[i] = 1.0 + static_cast<Real>(p.global_id[i] % 3);
  EXPECT_LT(d.imbalance(p, wp), 0.05);
}

TEST_P(DistributionMethod, CutsLieInTheGapsBetweenLatticePlanes) {
  // A jittered lattice (every plane fuzzed by +-0.025 dp): with a skin, every cut lies at least 0.45 dp from the
  // points on either side of it (the gaps between planes are at least 0.95 dp wide), so that no plane lies on a
  // cut, wherever Zoltan2 put it. One plane across x dropped: 59 planes, so that an even split lies within one.
  ParticleSet all = lattice();
  {
    std::vector<std::uint8_t> first_plane(all.size());
    for (std::size_t i = 0; i < all.size(); ++i) first_plane[i] = all.position[i][0] < 0.5 * dp;
    all.remove_if(first_plane);
  }
  {
    DistributionSettings s = settings(GetParam());
    s.skin = 2 * dp;
    Distribution d(world, s);
    ParticleSet p = all;
    d.distribute_replicated(p);
    std::size_t near_a_cut = 0, n_cuts = 0;
    for (const Box& b : d.regions())
      for (int a = 0; a < dim; ++a) {
        if (!std::isfinite(b.hi[a]) || !(b.lo[a] <= b.hi[a])) continue;
        ++n_cuts;
        for (const Vec& x : all.position) {
          bool beside = true;  // within the face's extent on the other axes
          for (int e = 0; e < dim; ++e) beside &= e == a || (b.lo[e] <= x[e] && x[e] < b.hi[e]);
          near_a_cut += beside && std::abs(x[a] - b.hi[a]) < 0.45 * dp;
        }
      }
    if (world_size() == 1) {
      EXPECT_EQ(n_cuts, 0u);
    } else {
      EXPECT_GT(n_cuts, 0u);
      EXPECT_EQ(near_a_cut, 0u) << "points closer than 0.45 dp to one of " << n_cuts << " cuts";
      // Every particle owned once; each cut moved by less than a plane (a plane across x or y holds at most 1/40
      // of the block's points).
      auto ids = all_gather(owned_ids(p));
      std::sort(ids.begin(), ids.end());
      EXPECT_EQ(ids, std::vector<GlobalId>(all.global_id.begin(), all.global_id.end()));
      EXPECT_LT(d.imbalance(p), 0.05 + world_size() / 40.0);
    }
  }
}

TEST(Distribution, NonFinitePositionIsRefusedOnEveryRankNamingTheParticle) {
  Distribution d(world, settings(PartitionMethod::rcb));
  ParticleSet p = lattice();
  d.distribute_replicated(p);
  // The smallest global id held by rank 0 gets a NaN position.
  GlobalId bad = p.n_owned() > 0 && d.rank() == 0 ? *std::min_element(p.global_id.begin(), p.global_id.end()) : -1;
  MPI_Bcast(&bad, 1, MPI_LONG_LONG, 0, world);
  ASSERT_GE(bad, 0);
  if (d.rank() == 0) p.position[static_cast<std::size_t>(p.local_index(bad))][0] = std::nan("");
  try {
    d.migrate(p);
    ADD_FAILURE() << "migrate accepted a NaN position";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("particle " + std::to_string(bad) + " "), std::string::npos) << e.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, DistributionMethod,
                         ::testing::Values(PartitionMethod::rcb, PartitionMethod::multijagged),
                         [](const ::testing::TestParamInfo<PartitionMethod>& info) {
                           return std::string(name_of(partition_method_names(), info.param));
                         });
