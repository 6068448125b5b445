// Points and boxes as text for messages, in the build's dimension: "(x, y)" or "(x, y, z)" and
// "[x0, x1] x [y0, y1] (x [z0, z1])".
#pragma once

#include "core/geometry.hpp"
#include "core/types.hpp"

#include <fmt/format.h>

#include <string>

namespace mpsfsi {

/// "(x, y[, z])" with 6 significant digits.
inline std::string show_point(const Vec& v) {
  std::string s = "(";
  for (int a = 0; a < dim; ++a) s += fmt::format("{}{:.6g}", a ? ", " : "", v[a]);
  return s + ")";
}

/// "[lo_x, hi_x] x [lo_y, hi_y][ x [lo_z, hi_z]]" with 4 significant digits.
inline std::string show_box(const Rect& r) {
  std::string s;
  for (int a = 0; a < dim; ++a) s += fmt::format("{}[{:.4g}, {:.4g}]", a ? " x " : "", r.lo[a], r.hi[a]);
  return s;
}

}  // namespace mpsfsi
