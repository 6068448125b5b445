// Seismic sources of solid bodies (issue 6; seed 000 §3, Lamb's problem): the source time functions
// and the per-particle force patterns of an explosive line source and of a line force (see
// solid/solid_parameters.hpp SourceSpec and core/point_stencil.hpp). The solver adds, at time t,
//   F_k(t) = amplitude s(t) g_k
// to each particle k of the stencil; for an explosion sum g_k = 0 and sum (x_k - x_s) g_k^T = I (moment
// tensor M(t) I, the body force -M grad(delta)), for a force sum g_k = direction with no moment about x_s.
// The definitions match scripts/lamb/lamb2d.py, the analytic reference.
#pragma once

#include "core/point_stencil.hpp"
#include "core/setup_error.hpp"
#include "solid/solid_parameters.hpp"

#include <vector>

namespace mpsfsi {

/// s(t) of a wavelet (solid/solid_parameters.hpp WaveletSpec): dimensionless, unit peak for gaussian_derivative,
/// ricker and gaussian.
Real wavelet_value(const WaveletSpec& w, Real t);

/// Force pattern g_k of a source over the particles `candidates` (indices into the reference positions
/// x0) within source.radius of source.position. Throws SetupError (naming the source) when the stencil
/// cannot be built (too few particles in range).
VectorStencil source_stencil(const SourceSpec& source, const std::vector<Vec>& x0,
                             const std::vector<std::size_t>& candidates);

}  // namespace mpsfsi
