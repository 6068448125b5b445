// Unit tests of the explicit elastic solid (seed 004 eq. 25-48, seed 000 eq. 5-26): conservation of
// momentum, angular momentum and energy for a free body; the P-wave speed of the model; clamping;
// brittle fracture and fragments (eq. 47-48); contact between bodies and fragments (seed 004 §4.4); the
// Kelvin-Voigt bond damping of coupled runs keeps the first bending mode and damps particle-scale noise.
#include "core/ramp.hpp"
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"
#include "support/solid_runs.hpp"
#include "support/spec_builders.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>
#include <filesystem>
#include <fstream>
#include <string>

namespace mpsfsi {
namespace {

using test::base_case;
using test::material;
using test::solid_body;

// A free body with initial velocity and angular velocity: linear momentum and total angular
// momentum (orbital + spin I omega) are conserved to round-off, the energy drifts by < 1 %.
TEST(Solid, FreeBodyConservesMomentumAngularMomentumAndEnergy) {
  CaseSpec spec = base_case(0.01);
  spec.solid_materials.push_back(material("rubber", 1000, 1e5, 0.3));
  BodySpec b = solid_body("plate", "rubber", Vec(0, 0), Vec(0.2, 0.1));
  b.velocity = Vec(1.0, -0.5);
  b.angular_velocity = 20.0;  // centrifugal stretch: strain energy of a few % of the total
  spec.bodies.push_back(b);
  Scene scene = build_scene(spec);
  SolidSolver solid(solid_setup(spec), scene.particles);
  const Real dt = solid.stable_dt();
  const SolidDiagnostics d0 = solid.diagnostics();
  EXPECT_GT(d0.rotational, 0);
  const test::EnergyRecord run = test::advance_recording_energy(solid, 10000, 100);
  const Real e_min = run.e_min, e_max = run.e_max, t = run.t;
  const SolidDiagnostics d1 = solid.diagnostics();
  std::printf("free body, %d particles, 1e4 steps of %.3e s: |dP|/|P| = %.2e, |dL|/|L| = %.2e, "
              "energy drift %.3e, energy range %.3e (strain energy at the end %.3f of the total)\n",
              static_cast<int>(scene.particles.size()), dt, (d1.momentum - d0.momentum).norm() / d0.momentum.norm(),
              std::abs(d1.angular_momentum - d0.angular_momentum) / std::abs(d0.angular_momentum),
              (d1.total() - d0.total()) / d0.total(), (e_max - e_min) / d0.total(), d1.strain / d1.total());
  EXPECT_LT((d1.momentum - d0.momentum).norm() / d0.momentum.norm(), 1e-10);
  EXPECT_LT(std::abs(d1.angular_momentum - d0.angular_momentum) / std::abs(d0.angular_momentum), 1e-10);
  EXPECT_LT(std::abs(d1.total() - d0.total()) / d0.total(), 0.01);
  EXPECT_LT((e_max - e_min) / d0.total(), 0.01);
  EXPECT_GT(d1.strain, 1e-3 * d1.total());  // the spin stretched the body: energy moves between the forms
  // The body turned through about omega t (rigid rotation of the mean particle angle).
  const auto& theta = scene.particles.scalar_field("rotation");
  Real mean_theta = 0;
  for (const Real th : theta) mean_theta += th;
  mean_theta /= static_cast<Real>(theta.size());
  EXPECT_NEAR(mean_theta, 20.0 * t, 0.05 * 20.0 * t);
}

// A Gaussian pressure pulse on the left edge of a wide plate: along the centre line, away from the
// free surfaces, the pulse is a plane P wave. The MPS model (eq. 30-38) reduces in the interior to
// the Navier equation with the plane-strain Lame constants of eq. 4, so its P-wave speed is
// c_p = sqrt((lambda + 2 mu) / rho). The peak arrival at two stations gives the measured speed.
TEST(Solid, CompressionalPulseTravelsAtPWaveSpeed) {
  const Real dp = 0.001;
  CaseSpec spec = base_case(dp);
  SolidMaterial m = material("rock", 2000, 13.31e9, 0.3);
  spec.solid_materials.push_back(m);
  const int nx = 300, ny = 80;
  spec.bodies.push_back(solid_body("plate", "rock", Vec(0, 0), Vec(nx * dp, ny * dp)));
  const Real mu = m.E / (2 * (1 + m.nu));
  const Real lambda = m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu));
  const Real c_p = std::sqrt((lambda + 2 * mu) / m.rho);
  SolidLoadSpec pulse;
  pulse.name = "pulse";
  pulse.body = "plate";
  pulse.region = {Vec(-dp, -dp), Vec(0.6 * dp, (ny + 1) * dp)};
  pulse.direction = Vec(1, 0);
  pulse.peak = 1e7;
  pulse.width = 8 * dp / c_p;  // about 25 particles per wavelength
  pulse.time = 3 * pulse.width;
  spec.solid_loads.push_back(pulse);
  Scene scene = build_scene(spec);
  auto& p = scene.particles;
  SolidSolver solid(solid_setup(spec), p);
  // Station particles on the centre line.
  const Real x1 = 100.5 * dp, x2 = 200.5 * dp, yc = (ny / 2 + 0.5) * dp;
  std::size_t i1 = 0, i2 = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if ((p.position[i] - Vec(x1, yc)).norm() < 0.1 * dp) i1 = i;
    if ((p.position[i] - Vec(x2, yc)).norm() < 0.1 * dp) i2 = i;
  }
  const Real dt = solid.stable_dt();
  // Stop before the reflection from the free right end (x = 300 dp) comes back to station 2.
  const int n_steps = static_cast<int>((pulse.time + 1.3 * x2 / c_p) / dt);
  // Peak of the x velocity at each station, refined by a parabola through the three samples around it.
  struct Peak {
    Real v[3] = {0, 0, 0};
    Real best = -1, t_best = 0, t_peak = 0;
  } pk[2];
  Real t = 0;
  for (int step = 0; step < n_steps; ++step) {
    solid.advance(t, dt);
    t += dt;
    for (int s = 0; s < 2; ++s) {
      auto& q = pk[s];
      q.v[0] = q.v[1];
      q.v[1] = q.v[2];
      q.v[2] = p.velocity[s == 0 ? i1 : i2][0];
      if (q.v[1] > q.best && q.v[1] >= q.v[0] && q.v[1] >= q.v[2] && step >= 2) {
        q.best = q.v[1];
        const Real den = q.v[0] - 2 * q.v[1] + q.v[2];
        const Real shift = den != 0 ? 0.5 * (q.v[0] - q.v[2]) / den : 0.0;
        q.t_peak = t - dt + shift * dt;
      }
    }
  }
  ASSERT_GT(pk[0].best, 0);
  ASSERT_GT(pk[1].best, 0);
  const Real c_measured = (x2 - x1) / (pk[1].t_peak - pk[0].t_peak);
  RecordProperty("c_p_expected", std::to_string(c_p));
  RecordProperty("c_p_measured", std::to_string(c_measured));
  std::printf("P-wave speed: measured %.1f m/s, expected sqrt((lambda+2mu)/rho) = %.1f m/s (%.2f %%)\n", c_measured, c_p,
              100 * (c_measured / c_p - 1));
  EXPECT_NEAR(c_measured / c_p, 1.0, 0.03);
}

