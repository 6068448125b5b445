// Structure-of-arrays particle storage: appending, extra fields, reordering and removal.
#include "core/particles.hpp"

#include <cassert>
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
  const auto i = static_cast<LocalIndex>(size());
  position.push_back(x);
  velocity.push_back(v);
  kind.push_back(k);
  body.push_back(static_cast<std::uint16_t>(body_index));
  material.push_back(static_cast<std::int16_t>(material_index));
  clamped.push_back(is_clamped ? 1 : 0);
  global_id.push_back(static_cast<GlobalId>(i));
  for (auto& [name, f] : scalar_fields_) f.push_back(scalar_defaults_[name]);
  for (auto& [name, f] : vector_fields_) f.push_back(vector_defaults_[name]);
  return i;
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

template <class F>
void ParticleSet::for_each_array(F&& f) {
  f(position);
  f(velocity);
  f(kind);
  f(body);
  f(material);
  f(clamped);
  f(global_id);
  for (auto& [name, a] : scalar_fields_) f(a);
  for (auto& [name, a] : vector_fields_) f(a);
}

void ParticleSet::reorder(const std::vector<LocalIndex>& order) {
  assert(order.size() == size());
  for_each_array([&](auto& a) { permute(a, order); });
}

std::size_t ParticleSet::remove_if(const std::vector<std::uint8_t>& remove) {
  assert(remove.size() == size());
  const std::size_t before = size();
  for_each_array([&](auto& a) { compact(a, remove); });
  return before - size();
}

std::size_t ParticleSet::memory_bytes() const {
  std::size_t b = size() * (2 * sizeof(Vec) + sizeof(ParticleKind) + sizeof(std::uint16_t) +
                            sizeof(std::int16_t) + sizeof(std::uint8_t) + sizeof(GlobalId));
  b += scalar_fields_.size() * size() * sizeof(Real);
  b += vector_fields_.size() * size() * sizeof(Vec);
  return b;
}

}  // namespace mpsfsi
