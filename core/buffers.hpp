// Arrays rebuilt every step (neighbour lists, the pressure system, the particle arrays after a migration)
// keep their capacity between steps; when a step needs more, they grow with headroom, so that a size that
// creeps up by a few entries per step does not reallocate (and page-fault a fresh, zeroed copy) every step.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace mpsfsi {

/// v.resize(n); when n exceeds the capacity, the capacity becomes n + n / 8 first.
template <class T, class A>
void resize_with_headroom(std::vector<T, A>& v, const std::size_t n) {
  if (n > v.capacity()) v.reserve(n + n / 8);
  v.resize(n);
}

/// resize_with_headroom, except that an array whose capacity exceeds twice the headroom's (a size that fell a
/// long way, e.g. after the first step of a run, whose pressure operator is the widest) is reallocated to
/// n + n / 8, so that its pages go back to the system.
template <class T, class A>
void fit_with_headroom(std::vector<T, A>& v, const std::size_t n) {
  const std::size_t want = n + n / 8;
  if (v.capacity() > 2 * want) {
    std::vector<T, A> fresh;
    fresh.reserve(want);
    fresh.assign(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(std::min(v.size(), n)));
    fresh.resize(n);
    v.swap(fresh);
    return;
  }
  resize_with_headroom(v, n);
}

/// An array filled to its size: reallocated to size + size / 8 if its capacity exceeds twice that (see
/// fit_with_headroom).
template <class T, class A>
void trim_oversized(std::vector<T, A>& v) {
  fit_with_headroom(v, v.size());
}

}  // namespace mpsfsi