// Clamped particles keep zero displacement under gravity; the rest of the beam moves.
TEST(Solid, ClampedParticlesStayPut) {
  CaseSpec spec = base_case(0.02);
  spec.gravity = Vec(0, -9.81);
  spec.solid_materials.push_back(material("steel", 1000, 1e7, 0.3));
  BodySpec b = solid_body("beam", "steel", Vec(-0.06, 0), Vec(1.0, 0.1));
  b.clamp = Rect{Vec(-0.07, -0.01), Vec(0.0, 0.11)};
  spec.bodies.push_back(b);
  Scene scene = build_scene(spec);
  const auto x0 = scene.particles.position;
  SolidSolver solid(solid_setup(spec), scene.particles);
  const Real dt = solid.stable_dt();
  for (int k = 0; k < 2000; ++k) solid.advance(k * dt, dt);
  Real tip = 0;
  for (std::size_t i = 0; i < x0.size(); ++i) {
    if (scene.particles.clamped[i]) {
      EXPECT_EQ(scene.particles.position[i], x0[i]);
    }
    tip = std::min(tip, scene.particles.position[i][1] - x0[i][1]);
  }
  EXPECT_LT(tip, -1e-3);
}

// Two halves of a bar pulled apart: the bonds across break (eq. 47), never heal, the new faces become
// surface particles (eq. 48), the fragments are counted and written to fragments.csv.
TEST(Solid, BarPulledApartBreaksIntoTwoFragments) {
  const CaseSpec spec = test::brittle_bar_case();
  Scene scene = build_scene(spec);
  auto& p = scene.particles;
  test::pull_bar_apart(p);
  SolidSolver solid(solid_setup(spec), p);
  const auto dir = std::filesystem::temp_directory_path() / "mpsfsi_test_solid_fracture";
  std::filesystem::create_directories(dir);
  solid.set_output_directory(dir.string());
  solid.prepare_output(0);
  EXPECT_EQ(solid.n_fragments(), 1u);
  const std::size_t n_bonds0 = solid.n_bonds();
  const Real dt = solid.stable_dt();
  SolidStepReport r;
  for (int k = 0; k < 3000; ++k) r = solid.advance(k * dt, dt);
  solid.prepare_output(3000 * dt);
  EXPECT_GT(r.n_broken, 0u);
  EXPECT_EQ(solid.n_bonds(), n_bonds0 - r.n_broken);
  EXPECT_GE(solid.n_fragments(), 2u);
  EXPECT_GT(solid.min_distance_between_fragments(), 0.5 * spec.dp);
  // Momentum is still zero (internal forces only).
  EXPECT_LT(solid.diagnostics().momentum.norm(), 1e-10);
  std::ifstream csv(dir / "fragments.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "time,n_fragments,fragment,body,particles,mass,centroid_x,centroid_y");
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, 1 + static_cast<int>(solid.n_fragments()));
}

