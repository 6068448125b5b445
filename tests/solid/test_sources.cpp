// Unit tests of the solid's seismic sources (solid/sources.hpp; issue 6, seed 000 §3): the source time
// functions match scripts/lamb/lamb2d.py (values, peaks, spectrum peak at f0, tables); an explosive
// line source gives no net force or torque and the moment tensor M(t) I, inside the body and just
// below the free surface; a point force gives the force F(t) with no moment about the source point;
// a source with too few particles in range is a SetupError (std::invalid_argument) naming it.
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"
#include "support/spec_builders.hpp"
#include "solid/sources.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>

namespace mpsfsi {
namespace {

WaveletSpec wavelet(const WaveletType type, const Real f0) {
  WaveletSpec w;
  w.type = type;
  w.frequency = f0;
  w.delay = 1.5 / f0;
  return w;
}

TEST(Sources, WaveletsMatchTheAnalyticReference) {
  // Values from scripts/lamb/lamb2d.py SourceTimeFunction(kind, 300).value(t).
  const WaveletSpec gd = wavelet(WaveletType::gaussian_derivative, 300);
  const WaveletSpec rk = wavelet(WaveletType::ricker, 300);
  const WaveletSpec ga = wavelet(WaveletType::gaussian, 300);
  EXPECT_NEAR(wavelet_value(gd, 0.004), 0.5259103436471033, 1e-14);
  EXPECT_NEAR(wavelet_value(gd, 0.0061), -0.39836548276566974, 1e-14);
  EXPECT_NEAR(wavelet_value(rk, 0.004), -0.31943995607776215, 1e-14);
  EXPECT_NEAR(wavelet_value(rk, 0.0061), -0.39243435508833435, 1e-14);
  EXPECT_NEAR(wavelet_value(ga, 0.004), 0.16922454248245006, 1e-14);
  EXPECT_NEAR(wavelet_value(ga, 0.0061), 0.11653077956962814, 1e-14);

  // Gaussian derivative: unit peak one sigma before the delay, positive lobe first, zero at the delay.
  const Real sigma = 1 / (2 * pi * 300);
  EXPECT_NEAR(wavelet_value(gd, gd.delay - sigma), 1, 1e-14);
  EXPECT_NEAR(wavelet_value(gd, gd.delay + sigma), -1, 1e-14);
  EXPECT_NEAR(wavelet_value(gd, gd.delay), 0, 1e-14);
  EXPECT_LT(std::abs(wavelet_value(gd, 0)), 1e-15);  // starts at rest (delay 1.5 / f0 = 9.4 sigma)
  EXPECT_NEAR(wavelet_value(rk, rk.delay), 1, 1e-14);
  EXPECT_NEAR(wavelet_value(ga, ga.delay + sigma), std::exp(-0.5), 1e-14);

  // The amplitude spectrum of the Gaussian derivative peaks at f0.
  const auto spectrum = [&](const Real f) {
    std::complex<Real> s = 0;
    const Real dt = 1e-6;
    for (int k = 0; k < 20000; ++k) s += wavelet_value(gd, k * dt) * std::exp(std::complex<Real>(0, -2 * pi * f * k * dt));
    return std::abs(s);
  };
  EXPECT_GT(spectrum(300), spectrum(285));
  EXPECT_GT(spectrum(300), spectrum(315));
}

TEST(Sources, TableWaveletInterpolatesLinearlyAndIsZeroOutside) {
  WaveletSpec w;
  w.type = WaveletType::table;
  w.time = {0.001, 0.002, 0.004};
  w.value = {1, 3, -1};
  EXPECT_DOUBLE_EQ(wavelet_value(w, 0.0), 0);
  EXPECT_DOUBLE_EQ(wavelet_value(w, 0.001), 1);
  EXPECT_DOUBLE_EQ(wavelet_value(w, 0.0015), 2);
  EXPECT_DOUBLE_EQ(wavelet_value(w, 0.003), 1);
  EXPECT_DOUBLE_EQ(wavelet_value(w, 0.004), -1);
  EXPECT_DOUBLE_EQ(wavelet_value(w, 0.0041), 0);
}

/// A 3 x 1.5 m block (dp 0.1 m, top at y = 0) of a rock, with one source.
struct SourceCase {
  CaseSpec spec;
  explicit SourceCase(const SourceSpec& source) : spec(test::base_case(0.1, 10)) {
    spec.solid_materials.push_back(test::wave_material("rock", 2200, 2611, 1846));
    spec.bodies.push_back(test::solid_body("ground", "rock", Vec(-1.5, -1.5), Vec(1.5, 0)));
    spec.sources.push_back(source);
  }
};

SourceSpec source(const SourceType type, const Vec& position) {
  SourceSpec s;
  s.name = "s";
  s.body = "ground";
  s.type = type;
  s.position = position;
  s.direction = Vec(0.6, 0.8);
  s.amplitude = 1e5;
  s.radius = 0.2;
  s.wavelet = wavelet(WaveletType::gaussian_derivative, 300);
  return s;
}

/// Impulse given in one step from rest at time t: the bodies are unstrained, so the only forces are the
/// source's and v_k = dt F_k / m_k. Returns (net force, moment tensor about the source, torque).
struct Impulse {
  Vec force = Vec::Zero();
  Mat moment = Mat::Zero();
  Real torque = 0;
};

Impulse one_step(const SourceSpec& s, const Real t, const Real dt) {
  SourceCase c(s);
  Scene scene = build_scene(c.spec);
  const std::vector<Vec> x0 = scene.particles.position;
  SolidSolver solid(solid_setup(c.spec), scene.particles);
  solid.advance(t, dt);
  const Real mass = 2200 * 0.1 * 0.1;
  Impulse r;
  for (std::size_t i = 0; i < x0.size(); ++i) {
    const Vec f = mass * scene.particles.velocity[i] / dt;
    const Vec d = x0[i] - s.position;
    r.force += f;
    r.moment += d * f.transpose();
    r.torque += cross(d, f);
  }
  return r;
}

TEST(Sources, ExplosionHasNoNetForceAndTheMomentM) {
  const Real t = 0.004, dt = 1e-5;
  for (const Vec& p : {Vec(0, -0.75), Vec(0.03, -0.12), Vec(0.05, -1.0)}) {  // interior, below the surface, on a row
    const SourceSpec s = source(SourceType::explosion, p);
    const Real m = s.amplitude * wavelet_value(s.wavelet, t);
    const Impulse r = one_step(s, t, dt);
    EXPECT_LT(r.force.norm(), 1e-9 * std::abs(m) / 0.1) << p.transpose();
    EXPECT_LT((r.moment - m * Mat::Identity()).norm(), 1e-9 * std::abs(m)) << p.transpose();
    EXPECT_LT(std::abs(r.torque), 1e-9 * std::abs(m)) << p.transpose();
  }
}

TEST(Sources, ForceHasTheNetForceFAndNoMoment) {
  const Real t = 0.0061, dt = 1e-5;
  for (const Vec& p : {Vec(0, -0.75), Vec(0.03, 0.0)}) {  // interior and on the free surface
    const SourceSpec s = source(SourceType::force, p);
    const Real f = s.amplitude * wavelet_value(s.wavelet, t);
    const Impulse r = one_step(s, t, dt);
    EXPECT_LT((r.force - f * s.direction).norm(), 1e-9 * std::abs(f)) << p.transpose();
    EXPECT_LT(r.moment.norm(), 1e-9 * std::abs(f) * 0.1) << p.transpose();
  }
}

TEST(Sources, ExplosionKeepsTheMomentumZeroOverManySteps) {
  const SourceSpec s = source(SourceType::explosion, Vec(0.0, -0.6));
  SourceCase c(s);
  Scene scene = build_scene(c.spec);
  SolidSolver solid(solid_setup(c.spec), scene.particles);
  const Real dt = 1e-5;
  for (int k = 0; k < 600; ++k) solid.advance(k * dt, dt);
  const SolidDiagnostics d = solid.diagnostics();
  EXPECT_GT(d.kinetic, 0);
  // Momentum scale: sqrt(2 m_total E_kin).
  const Real p_scale = std::sqrt(2 * 2200 * 3.0 * 1.5 * d.kinetic);
  EXPECT_LT(d.momentum.norm(), 1e-9 * p_scale);
}

TEST(Sources, TooFewParticlesInRangeNamesTheSource) {
  SourceSpec s = source(SourceType::explosion, Vec(0, -0.75));
  s.radius = 0.03;
  SourceCase c(s);
  Scene scene = build_scene(c.spec);
  try {
    SolidSolver solid(solid_setup(c.spec), scene.particles);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {  // SetupError
    EXPECT_NE(std::string(e.what()).find("source 's' at (0, -0.75) on body 'ground'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("use a larger radius"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mpsfsi
