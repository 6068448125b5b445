// Small builders of in-memory case specs for the unit tests (no YAML): a bare case, a solid material from
// E and nu or from the wave speeds, and a rectangular solid body. Header-only; tests include it as
// "support/spec_builders.hpp".
#pragma once

#include "io/case.hpp"

#include <string>

namespace mpsfsi::test {

/// A case with only its name, dp and a domain of +-half_width around the origin.
inline CaseSpec base_case(const Real dp, const Real half_width = 100) {
  CaseSpec spec;
  spec.file = "test";
  spec.name = "test";
  spec.dp = dp;
  spec.domain = {Vec(-half_width, -half_width), Vec(half_width, half_width)};
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

}  // namespace mpsfsi::test
