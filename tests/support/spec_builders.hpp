// Small builders of in-memory case specs for the unit tests (no YAML): a bare case, a solid material from
// E and nu or from the wave speeds, a rectangular solid body, and a brittle bar to pull apart. Header-only;
// tests include it as
// "support/spec_builders.hpp".
#pragma once

#include "core/particles.hpp"
#include "io/case.hpp"

#include <string>

namespace mpsfsi::test {

/// A case with only its name, dp and a domain of +-half_width around the origin.
inline CaseSpec base_case(const Real dp, const Real half_width = 100) {
  CaseSpec spec;
  spec.file = "test";
  spec.name = "test";
  spec.dp = dp;
  spec.domain = {Vec::Constant(-half_width), Vec::Constant(half_width)};
  return spec;
}

/// A solid material from Young's modulus and Poisson's ratio.
inline SolidMaterial material(const std::string& name, const Real rho, const Real E, const Real nu) {
  SolidMaterial m;
  m.name = name;
  m.rho = rho;
  m.E = E;
  m.nu = nu;
  return m;
}

/// A solid material from its wave speeds (seed 000 §4).
inline SolidMaterial wave_material(const std::string& name, const Real rho, const Real vp, const Real vs) {
  SolidMaterial m;
  m.name = name;
  m.rho = rho;
  m.vp = vp;
  m.vs = vs;
  return m;
}

/// A rectangular solid body [lo, hi] of material `mat`.
inline BodySpec solid_body(const std::string& name, const std::string& mat, const Vec& lo, const Vec& hi) {
  BodySpec b;
  b.name = name;
  b.kind = BodyKind::solid;
  b.material = mat;
  b.rect = {lo, hi};
  return b;
}

/// A brittle bar of 20 x 5 (x 5) particles (dp 1 cm, 0.2 x 0.05 (x 0.05) m, fracture strain 0.05)...
inline CaseSpec brittle_bar_case() {
  CaseSpec spec = base_case(0.01);
  SolidMaterial m = material("glass", 1000, 1e6, 0.3);
  m.fracture_strain = 0.05;
  spec.solid_materials.push_back(m);
  Vec hi = Vec::Constant(0.05);
  hi[0] = 0.2;
  spec.bodies.push_back(solid_body("bar", "glass", Vec::Zero(), hi));
  return spec;
}

/// ... and its halves pulled apart at x = 0.1 m (5 m/s each way).
inline void pull_bar_apart(ParticleSet& p) {
  for (std::size_t i = 0; i < p.size(); ++i) {
    p.velocity[i] = Vec::Zero();
    p.velocity[i][0] = p.position[i][0] < 0.1 ? -5.0 : 5.0;
  }
}

}  // namespace mpsfsi::test
