// Builds the particles of a case: fluid and solid bodies on the lattice, walls with their dummy
// layers, clamped regions and initial velocities; checks that no two bodies' particles overlap, and,
// before allocating, that the machine has the memory the case needs.
#pragma once

#include "core/particles.hpp"
#include "io/case.hpp"

#include <cstddef>
#include <optional>
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
  /// Bodies: the region the particles represent, their bounding box widened by dp/2 on each side (the
  /// file's rectangle rounded to whole lattice cells).
  Rect extent;
  /// Bodies: the largest distance between a side of `extent` and the same side of the file's rectangle [m]
  /// (0 for a sphere or cylinder).
  Real extent_difference = 0;
  /// Spheres, cylinders and surfaces: the shape's volume (area in 2D), to compare with the particles' n dp^dim
  /// (bodies; without the parts cut out by `subtract`), and what the shape is ("disc", "sphere", "cylinder",
  /// "polygon", "surface").
  std::optional<Real> shape_volume;
  std::string shape;
  /// Surfaces: the surface's bounding box, and where it comes from ("hull.stl, 1204 triangles").
  std::optional<Rect> shape_bounds;
  std::string shape_source;
  /// Clamped solids: the extent of the unclamped particles (+ dp/2 at each end) along the clamp direction
  /// `free_axis` (0: x, 1: y, 2: z) [m], and the same length in the file (free_part of the rectangle).
  std::optional<Real> free_length;
  int free_axis = 1;
  Real file_free_length = 0;
};

struct Scene {
  ParticleSet particles;
  std::vector<BodyCount> counts;  ///< one per body, in particle body-index order
};

/// Particles of a case by kind.
struct ParticleCounts {
  std::size_t fluid = 0, solid = 0, wall = 0, dummy = 0;
  std::size_t total() const { return fluid + solid + wall + dummy; }
};

/// The memory the program takes with its libraries (Trilinos, VTK, MPI) before any particle: the peak of
/// `mpsfsi run cases/hydrostatic.yaml` (1,600 fluid particles) is 86 MiB.
constexpr std::size_t program_bytes = std::size_t{85} << 20;
/// Most particles of a scene, whatever the memory (the parser bounds the bodies alone to the same).
constexpr double max_scene_particles = 1e9;


/// The particles build_scene makes for a case, counted from its rectangles, spheres and cylinders without
/// building them (surfaces, and bodies with walls cut out of them, by building their points):
/// bodies on the dp lattice, walls with their wall and dummy layers. Wall points that give way to
/// clamped particles embedded in a wall are counted too (so wall and dummy may be a few too many).
ParticleCounts count_particles(const CaseSpec& spec);

/// Rough peak memory of a run [bytes], without the program itself: particles, neighbour lists, pressure
/// matrix and preconditioner, the solid's bonds. From particle counts, or from a built scene (the same for
/// the scene's counts).
std::size_t estimate_memory_bytes(const CaseSpec& spec, const ParticleCounts& n);
std::size_t estimate_memory_bytes(const CaseSpec& spec, const Scene& scene);

/// The memory this process can still take [bytes]: MemAvailable of /proc/meminfo, or less under a limit on
/// the address space (ulimit -v: the limit minus VmSize); none where neither can be read.
std::optional<std::size_t> available_memory_bytes();

/// Build the scene of a case. Throws CaseError when two bodies' particles come closer than dp/2, and
/// (check_scene_size, before allocating) when the case needs more memory than `available_memory` (by
/// default what this machine has available; under MPI pass the same value on every rank, e.g. the
/// smallest over the ranks, so that all of them take the same decision).
Scene build_scene(const CaseSpec& spec, const std::optional<std::size_t>& available_memory = available_memory_bytes());

/// Throws CaseError naming dp, the particle count and the memory estimate when the case (count_particles,
/// estimate_memory_bytes + program_bytes) needs more than `available` bytes (none: not checked) or has
/// more than max_scene_particles particles. Allocates nothing.
void check_scene_size(const CaseSpec& spec, const std::optional<std::size_t>& available);

}  // namespace mpsfsi
