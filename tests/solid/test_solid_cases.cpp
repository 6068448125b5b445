// Validation runs of the solid's shipped cases (label validation), in-process so that every step can
// be checked: collision_fracture (seed 004 §5.2: fracture, fragments fly apart, no two fragments ever
// closer than l0/2, finite to 2 s) and the Hopkinson bar models A/B/C (seed 000 §4: spalling near the
// free end between 0.17 and 0.22 ms, spalled piece longer for larger Vp: A > B > C).
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#ifndef MPSFSI_CASES_DIR
#error "MPSFSI_CASES_DIR must point to cases/"
#endif

namespace mpsfsi {
namespace {

std::string case_path(const std::string& name) { return std::string(MPSFSI_CASES_DIR) + "/" + name + ".yaml"; }

TEST(SolidCases, CollisionFractureBreaksAndFragmentsNeverOverlap) {
  const CaseSpec spec = load_case(case_path("collision_fracture"));
  Scene scene = build_scene(spec);
  auto& p = scene.particles;
  SolidSolver solid(solid_setup(spec), p);
  const Real dt = solid.stable_dt();
  Real t = 0, d_min = 1e9, t_fracture = -1;
  std::size_t max_fragments = 0;
  for (std::size_t step = 0; t < spec.time.end - 1e-12; ++step) {
    const Real h = std::min(dt, spec.time.end - t);
    solid.advance(t, h);
    t += h;
    d_min = std::min(d_min, solid.min_distance_between_fragments());
    max_fragments = std::max(max_fragments, solid.n_fragments());
    if (t_fracture < 0 && solid.n_fragments() > 2) t_fracture = t;
    for (std::size_t i = 0; i < p.size(); ++i)
      ASSERT_TRUE(p.position[i].allFinite() && p.velocity[i].allFinite()) << "step " << step;
  }
  std::printf("collision_fracture: first fracture at %.3f s, up to %zu fragments, closest fragments %.3f l0\n",
              t_fracture, max_fragments, d_min / spec.dp);
  EXPECT_GT(t_fracture, 0);
  EXPECT_GE(max_fragments, 3u);
  EXPECT_GT(d_min, 0.5 * spec.dp);
  // The block's pieces move apart: their centroids separate at the end.
  solid.prepare_output(t);
  const auto& frag = p.scalar_field("fragment");
  const auto& vel = p.velocity;
  Vec c[2] = {Vec::Zero(), Vec::Zero()}, v[2] = {Vec::Zero(), Vec::Zero()};
  int n[2] = {0, 0}, ids[2] = {-1, -1};
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.bodies[p.body[i]].name != "block") continue;
    const int f = static_cast<int>(frag[i]);
    int k = f == ids[0] ? 0 : f == ids[1] ? 1 : ids[0] < 0 ? 0 : ids[1] < 0 ? 1 : -1;
    if (k < 0) continue;
    ids[k] = f;
    c[k] += p.position[i];
    v[k] += vel[i];
    ++n[k];
  }
  ASSERT_GT(n[0], 0);
  ASSERT_GT(n[1], 0);
  const Vec dc = c[1] / n[1] - c[0] / n[0];
  const Vec dv = v[1] / n[1] - v[0] / n[0];
  EXPECT_GT(dc.dot(dv), 0) << "the block's two largest pieces are not separating";
}

struct SpallResult {
  Real t_first = -1;      ///< first time with more than one fragment [s]
  Real length = 0;        ///< length of the first spalled end piece [m]
};

SpallResult run_hopkinson(const std::string& name) {
  const CaseSpec spec = load_case(case_path(name));
  Scene scene = build_scene(spec);
  auto& p = scene.particles;
  SolidSolver solid(solid_setup(spec), p);
  const Real dt = *spec.solid.dt;
  SpallResult r;
  const int n_steps = static_cast<int>(std::lround(spec.time.end / dt));
  for (int k = 0; k < n_steps; ++k) {
    solid.advance(k * dt, dt);
    if (k % 10 != 9) continue;
    solid.prepare_output((k + 1) * dt);
    if (solid.n_fragments() < 2) continue;
    // The first spall: the particles not in the main piece (fragment 0) right of its end.
    const auto& frag = p.scalar_field("fragment");
    std::size_t n_piece = 0;
    for (std::size_t i = 0; i < p.size(); ++i) n_piece += frag[i] != 0;
    r.t_first = (k + 1) * dt;
    r.length = static_cast<Real>(n_piece) / 11 * spec.dp;
    break;
  }
  std::printf("%s: first spall at %.4f ms, spalled length %.1f mm\n", name.c_str(), 1e3 * r.t_first, 1e3 * r.length);
  return r;
}

TEST(SolidCases, HopkinsonBarSpallsNearTheFreeEndWithLengthOrderABC) {
  const SpallResult a = run_hopkinson("hopkinson_bar");
  const SpallResult b = run_hopkinson("hopkinson_bar_B");
  const SpallResult c = run_hopkinson("hopkinson_bar_C");
  for (const auto& r : {a, b, c}) {
    EXPECT_GE(r.t_first, 0.17e-3);
    EXPECT_LE(r.t_first, 0.22e-3);
    EXPECT_GT(r.length, 0);
    EXPECT_LT(r.length, 0.05);  // near the free end
  }
  EXPECT_GT(a.length, b.length);
  EXPECT_GT(b.length, c.length);
}

}  // namespace
}  // namespace mpsfsi
