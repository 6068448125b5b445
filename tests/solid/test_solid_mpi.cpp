// The distributed solid (solid/solid_solver.hpp with a core/distribution.hpp) against the same solid held
// whole by one process, on 1 to 4 ranks: a bar pulled apart breaks across a rank boundary on both sides in the
// same step; positions, rotations and broken-bond flags agree particle by particle (by global id); fragments,
// bonds and conserved quantities are the whole solid's on every rank. Run under mpirun (label mpi).
#include "core/distribution.hpp"
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"
#include "support/spec_builders.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

namespace mpsfsi {
namespace {

using test::base_case;
using test::material;
using test::solid_body;

int n_ranks() {
  int n = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

int my_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

/// The distribution of the solid of `spec` over the ranks, with `p` (the whole scene) cut down to this rank's part.
std::unique_ptr<Distribution> distribute(const CaseSpec& spec, ParticleSet& p) {
  DistributionSettings ds;
  ds.skin = 2 * spec.dp;
  ds.halo_width = solid_interaction_radius(solid_setup(spec)) + ds.skin;
  auto dist = std::make_unique<Distribution>(MPI_COMM_WORLD, ds);
  dist->distribute_replicated(p);
  return dist;
}

// Two halves of a bar (20 x 5 particles) pulled apart at x = 0.1 m; on 2 ranks the bisection cuts the bar
// there, so the bonds that break join particles of different ranks.
TEST(SolidMpi, BondAcrossARankBoundaryBreaksOnBothSidesInTheSameStep) {
  const CaseSpec spec = test::brittle_bar_case();
  const auto pull = test::pull_bar_apart;
  // The reference: the whole bar in this process.
  Scene whole = build_scene(spec);
  pull(whole.particles);
  SolidSolver reference(solid_setup(spec), whole.particles);
  // The distributed bar.
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  pull(p);
  const auto dist = distribute(spec, p);
  SolidSolver solid(solid_setup(spec), p, *dist);
  ASSERT_EQ(solid.n_bonds(), reference.n_bonds());

  const Real dt = solid.stable_dt();
  ASSERT_EQ(dt, reference.stable_dt());
  int first_break = -1;
  for (int k = 0; k < 3000; ++k) {
    const SolidStepReport a = solid.advance(k * dt, dt), b = reference.advance(k * dt, dt);
    ASSERT_EQ(a.n_broken, b.n_broken) << "step " << k;  // the same bonds break in the same step
    if (first_break < 0 && a.n_broken > 0) first_break = k;
  }
  ASSERT_GE(first_break, 0) << "the bar did not break";
  EXPECT_EQ(solid.n_bonds(), reference.n_bonds());

  // Particle by particle (global id): position, rotation and the broken-bond flags of both ends.
  const auto& broken = p.scalar_field("_solid_broken");
  const auto& broken_ref = whole.particles.scalar_field("_solid_broken");
  const auto& theta = p.scalar_field("rotation");
  const auto& theta_ref = whole.particles.scalar_field("rotation");
  Real dx = 0, dtheta = 0;
  int flag_mismatch = 0;
  unsigned long long n_flagged = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    const auto r = static_cast<std::size_t>(whole.particles.local_index(p.global_id[i]));
    dx = std::max(dx, (p.position[i] - whole.particles.position[r]).norm());
    dtheta = std::max(dtheta, std::abs(theta[i] - theta_ref[r]));
    flag_mismatch += broken[i] != broken_ref[r];
    n_flagged += broken[i] != 0;
  }
  MPI_Allreduce(MPI_IN_PLACE, &dx, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &dtheta, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &flag_mismatch, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &n_flagged, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_LT(dx, 1e-12);
  EXPECT_LT(dtheta, 1e-12);
  EXPECT_EQ(flag_mismatch, 0);
  EXPECT_GE(n_flagged, 2u);  // at least both ends of one bond

  // Fragments: the whole bar's count on every rank, the same as one process finds.
  solid.prepare_output(3000 * dt);
  reference.prepare_output(3000 * dt);
  EXPECT_EQ(solid.n_fragments(), reference.n_fragments());
  EXPECT_GE(solid.n_fragments(), 2u);
  EXPECT_EQ(solid.min_distance_between_fragments(), reference.min_distance_between_fragments());

  if (n_ranks() == 2) {
    // The two fragments lie on different ranks: every broken bond crossed the boundary, and both of its ends
    // (on two ranks) carry the broken flag.
    const auto& frag = p.scalar_field("fragment");
    int lo[2] = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max()}, hi[2] = {-1, -1};
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      const int f = static_cast<int>(frag[i]);
      if (f > 1) continue;
      lo[f] = std::min(lo[f], my_rank());
      hi[f] = std::max(hi[f], my_rank());
    }
    MPI_Allreduce(MPI_IN_PLACE, lo, 2, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, hi, 2, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    EXPECT_EQ(lo[0], hi[0]) << "fragment 0 spans ranks";
    EXPECT_EQ(lo[1], hi[1]) << "fragment 1 spans ranks";
    EXPECT_NE(lo[0], lo[1]) << "both fragments on one rank: no bond crossed the boundary";
    for (int r = 0; r < 2; ++r) {
      unsigned long long mine = 0;
      if (my_rank() == r)
        for (std::size_t i = 0; i < p.n_owned(); ++i) mine += broken[i] != 0;
      MPI_Allreduce(MPI_IN_PLACE, &mine, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
      EXPECT_GT(mine, 0u) << "rank " << r << " holds no end of a broken bond";
    }
  }

  // Conserved quantities of the whole solid (internal forces only: zero momentum).
  const SolidDiagnostics d = solid.diagnostics(), d_ref = reference.diagnostics();
  EXPECT_LT(d.momentum.norm(), 1e-10);
  EXPECT_NEAR(d.total(), d_ref.total(), 1e-12 * d_ref.total());
}

// A spinning, moving plate crosses the rank boundaries: its particles migrate, and the state stays that of
// one process (momentum, angular momentum and energy of the whole body).
TEST(SolidMpi, MigratingBodyKeepsTheStateOfOneProcess) {
  CaseSpec spec = base_case(0.01);
  spec.solid_materials.push_back(material("rubber", 1000, 1e5, 0.3));
  BodySpec b = solid_body("plate", "rubber", Vec(0, 0), Vec(0.2, 0.1));
  b.velocity = Vec(2.0, -1.0);
  b.angular_velocity = 20.0;
  spec.bodies.push_back(b);
  Scene whole = build_scene(spec);
  SolidSolver reference(solid_setup(spec), whole.particles);
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  const auto dist = distribute(spec, p);
  SolidSolver solid(solid_setup(spec), p, *dist);
  const Real dt = solid.stable_dt();
  for (int k = 0; k < 1500; ++k) {
    solid.advance(k * dt, dt);
    reference.advance(k * dt, dt);
  }
  Real dx = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    const auto r = static_cast<std::size_t>(whole.particles.local_index(p.global_id[i]));
    dx = std::max(dx, (p.position[i] - whole.particles.position[r]).norm());
  }
  unsigned long long n_owned = p.n_owned(), migrated = dist->stats().n_migrated_out;
  MPI_Allreduce(MPI_IN_PLACE, &dx, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &n_owned, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &migrated, 1, MPI_UNSIGNED_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(n_owned, whole.particles.size());
  EXPECT_LT(dx, 1e-12);
  if (n_ranks() > 1) {
    EXPECT_GT(dist->stats().n_ghost_builds, 1) << "no renewal of owners and ghosts happened";
  }
  const SolidDiagnostics d = solid.diagnostics(), d_ref = reference.diagnostics();
  EXPECT_LT((d.momentum - d_ref.momentum).norm(), 1e-12 * d_ref.momentum.norm());
  EXPECT_NEAR(d.angular_momentum, d_ref.angular_momentum, 1e-12 * std::abs(d_ref.angular_momentum));
  EXPECT_NEAR(d.total(), d_ref.total(), 1e-12 * d_ref.total());
}

}  // namespace
}  // namespace mpsfsi
