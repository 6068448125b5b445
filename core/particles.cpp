// Structure-of-arrays particle storage: appending, extra fields, reordering and removal, packing for transfers.
#include "core/particles.hpp"

#include "core/binary_io.hpp"
#include "core/buffers.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cstring>
#include <stdexcept>

namespace mpsfsi {

const char* to_string(const ParticleKind kind) {
  switch (kind) {
    case ParticleKind::fluid: return "fluid";
    case ParticleKind::wall: return "wall";
    case ParticleKind::dummy: return "dummy";
    case ParticleKind::solid: return "solid";
  }
  return "unknown";
}

std::size_t ParticleSet::n_of_kind(const ParticleKind k) const {
  std::size_t n = 0;
  for (const auto kk : kind) n += (kk == k);
  return n;
}

LocalIndex ParticleSet::add(const Vec& x, const Vec& v, const ParticleKind k, const int body_index,
                            const int material_index, const bool is_clamped) {
  assert(n_ghost_ == 0 && "owned particles come before the ghosts");
  const auto i = static_cast<LocalIndex>(size());
  index_stale_ = true;
  position.push_back(x);
  velocity.push_back(v);
  kind.push_back(k);
  body.push_back(static_cast<std::uint16_t>(body_index));
  material.push_back(static_cast<std::int16_t>(material_index));
  clamped.push_back(is_clamped ? 1 : 0);
  global_id.push_back(next_id_++);
  for (auto& [name, f] : scalar_fields_) f.push_back(scalar_defaults_[name]);
  for (auto& [name, f] : vector_fields_) f.push_back(vector_defaults_[name]);
  return i;
}

LocalIndex ParticleSet::local_index(const GlobalId id) const {
  if (index_stale_) {
    index_of_.clear();
    index_of_.reserve(size());
    for (std::size_t i = 0; i < size(); ++i) index_of_.emplace(global_id[i], static_cast<LocalIndex>(i));
    index_stale_ = false;
  }
  const auto it = index_of_.find(id);
  if (it == index_of_.end()) return -1;
  assert(global_id[static_cast<std::size_t>(it->second)] == id && "global_id changed behind the set's back");
  return it->second;
}

void ParticleSet::reserve(const std::size_t n) {
  position.reserve(n);
  velocity.reserve(n);
  kind.reserve(n);
  body.reserve(n);
  material.reserve(n);
  clamped.reserve(n);
  global_id.reserve(n);
}

std::vector<Real>& ParticleSet::add_scalar_field(const std::string& name, const Real initial) {
  auto it = scalar_fields_.find(name);
  if (it != scalar_fields_.end()) return it->second;
  scalar_defaults_[name] = initial;
  return scalar_fields_.emplace(name, std::vector<Real>(size(), initial)).first->second;
}

std::vector<Vec>& ParticleSet::add_vector_field(const std::string& name, const Vec& initial) {
  auto it = vector_fields_.find(name);
  if (it != vector_fields_.end()) return it->second;
  vector_defaults_[name] = initial;
  return vector_fields_.emplace(name, std::vector<Vec>(size(), initial)).first->second;
}

namespace {
template <class Map>
auto& find_field(Map& fields, const std::string& name) {
  auto it = fields.find(name);
  if (it == fields.end()) throw std::out_of_range("particle field '" + name + "' is not registered");
  return it->second;
}

template <class T>
void permute(std::vector<T>& a, const std::vector<LocalIndex>& order) {
  std::vector<T> b(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) b[k] = a[static_cast<std::size_t>(order[k])];
  a.swap(b);
}

template <class T>
void compact(std::vector<T>& a, const std::vector<std::uint8_t>& remove) {
  std::size_t k = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!remove[i]) a[k++] = a[i];
  a.resize(k);
}
}  // namespace

std::vector<Real>& ParticleSet::scalar_field(const std::string& name) { return find_field(scalar_fields_, name); }
const std::vector<Real>& ParticleSet::scalar_field(const std::string& name) const {
  return find_field(scalar_fields_, name);
}
std::vector<Vec>& ParticleSet::vector_field(const std::string& name) { return find_field(vector_fields_, name); }
const std::vector<Vec>& ParticleSet::vector_field(const std::string& name) const {
  return find_field(vector_fields_, name);
}

template <class Self, class F>
void ParticleSet::for_each_array_of(Self& self, F&& f) {
  f(self.position);
  f(self.velocity);
  f(self.kind);
  f(self.body);
  f(self.material);
  f(self.clamped);
  f(self.global_id);
  for (auto& [name, a] : self.scalar_fields_) f(a);
  for (auto& [name, a] : self.vector_fields_) f(a);
}

template <class F>
void ParticleSet::for_each_array(F&& f) {
  for_each_array_of(*this, f);
}

template <class F>
void ParticleSet::for_each_array(F&& f) const {
  for_each_array_of(*this, f);
}

static_assert(sizeof(Vec) == dim * sizeof(Real), "Vec must be dim contiguous reals (packing, real_array)");