// Two bodies thrown at each other: the unbonded surface particles repel (seed 004 §4.4), the bodies
// never come closer than l0/2, they bounce apart, momentum is conserved through the contact.
TEST(Solid, BodiesInContactRepelAndNeverInterpenetrate) {
  CaseSpec spec = base_case(0.05);
  spec.solid_materials.push_back(material("soft", 1000, 6e6, 0.3));
  spec.solid_materials.push_back(material("hard", 1000, 10e6, 0.3));
  BodySpec a = solid_body("cube", "soft", Vec(0, 0.3), Vec(0.5, 0.8));
  a.velocity = Vec(0, -15);
  spec.bodies.push_back(a);
  spec.bodies.push_back(solid_body("block", "hard", Vec(-0.5, 0), Vec(1.0, 0.25)));
  Scene scene = build_scene(spec);
  SolidSolver solid(solid_setup(spec), scene.particles);
  solid.prepare_output(0);
  EXPECT_EQ(solid.n_fragments(), 2u);
  const SolidDiagnostics d0 = solid.diagnostics();
  const test::ContactRecord c = test::advance_recording_contacts(solid, 2000);
  EXPECT_GT(c.max_contacts, 0u);
  EXPECT_GT(c.closest, 0.5 * spec.dp);
  const SolidDiagnostics d1 = solid.diagnostics();
  EXPECT_LT((d1.momentum - d0.momentum).norm() / d0.momentum.norm(), 1e-10);
  // The cube has bounced: its mean vertical velocity is now upward relative to the block's.
  EXPECT_GT(test::mean_velocity(scene.particles, 0, 1), test::mean_velocity(scene.particles, 1, 1));
}

