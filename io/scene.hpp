// Builds the particles of a case: fluid and solid bodies on the lattice, walls with their dummy
// layers, clamped regions and initial velocities; checks that no two bodies' particles overlap.
#pragma once

#include "core/particles.hpp"
#include "io/case.hpp"

#include <string>
#include <vector>

namespace mpsfsi {

struct BodyCount {
  std::string name;
  std::string kind;          ///< fluid | solid | wall
  std::size_t n_particles = 0;
  std::size_t n_wall = 0;    ///< walls: wall-layer particles
  std::size_t n_dummy = 0;   ///< walls: dummy-layer particles
  std::size_t n_clamped = 0; ///< solids: clamped particles
};

struct Scene {
  ParticleSet particles;
  std::vector<BodyCount> counts;  ///< one per body, in particle body-index order
};

/// Build the scene of a case. Throws CaseError when two bodies' particles come closer than dp/2.
Scene build_scene(const CaseSpec& spec);

/// Rough peak memory of a run [bytes]: particles, neighbour lists, pressure matrix and preconditioner.
std::size_t estimate_memory_bytes(const CaseSpec& spec, const Scene& scene);

}  // namespace mpsfsi
