// Name tables of enumerated options: each option enum (fluid/fluid_parameters.hpp,
// solid/solid_parameters.hpp, ...) has ONE table of (name, value) pairs in its own header; the case
// parser (io/case_file.cpp) reads the names through it and the run log writes them through it.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mpsfsi {

template <class E>
using NameTable = std::vector<std::pair<std::string_view, E>>;

/// The name of `value` in `table` ("?" when absent, which a complete table never is).
template <class E>
std::string_view name_of(const NameTable<E>& table, const E value) {
  for (const auto& [name, v] : table)
    if (v == value) return name;
  return "?";
}

/// The value named `name`, or none.
template <class E>
std::optional<E> value_of(const NameTable<E>& table, const std::string_view name) {
  for (const auto& [n, v] : table)
    if (n == name) return v;
  return std::nullopt;
}

/// The names of a table, in its order.
template <class E>
std::vector<std::string> names_of(const NameTable<E>& table) {
  std::vector<std::string> out;
  for (const auto& entry : table) out.emplace_back(entry.first);
  return out;
}

/// The names of a table joined by ", " (for messages).
template <class E>
std::string join_names(const NameTable<E>& table) {
  std::string out;
  for (const auto& entry : table) out += (out.empty() ? "" : ", ") + std::string(entry.first);
  return out;
}

}  // namespace mpsfsi
