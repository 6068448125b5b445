// Source time functions and force patterns of the solid's seismic sources (solid/sources.hpp).
#include "solid/sources.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mpsfsi {

Real wavelet_value(const WaveletSpec& w, const Real t) {
  if (w.type == WaveletType::table) {
    if (w.time.size() < 2 || t < w.time.front() || t > w.time.back()) return 0;
    const auto hi = static_cast<std::size_t>(std::upper_bound(w.time.begin(), w.time.end(), t) - w.time.begin());
    if (hi >= w.time.size()) return w.value.back();  // t == last time
    const std::size_t lo = hi - 1;
    const Real a = (t - w.time[lo]) / (w.time[hi] - w.time[lo]);
    return (1 - a) * w.value[lo] + a * w.value[hi];
  }
  const Real tau = t - w.delay;
  const Real sigma = 1 / (2 * pi * w.frequency);
  switch (w.type) {
    case WaveletType::gaussian_derivative: {
      const Real q = tau / sigma;
      return -std::sqrt(std::exp(1.0)) * q * std::exp(-0.5 * q * q);
    }
    case WaveletType::gaussian: {
      const Real q = tau / sigma;
      return std::exp(-0.5 * q * q);
    }
    case WaveletType::ricker: {
      const Real a = pi * w.frequency * tau;
      return (1 - 2 * a * a) * std::exp(-a * a);
    }
    case WaveletType::table: break;
  }
  return 0;
}

VectorStencil source_stencil(const SourceSpec& source, const std::vector<Vec>& x0,
                             const std::vector<std::size_t>& candidates) {
  try {
    if (source.type == SourceType::explosion) return moment_stencil(x0, candidates, source.position, source.radius);
    const PointStencil s = interpolation_stencil(x0, candidates, source.position, source.radius);
    VectorStencil v;
    v.index = s.index;
    for (const Real phi : s.weight) v.value.push_back(phi * source.direction);
    return v;
  } catch (const std::invalid_argument& e) {
    throw SetupError(fmt::format("source '{}' at ({:g}, {:g}) on body '{}': {}", source.name, source.position[0],
                                source.position[1], source.body, e.what()));
  }
}

}  // namespace mpsfsi