// Another module may reorder the particle set between steps (ParticleSet::reorder): the solver follows
// the global ids and the motion is unchanged.
TEST(Solid, FollowsAReorderingOfTheParticleSet) {
  CaseSpec spec = base_case(0.01);
  spec.gravity = Vec(0, -9.81);
  spec.solid_materials.push_back(material("rubber", 1000, 1e6, 0.3));
  BodySpec b = solid_body("plate", "rubber", Vec(0, 0), Vec(0.2, 0.05));
  b.angular_velocity = 2.0;
  spec.bodies.push_back(b);
  Scene a = build_scene(spec), c = build_scene(spec);
  SolidSolver sa(solid_setup(spec), a.particles), sc(solid_setup(spec), c.particles);
  const Real dt = sa.stable_dt();
  for (int k = 0; k < 100; ++k) sa.advance(k * dt, dt), sc.advance(k * dt, dt);
  std::vector<LocalIndex> order(c.particles.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<LocalIndex>(order.size() - 1 - k);
  c.particles.reorder(order);
  for (int k = 100; k < 200; ++k) sa.advance(k * dt, dt), sc.advance(k * dt, dt);
  for (std::size_t i = 0; i < a.particles.size(); ++i) {
    const std::size_t j = a.particles.size() - 1 - i;
    ASSERT_EQ(a.particles.global_id[i], c.particles.global_id[j]);
    EXPECT_EQ(a.particles.position[i], c.particles.position[j]);
    EXPECT_EQ(a.particles.scalar_field("rotation")[i], c.particles.scalar_field("rotation")[j]);
  }
}

// Kelvin-Voigt bond damping (SolidSolver::set_damping, used by coupled runs): the plate of the dam break on
// an elastic plate (12 x 80 mm, E 1 MPa, rho 2500, clamped 3 dp deep) under a suddenly applied sideways
// body force swings about its static deflection in its first bending mode (f1 ~ 6 Hz). With beta = 0.5 the
// first mode keeps its period and amplitude (damping ratio eta omega_1 / 2 ~ 1.4e-3), while particle-scale
// noise (random velocities of 0.1 m/s) loses most of its energy within 200 solid steps.
namespace {
struct PlateRun {
  std::vector<Real> t, tip;
  Real noise_ke_end = 0, noise_ke_start = 0;
};
PlateRun swing_plate(const Real beta, const bool noise) {
  CaseSpec spec = base_case(0.003);
  spec.gravity = noise ? Vec(0, 0) : Vec(2.0, 0);
  spec.solid_materials.push_back(material("rubber", 2500, 1e6, 0.0));
  BodySpec b = solid_body("plate", "rubber", Vec(0.0, -0.009), Vec(0.012, 0.080));
  b.clamp = Rect{Vec(-0.002, -0.01), Vec(0.014, 0.0)};
  spec.bodies.push_back(b);
  Scene scene = build_scene(spec);
  ParticleSet& p = scene.particles;
  SolidSolver solid(solid_setup(spec), p);
  solid.set_damping(beta);
  std::size_t tip = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.position[i][1] > p.position[tip][1] || (p.position[i][1] == p.position[tip][1] && p.position[i][0] < p.position[tip][0])) tip = i;
  const Vec tip0 = p.position[tip];
  PlateRun run;
  if (noise) {
    unsigned state = 12345;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (p.clamped[i]) continue;
      for (int d = 0; d < 2; ++d) {
        state = state * 1103515245u + 12345u;
        p.velocity[i][d] = 0.1 * (static_cast<Real>((state >> 8) & 0xffff) / 65535.0 - 0.5) * 2;
      }
    }
    SolidSolver fresh(solid_setup(spec), p);  // picks up the velocities
    fresh.set_damping(beta);
    run.noise_ke_start = fresh.diagnostics().kinetic;
    const Real dt = fresh.stable_dt();
    for (int k = 0; k < 200; ++k) fresh.advance(k * dt, dt);
    run.noise_ke_end = fresh.diagnostics().kinetic + fresh.diagnostics().rotational;
    return run;
  }
  const Real dt = solid.stable_dt();
  const int steps = static_cast<int>(0.5 / dt);
  for (int k = 0; k < steps; ++k) {
    solid.advance(k * dt, dt);
    run.t.push_back((k + 1) * dt);
    run.tip.push_back(p.position[tip][0] - tip0[0]);
  }
  return run;
}
/// Upward crossings of the mean and the largest excursion after the first crossing.
void swing_measures(const PlateRun& r, Real& period, Real& amplitude) {
  Real mean = 0;
  for (const Real x : r.tip) mean += x;
  mean /= static_cast<Real>(r.tip.size());
  std::vector<Real> up;
  for (std::size_t k = 1; k < r.tip.size(); ++k)
    if (r.tip[k - 1] < mean && r.tip[k] >= mean) up.push_back(r.t[k]);
  ASSERT_GE(up.size(), 2u);
  period = (up.back() - up.front()) / static_cast<Real>(up.size() - 1);
  amplitude = 0;
  for (std::size_t k = 0; k < r.t.size(); ++k)
    if (r.t[k] > up[up.size() - 2]) amplitude = std::max(amplitude, r.tip[k] - mean);
}
}  // namespace