void ParticleSet::drop_ghosts() {
  if (n_ghost_ == 0) return;
  const std::size_t n = n_owned();
  for_each_array([&](auto& a) { a.resize(n); });
  n_ghost_ = 0;
  index_stale_ = true;
}

void ParticleSet::assign_from(const ParticleSet& saved) {
  if (&saved == this) return;
  if (saved.field_layout() != field_layout() || saved.bodies.size() != bodies.size())
    throw std::logic_error("ParticleSet::assign_from: the saved set has other fields or bodies");
  position = saved.position;
  velocity = saved.velocity;
  kind = saved.kind;
  body = saved.body;
  material = saved.material;
  clamped = saved.clamped;
  global_id = saved.global_id;
  for (auto& [name, a] : scalar_fields_) a = saved.scalar_fields_.at(name);
  for (auto& [name, a] : vector_fields_) a = saved.vector_fields_.at(name);
  n_ghost_ = saved.n_ghost_;
  next_id_ = saved.next_id_;
  index_stale_ = true;
}

std::size_t ParticleSet::packed_size() const {
  std::size_t b = 0;
  for_each_array([&](const auto& a) { b += sizeof(typename std::decay_t<decltype(a)>::value_type); });
  return b;
}

void ParticleSet::pack(const std::vector<LocalIndex>& indices, std::vector<char>& out) const {
  const std::size_t record = packed_size();
  const std::size_t start = out.size();
  out.resize(start + indices.size() * record);
  std::size_t column = 0;  // byte offset of the current array inside a record
  for_each_array([&](const auto& a) {
    using T = typename std::decay_t<decltype(a)>::value_type;
    char* dst = out.data() + start + column;
    for (const LocalIndex i : indices) {
      assert(i >= 0 && static_cast<std::size_t>(i) < a.size());
      std::memcpy(dst, &a[static_cast<std::size_t>(i)], sizeof(T));
      dst += record;
    }
    column += sizeof(T);
  });
}

void ParticleSet::unpack(const char* data, const std::size_t n) {
  const std::size_t record = packed_size();
  std::size_t column = 0;
  for_each_array([&](auto& a) {
    using T = typename std::decay_t<decltype(a)>::value_type;
    const std::size_t old = a.size();
    resize_with_headroom(a, old + n);
    const char* src = data + column;
    for (std::size_t k = 0; k < n; ++k, src += record) std::memcpy(static_cast<void*>(&a[old + k]), src, sizeof(T));
    column += sizeof(T);
  });
  index_stale_ = true;
}

void ParticleSet::unpack_owned(const char* data, const std::size_t n) {
  assert(n_ghost_ == 0 && "owned particles come before the ghosts: drop the ghosts first");
  unpack(data, n);
}

void ParticleSet::unpack_ghosts(const char* data, const std::size_t n) {
  unpack(data, n);
  n_ghost_ += n;
}

std::string ParticleSet::field_layout() const {
  std::string s;
  for (const auto& kv : scalar_fields_) s += "s:" + kv.first + "\n";
  for (const auto& kv : vector_fields_) s += "v:" + kv.first + "\n";
  return s;
}

ParticleSet::RealArray ParticleSet::real_array(const std::string& name) {
  if (name == "position") return {position.empty() ? nullptr : position.data()->data(), dim};
  if (name == "velocity") return {velocity.empty() ? nullptr : velocity.data()->data(), dim};
  if (auto it = scalar_fields_.find(name); it != scalar_fields_.end()) return {it->second.data(), 1};
  if (auto it = vector_fields_.find(name); it != vector_fields_.end())
    return {it->second.empty() ? nullptr : it->second.data()->data(), dim};
  throw std::out_of_range("particle array '" + name + "' is neither position, velocity nor a registered field");
}

void ParticleSet::reorder(const std::vector<LocalIndex>& order) {
  assert(order.size() == size() && n_ghost_ == 0);
  for_each_array([&](auto& a) { permute(a, order); });
  index_stale_ = true;
}

std::size_t ParticleSet::remove_if(const std::vector<std::uint8_t>& remove) {
  assert(remove.size() == size());
  assert(n_ghost_ == 0);
  const std::size_t before = size();
  for_each_array([&](auto& a) { compact(a, remove); });
  index_stale_ = true;
  return before - size();
}

std::size_t ParticleSet::memory_bytes() const {
  std::size_t b = size() * (2 * sizeof(Vec) + sizeof(ParticleKind) + sizeof(std::uint16_t) +
                            sizeof(std::int16_t) + sizeof(std::uint8_t) + sizeof(GlobalId));
  b += scalar_fields_.size() * size() * sizeof(Real);
  b += vector_fields_.size() * size() * sizeof(Vec);
  return b;
}

