// Structure-of-arrays particle storage. Every particle has position, velocity, kind, body,
// material, a clamp flag and a global id; physics modules register extra named per-particle
// fields (pressure, rotation angle, ...) that are stored, reordered and written out with the rest.
// The set holds this rank's owned particles first and then its ghosts (read-only copies of other
// ranks' particles near its region); the global id is a particle's identity on every rank, and
// local_index() is the one map from global id to local index that every module uses.
#pragma once

#include "core/types.hpp"

#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

namespace mpsfsi {

class BinaryWriter;
class BinaryReader;

/// What a particle is. Wall particles take part in the pressure solve, dummy particles only fill
/// the kernel support behind a wall (seed 004 §4.3).
enum class ParticleKind : std::uint8_t { fluid = 0, wall = 1, dummy = 2, solid = 3 };

const char* to_string(ParticleKind kind);

/// One body of the scene (a fluid column, an elastic plate, a tank wall, ...).
struct BodyInfo {
  std::string name;
  ParticleKind kind = ParticleKind::fluid;  ///< kind of most of its particles (walls: wall)
  int material = -1;                        ///< index into the case's materials; -1 for walls
};

class ParticleSet {
 public:
  // Core state, one entry per particle.
  std::vector<Vec> position;
  std::vector<Vec> velocity;
  std::vector<ParticleKind> kind;
  std::vector<std::uint16_t> body;      ///< index into bodies
  std::vector<std::int16_t> material;   ///< index into the case's materials, -1 for walls
  std::vector<std::uint8_t> clamped;    ///< 1: displacement held at zero
  std::vector<GlobalId> global_id;

  std::vector<BodyInfo> bodies;

  /// Owned particles and ghosts: the particles a rank computes with.
  std::size_t size() const { return position.size(); }
  /// Owned particles are [0, n_owned()): this rank advances them. Ghosts are [n_owned(), size()): read-only
  /// copies of other ranks' particles within the interaction radius of this rank's region (none on one rank).
  std::size_t n_owned() const { return size() - n_ghost_; }
  std::size_t n_ghost() const { return n_ghost_; }
  std::size_t n_of_kind(ParticleKind k) const;

  /// Local index (owned or ghost) of the particle with global id `id`, or -1 if this rank does not hold it.
  /// The map is rebuilt after add, reorder, remove_if, load_state, drop_ghosts and unpack_*; `global_id` is
  /// not to be assigned otherwise.
  LocalIndex local_index(GlobalId id) const;

  /// Append one owned particle with the next unused global id (0, 1, 2, ... for a scene built on one rank);
  /// the extra fields get their default value. Returns its local index.
  LocalIndex add(const Vec& x, const Vec& v, ParticleKind k, int body_index, int material_index,
                 bool is_clamped = false);
  void reserve(std::size_t n);

  /// Register an extra per-particle field (idempotent). References stay valid while fields are added.
  /// A name starting with '_' marks a module's internal field: stored, moved between ranks and checkpointed
  /// like any other, but not written to the output unless asked for by name.
  std::vector<Real>& add_scalar_field(const std::string& name, Real initial = 0);
  std::vector<Vec>& add_vector_field(const std::string& name, const Vec& initial = Vec::Zero());
  bool has_scalar_field(const std::string& name) const { return scalar_fields_.count(name) != 0; }
  bool has_vector_field(const std::string& name) const { return vector_fields_.count(name) != 0; }
  /// Access a registered field; throws std::out_of_range naming the field if it does not exist.
  std::vector<Real>& scalar_field(const std::string& name);
  const std::vector<Real>& scalar_field(const std::string& name) const;
  std::vector<Vec>& vector_field(const std::string& name);
  const std::vector<Vec>& vector_field(const std::string& name) const;
  const std::map<std::string, std::vector<Real>>& scalar_fields() const { return scalar_fields_; }
  const std::map<std::string, std::vector<Vec>>& vector_fields() const { return vector_fields_; }

  /// Reorder every array: new particle k is old particle order[k]. `order` is a permutation.
  void reorder(const std::vector<LocalIndex>& order);
  /// Remove the particles with remove[i] != 0, keeping the order of the rest. Returns the count.
  std::size_t remove_if(const std::vector<std::uint8_t>& remove);

  // Transfers between ranks (core/distribution.hpp). A packed particle is every array's value in a fixed order:
  // position, velocity, kind, body, material, clamped, global_id, the scalar fields by name, the vector fields by
  // name. Sender and receiver must have registered the same fields (field_layout()).