TEST(Solid, BondDampingKeepsTheFirstBendingModeAndDampsParticleScaleNoise) {
  Real period0 = 0, amp0 = 0, period1 = 0, amp1 = 0;
  swing_measures(swing_plate(0.0, false), period0, amp0);
  swing_measures(swing_plate(0.5, false), period1, amp1);
  EXPECT_GT(period0, 0.1);
  EXPECT_LT(period0, 0.25);
  EXPECT_NEAR(period1 / period0, 1.0, 0.01);
  EXPECT_NEAR(amp1 / amp0, 1.0, 0.03);
  const PlateRun undamped = swing_plate(0.0, true), damped = swing_plate(0.5, true);
  EXPECT_GT(undamped.noise_ke_end, 0.3 * undamped.noise_ke_start);  // elastic: energy moves, stays
  EXPECT_LT(damped.noise_ke_end, 0.1 * damped.noise_ke_start);
  std::printf("first mode: T %.4f / %.4f s, amplitude %.3f / %.3f mm; noise KE left after 200 steps: %.2f / %.2f\n",
              period0, period1, 1e3 * amp0, 1e3 * amp1, undamped.noise_ke_end / undamped.noise_ke_start,
              damped.noise_ke_end / damped.noise_ke_start);
}

// solid.wide_plate: plane stress with E / (1 - nu^2). Every elastic force scales with E, so from the same
// deformed state one step gives velocities exactly 1 / (1 - nu^2) times those of plain plane stress, and the
// stable dt (dp / c_p) is sqrt(1 - nu^2) times; plane strain gives neither (different lambda / mu).
TEST(Solid, WidePlateScalesTheModulusByOneOverOneMinusNuSquared) {
  const Real nu = 0.49;
  auto velocities_after_a_step = [&](const bool wide, Real& dt_stable) {
    CaseSpec spec = base_case(0.002);
    spec.solid_materials.push_back(material("rubber", 1100, 6e6, nu));
    spec.bodies.push_back(solid_body("plate", "rubber", Vec(0, 0), Vec(0.06, 0.004)));
    spec.solid.plane_stress = true;
    spec.solid.wide_plate = wide;
    Scene scene = build_scene(spec);
    ParticleSet& p = scene.particles;
    SolidSolver solid(solid_setup(spec), p);
    dt_stable = solid.stable_dt();
    for (std::size_t i = 0; i < p.size(); ++i)  // a bend and a stretch: u = (0.01 x, 0.5 x^2)
      p.position[i] += Vec(0.01 * p.position[i][0], 0.5 * p.position[i][0] * p.position[i][0]);
    solid.advance(0.0, 1e-6);
    return p.velocity;
  };
  Real dt_plain = 0, dt_wide = 0;
  const std::vector<Vec> v_plain = velocities_after_a_step(false, dt_plain);
  const std::vector<Vec> v_wide = velocities_after_a_step(true, dt_wide);
  ASSERT_EQ(v_plain.size(), v_wide.size());
  Real v_max = 0, err = 0;
  for (std::size_t i = 0; i < v_plain.size(); ++i) {
    v_max = std::max(v_max, v_plain[i].norm());
    err = std::max(err, (v_wide[i] - v_plain[i] / (1 - nu * nu)).norm());
  }
  EXPECT_GT(v_max, 1e-6);
  EXPECT_LT(err, 1e-12 * v_max / (1 - nu * nu) + 1e-300);
  EXPECT_NEAR(dt_wide / dt_plain, std::sqrt(1 - nu * nu), 1e-12);
}

// gravity_ramp (core/ramp.hpp): a free body falls with the ramped gravity, each step's force taken at the
// step's start: v_N = g dt sum_k ramp(k dt), with no internal force (a uniform acceleration strains nothing).
TEST(Solid, GravityRampScalesTheFallExactly) {
  CaseSpec spec = base_case(0.01);
  spec.gravity = Vec(0, -9.81);
  spec.gravity_ramp = 0.01;
  spec.solid_materials.push_back(material("rubber", 1000, 1e6, 0.3));
  spec.bodies.push_back(solid_body("block", "rubber", Vec(0, 0), Vec(0.05, 0.05)));
  Scene scene = build_scene(spec);
  SolidSolver solid(solid_setup(spec), scene.particles);
  const Real dt = solid.stable_dt();
  Real sum = 0;
  for (int k = 0; k * dt < 1.5 * spec.gravity_ramp; ++k) {
    solid.advance(k * dt, dt);
    sum += ramp_factor(k * dt, spec.gravity_ramp);
    if (k == 0) {
      EXPECT_EQ(scene.particles.velocity[0][1], 0.0);  // the ramp starts at 0
    }
  }
  for (const Vec& v : scene.particles.velocity) EXPECT_NEAR(v[1], -9.81 * dt * sum, 1e-12);
  EXPECT_GT(sum * dt, 0.4 * spec.gravity_ramp);
  EXPECT_LT(sum * dt, 1.1 * spec.gravity_ramp);
}

}  // namespace
}  // namespace mpsfsi