void ParticleSet::save_state(BinaryWriter& out) const {
  out.section("particles");
  out.u64(size());
  out.u64(bodies.size());
  for (const auto& b : bodies) {
    out.string(b.name);
    out.value(static_cast<std::uint8_t>(b.kind));
    out.value(static_cast<std::int32_t>(b.material));
  }
  const auto named = [&](const char* name, const auto& a) {
    out.string(name);
    out.array(a);
  };
  named("position", position);
  named("velocity", velocity);
  named("kind", kind);
  named("body", body);
  named("material", material);
  named("clamped", clamped);
  named("global_id", global_id);
  out.u64(scalar_fields_.size());
  for (const auto& [name, a] : scalar_fields_) named(name.c_str(), a);
  out.u64(vector_fields_.size());
  for (const auto& [name, a] : vector_fields_) named(name.c_str(), a);
}

void ParticleSet::load_state(BinaryReader& in) {
  in.expect_section("particles");
  const std::size_t n = in.u64("the particle count");
  const std::size_t nb = in.u64("the body count");
  if (nb != bodies.size())
    in.fail("the checkpoint has " + std::to_string(nb) + " bodies, this case " + std::to_string(bodies.size()));
  for (std::size_t b = 0; b < nb; ++b) {
    const std::string name = in.string("a body name");
    const auto k = in.value<std::uint8_t>("a body kind");
    const auto m = in.value<std::int32_t>("a body material");
    if (name != bodies[b].name || k != static_cast<std::uint8_t>(bodies[b].kind) || m != bodies[b].material)
      in.fail("body " + std::to_string(b) + " of the checkpoint is '" + name + "', of this case '" + bodies[b].name +
              "' (or its kind or material differ)");
  }
  // Read into a copy: this set stays unchanged when the data do not match.
  ParticleSet next;
  next.bodies = bodies;
  const auto named = [&](const char* name, auto& a) {
    const std::string got = in.string("an array name");
    if (got != name) in.fail("expected particle array '" + std::string(name) + "', found '" + got + "'");
    a = in.array<typename std::decay_t<decltype(a)>::value_type>(name, n);
  };
  named("position", next.position);
  named("velocity", next.velocity);
  named("kind", next.kind);
  named("body", next.body);
  named("material", next.material);
  named("clamped", next.clamped);
  named("global_id", next.global_id);
  const auto fields = [&](auto& mine, auto& theirs, const char* what) {
    const std::size_t count = in.u64("a field count");
    for (std::size_t f = 0; f < count; ++f) {
      const std::string name = in.string("a field name");
      if (!mine.count(name))
        in.fail("the checkpoint has the " + std::string(what) + " particle field '" + name + "', which this run does not have");
      theirs[name] = in.template array<typename std::decay_t<decltype(mine.begin()->second)>::value_type>(name.c_str(), n);
    }
    for (const auto& kv : mine)
      if (!theirs.count(kv.first))
        in.fail("this run has the " + std::string(what) + " particle field '" + kv.first + "', which the checkpoint does not have");
  };
  fields(scalar_fields_, next.scalar_fields_, "scalar");
  fields(vector_fields_, next.vector_fields_, "vector");
  for (std::size_t i = 0; i < n; ++i) {
    if (static_cast<std::size_t>(next.body[i]) >= bodies.size()) in.fail("particle " + std::to_string(i) + " has no valid body");
    if (static_cast<std::uint8_t>(next.kind[i]) > static_cast<std::uint8_t>(ParticleKind::solid))
      in.fail("particle " + std::to_string(i) + " has no valid kind");
  }
  position.swap(next.position);
  velocity.swap(next.velocity);
  kind.swap(next.kind);
  body.swap(next.body);
  material.swap(next.material);
  clamped.swap(next.clamped);
  global_id.swap(next.global_id);
  for (auto& [name, a] : scalar_fields_) a.swap(next.scalar_fields_[name]);
  for (auto& [name, a] : vector_fields_) a.swap(next.vector_fields_[name]);
  n_ghost_ = 0;
  index_stale_ = true;
  next_id_ = global_id.empty() ? 0 : *std::max_element(global_id.begin(), global_id.end()) + 1;
}

std::vector<GlobalId> owned_ids(const ParticleSet& p, const ParticleKind k) {
  std::vector<GlobalId> ids;
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    if (p.kind[i] == k) ids.push_back(p.global_id[i]);
  return ids;
}

std::vector<LocalIndex> owned_in_order(const ParticleSet& p, const ParticleKind k, const std::vector<GlobalId>& ids,
                                       const char* who) {
  std::vector<LocalIndex> at;
  at.reserve(ids.size());
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    if (p.kind[i] != k) continue;
    if (at.size() >= ids.size() || ids[at.size()] != p.global_id[i])
      throw std::logic_error(fmt::format("{}: owned {} particle {} (global id {}) is not entry {} of the data", who,
                                         to_string(k), i, p.global_id[i], at.size()));
    at.push_back(static_cast<LocalIndex>(i));
  }
  if (at.size() != ids.size())
    throw std::logic_error(fmt::format("{}: {} ids for {} owned {} particles", who, ids.size(), at.size(), to_string(k)));
  return at;
}

}  // namespace mpsfsi