  /// Removes the ghosts, leaving the owned particles.
  void drop_ghosts();
  /// Puts back a copy taken earlier of this set (`ParticleSet saved = p;`): every array's values, the owned
  /// and ghost counts. The arrays stay the same objects (references to fields remain valid). The copy must have
  /// the same fields; otherwise throws std::logic_error and leaves this set unchanged.
  void assign_from(const ParticleSet& saved);
  /// Bytes of one packed particle.
  std::size_t packed_size() const;
  /// Appends the packed particles `indices` (local indices, owned or ghost) to `out`.
  void pack(const std::vector<LocalIndex>& indices, std::vector<char>& out) const;
  /// Appends `n` packed particles from `data` as owned particles (there must be no ghosts: drop them first).
  void unpack_owned(const char* data, std::size_t n);
  /// Appends `n` packed particles from `data` as ghosts, after the owned particles and the present ghosts.
  void unpack_ghosts(const char* data, std::size_t n);
  /// The names of the extra fields, scalar then vector ("s:name\nv:name\n..."): equal on every rank of a run.
  std::string field_layout() const;

  /// A per-particle array of reals by name ("position", "velocity", a scalar or a vector field): `components`
  /// reals per particle, particle i at data[i * components]. Throws std::out_of_range naming an unknown name.
  struct RealArray {
    Real* data = nullptr;
    int components = 0;
  };
  RealArray real_array(const std::string& name);

  /// Bytes held by the particle arrays (for the memory estimate).
  std::size_t memory_bytes() const;

  /// Checkpoints: the bodies and every per-particle array (core arrays and extra fields) by name.
  void save_state(BinaryWriter& out) const;
  /// Replaces every array by the saved one (the particle count may differ). The saved set must have the
  /// same bodies and the same arrays (names, element types) as this one; otherwise throws
  /// StateFormatError naming the first difference and leaves this set unchanged.
  void load_state(BinaryReader& in);

 private:
  /// Apply f to every per-particle array (core and extra fields).
  template <class F>
  void for_each_array(F&& f);
  template <class F>
  void for_each_array(F&& f) const;
  /// The one list of the arrays, for both of the above.
  template <class Self, class F>
  static void for_each_array_of(Self& self, F&& f);
  void unpack(const char* data, std::size_t n);

  std::size_t n_ghost_ = 0;
  GlobalId next_id_ = 0;  ///< global id of the next particle added
  mutable std::unordered_map<GlobalId, LocalIndex> index_of_;  ///< built by local_index() when stale
  mutable bool index_stale_ = true;
  std::map<std::string, std::vector<Real>> scalar_fields_;
  std::map<std::string, std::vector<Vec>> vector_fields_;
  std::map<std::string, Real> scalar_defaults_;
  std::map<std::string, Vec> vector_defaults_;
};

/// An angular per-particle field (rotation vector, angular velocity; types.hpp's Angular): a scalar field in
/// 2D, a vector field in 3D. Registers it like add_scalar_field / add_vector_field (idempotent).
inline std::vector<Angular>& add_angular_field(ParticleSet& p, const std::string& name) {
#if MPSFSI_DIM == 2
  return p.add_scalar_field(name);
#else
  return p.add_vector_field(name);
#endif
}
/// The registered angular field `name`; throws std::out_of_range naming it if it does not exist.
inline std::vector<Angular>& angular_field(ParticleSet& p, const std::string& name) {
#if MPSFSI_DIM == 2
  return p.scalar_field(name);
#else
  return p.vector_field(name);
#endif
}
inline const std::vector<Angular>& angular_field(const ParticleSet& p, const std::string& name) {
#if MPSFSI_DIM == 2
  return p.scalar_field(name);
#else
  return p.vector_field(name);
#endif
}

/// Global ids of the owned particles of kind k, in local order: how one module names the particles whose
/// interface data it hands to another.
std::vector<GlobalId> owned_ids(const ParticleSet& p, ParticleKind k);
/// The local indices of the owned particles of kind k, checked against interface data keyed by `ids` (one
/// entry per such particle, in local order); throws std::logic_error naming `who`, the particle and the entry
/// otherwise.
std::vector<LocalIndex> owned_in_order(const ParticleSet& p, ParticleKind k, const std::vector<GlobalId>& ids,
                                       const char* who);

}  // namespace mpsfsi
