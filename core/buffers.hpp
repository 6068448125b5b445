// Arrays rebuilt every step (neighbour lists, the pressure system, the particle arrays after a migration)
// keep their capacity between steps; when a step needs more, they grow with headroom, so that a size that
// creeps up by a few entries per step does not reallocate (and page-fault a fresh, zeroed copy) every step.
#pragma once

#include <cstddef>
#include <vector>

namespace mpsfsi {

/// v.resize(n); when n exceeds the capacity, the capacity becomes n + n / 8 first.
template <class T, class A>
void resize_with_headroom(std::vector<T, A>& v, const std::size_t n) {
  if (n > v.capacity()) v.reserve(n + n / 8);
  v.resize(n);
}

}  // namespace mpsfsi
