// Distribution of the particles over the ranks of a communicator (domain decomposition by space): each
// particle is owned by exactly one rank; a rank's region is a box of a Zoltan2 geometric partition
// (RCB or MultiJagged on the particle coordinates, weighted by particle cost), the boxes on the outside
// of the partition reaching to infinity so that the regions tile all space. Ghosts are copies of other
// ranks' owned particles within the halo width of this rank's region. The halo API follows AMReX's
// neighbour particles: migrate() (Redistribute), build_ghosts() (fillNeighbors), exchange_ghosts()
// (updateNeighbors) and reverse_sum() (sumNeighbors). Every transfer carries global ids, the identity of
// a particle on every rank.
#pragma once

#include "core/enum_names.hpp"
#include "core/particles.hpp"
#include "core/types.hpp"

#include <mpi.h>

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mpsfsi {

/// Geometric partitioner of Zoltan2. Both run Zoltan2's MultiJagged (the only Zoltan2 geometric algorithm that
/// returns its part boxes): rcb as recursive bisection ("mj_enable_rcb"), multijagged with several cuts per level.
enum class PartitionMethod { rcb, multijagged };

inline const NameTable<PartitionMethod>& partition_method_names() {
  static const NameTable<PartitionMethod> t = {{"rcb", PartitionMethod::rcb},
                                               {"multijagged", PartitionMethod::multijagged}};
  return t;
}

struct DistributionSettings {
  PartitionMethod method = PartitionMethod::rcb;
  /// Ghosts: other ranks' particles within this distance of the region (the largest interaction radius
  /// plus the skin) [m].
  Real halo_width = 0;
  /// The part of halo_width beyond the interaction radius [m]: the owners and ghosts stay valid until a
  /// particle has moved half of it (needs_rebuild).
  Real skin = 0;
  /// Re-partition when (largest owned work) / (mean owned work) - 1 passes this.
  Real imbalance_threshold = 0.1;
};

/// An axis-aligned box; the outer faces of a partition's boxes are +-infinity. It holds the points with
/// lo <= x < hi on every axis (x == hi too where hi is +infinity), so a point on a face shared by two regions
/// belongs to the one above it. A region with no points (an empty part) has lo = +inf, hi = -inf.
struct Box {
  Vec lo, hi;
  bool contains(const Vec& x) const;
  /// Euclidean distance from x to the box (0 inside).
  Real distance(const Vec& x) const;
};

/// Counters for the run log and the benchmarks (this rank's values).
struct DistributionStats {
  std::size_t n_migrated_out = 0;   ///< particles sent by the last migrate()
  std::size_t halo_bytes = 0;       ///< bytes sent by this rank in all build_ghosts() and exchanges so far
  int n_partitions = 0;             ///< partitions computed so far
  int n_ghost_builds = 0;           ///< build_ghosts() calls so far
  double t_partition = 0, t_migrate = 0, t_halo = 0;  ///< seconds, accumulated
};

class BinaryWriter;
class BinaryReader;

class Distribution {
 public:
  /// Collective: duplicates `comm` for its own messages (freed by the destructor, before MPI_Finalize).
  Distribution(MPI_Comm comm, const DistributionSettings& settings);
  ~Distribution();
  Distribution(const Distribution&) = delete;
  Distribution& operator=(const Distribution&) = delete;

  int rank() const { return rank_; }
  const DistributionSettings& settings() const { return settings_; }
  int n_ranks() const { return n_ranks_; }
  MPI_Comm comm() const { return comm_; }

  /// Partitions the owned particles of every rank with Zoltan2 (weights: one per owned particle, or all 1
  /// when empty) and migrates them to their new owners. Drops the ghosts first. Collective.
  void partition(ParticleSet& p, const std::vector<Real>& weights = {});
  /// From a set that every rank holds entirely (a scene built on every rank): partitions it and keeps on
  /// each rank only the particles it owns. Collective.
  void distribute_replicated(ParticleSet& p, const std::vector<Real>& weights = {});
  /// Sends every owned particle whose position left this rank's region to the rank whose region holds it
  /// (all its arrays and fields). Drops the ghosts first. Collective.
  void migrate(ParticleSet& p);
  /// (largest owned work) / (mean owned work) - 1 over the ranks for these weights (empty: counts).
  /// Collective.
  Real imbalance(const ParticleSet& p, const std::vector<Real>& weights = {}) const;

  /// Replaces the ghosts by copies (all arrays and fields) of the other ranks' owned particles within
  /// the halo width of this rank's region, and remembers who sent what for the exchanges below. Ghosts
  /// are appended after the owned particles in order of sending rank, then of the sender's local index.
  /// Collective.
  void build_ghosts(ParticleSet& p);
  /// Whether the owners and ghosts must be renewed (migrate, build_ghosts) before the particles are used
  /// again: `requested` on some rank, the ghost plan does not fit the particles (removed, migrated), or a
  /// particle moved more than half the skin since the last build_ghosts(); with `only`, a particle of that
  /// kind (the caller reads no other ghosts until a renew without `only` checks every particle). Always false
  /// on one rank unless requested. Collective: every rank gets the same answer.
  bool needs_rebuild(const ParticleSet& p, bool requested = false, std::optional<ParticleKind> only = std::nullopt) const;
  /// Owners and ghosts ready for a module's next use: when needs_rebuild(p, requested), drops the ghosts,
  /// migrates, calls `before_ghosts` (e.g. a reorder of the owned particles) and builds the ghosts, and returns
  /// true; otherwise refreshes `fields` of the ghosts (of kind `only`) and returns false. With `only`, only
  /// the displacements of that kind count (needs_rebuild). Collective.
  bool renew(ParticleSet& p, const std::vector<std::string>& fields, std::optional<ParticleKind> only = std::nullopt,
             bool requested = false, const std::function<void()>& before_ghosts = {});
  /// Refreshes the named fields ("position", "velocity" or registered scalar / vector fields) of the
  /// ghosts from their owners, with the plan of the last build_ghosts(); with `only`, of the ghosts of that
  /// kind alone (e.g. the solid's sub-steps, which move only solid particles). Collective.
  void exchange_ghosts(ParticleSet& p, const std::vector<std::string>& fields,
                       std::optional<ParticleKind> only = std::nullopt);
  /// Adds the ghosts' values of the named fields into their owners' values and sets the ghosts' values to
  /// zero (contributions computed at ghosts, e.g. a force on another rank's particle). Collective.
  void reverse_sum(ParticleSet& p, const std::vector<std::string>& fields);

  /// The rank that owns ghost k (the particle of local index n_owned() + k) since the last build_ghosts().
  int ghost_owner(std::size_t k) const;
  /// On rank `root`: every rank's owned particles (all arrays) in order of rank, then of local index;
  /// elsewhere an empty set with the same fields. Collective.
  ParticleSet gather(const ParticleSet& p, int root) const;
  /// Checkpoints (rank `root` writes, after gather(p, root)): the ranks' regions and owned counts, so that a
  /// restart on as many ranks gives every rank back its particles in their order. Collective.
  void save_state(BinaryWriter& out, const ParticleSet& p, int root) const;
  /// Restart: `p` holds a whole gathered set on every rank; reads what save_state wrote and keeps on this
  /// rank its own particles: the saved ones on as many ranks as saved them, else by a new partition
  /// (distribute_replicated). Collective.
  void load_state(BinaryReader& in, ParticleSet& p);
  /// The rank whose region holds x (-1 for a non-finite x).
  int owner_of(const Vec& x) const;
  /// Every rank's region (empty before the first partition). With no particles at all, or a partition whose
  /// boxes cannot tile space (all particles on one plane that the partition cuts), rank 0's region is all
  /// space and the other regions are empty.
  const std::vector<Box>& regions() const { return regions_; }
  const DistributionStats& stats() const { return stats_; }

  /// The ghost plan of the last build_ghosts() and the owned positions it was built at, for a caller that puts
  /// the particles back to the state they had (a coupling iteration that repeats a step: ParticleSet::
  /// assign_from): with restore_plan() the exchanges and needs_rebuild() behave as they did then.
  struct Plan;
  std::shared_ptr<const Plan> save_plan() const;
  void restore_plan(const std::shared_ptr<const Plan>& plan);

 private:
  /// exchange_ghosts (to_owners false) and reverse_sum (true) over the plan of the last build_ghosts().
  void transfer(ParticleSet& p, const std::vector<std::string>& fields, bool to_owners,
                std::optional<ParticleKind> only = std::nullopt);

  struct Impl;
  std::unique_ptr<Impl> impl_;
  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, n_ranks_ = 1;
  DistributionSettings settings_;
  std::vector<Box> regions_;
  DistributionStats stats_;
};

}  // namespace mpsfsi
