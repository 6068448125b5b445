// Probe evaluation and CSV output. "Up" is the last axis (y in 2D, z in 3D): the floor of surge_front and
// the heights of column_height and wave_gauge are along it.
#include "io/probes.hpp"

#include "core/files.hpp"
#include "core/kernel.hpp"
#include "core/tank_motion.hpp"
#include "fluid/fluid_parameters.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace mpsfsi {

namespace {
/// The vertical axis.
constexpr int up = dim - 1;

/// Largest coordinate `axis` of the fluid particles whose coordinate `other` is below `limit` (over this
/// rank's owned particles; the largest over the ranks is the probe's value; evaluate() adds the half
/// particle to the fluid's outer edge). In 3D over the whole width (the axis that is neither).
Real fluid_extent(const ParticleSet& p, const int axis, const int other, const Real limit) {
  Real m = -std::numeric_limits<Real>::max();
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    if (p.kind[i] == ParticleKind::fluid && p.position[i][other] < limit) m = std::max(m, p.position[i][axis]);
  return m;
}

/// Largest height of the fluid particles whose horizontal coordinates are within dp of the probe's (a strip 2 dp
/// wide in 2D, a square column 2 dp across in 3D), over this rank's owned particles.
Real fluid_top(const ParticleSet& p, const Vec& at, const Real dp) {
  Real m = -std::numeric_limits<Real>::max();
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    if (p.kind[i] != ParticleKind::fluid) continue;
    bool inside = true;
    for (int a = 0; a < up; ++a) inside = inside && std::abs(p.position[i][a] - at[a]) < dp;
    if (inside) m = std::max(m, p.position[i][up]);
  }
  return m;
}
}  // namespace

ProbeWriter::ProbeWriter(const CaseSpec& spec, const ParticleSet& particles, const std::string& path, const bool append)
    : dp_(spec.dp), tank_(make_tank_motion(spec.tank_motion)) {
  for (const auto& ps : spec.probes) {
    Probe p{ps, -1, Vec::Zero()};
    if (ps.type == ProbeType::displacement) {
      Real best = std::numeric_limits<Real>::max();
      for (std::size_t i = 0; i < particles.size(); ++i) {
        if (particles.bodies[particles.body[i]].name != ps.body) continue;
        const Real d = (particles.position[i] - ps.position).squaredNorm();
        if (d < best) {
          best = d;
          p.particle = particles.global_id[i];
          p.initial = particles.position[i];
        }
      }
      if (p.particle < 0) throw CaseError(fmt::format("probe '{}': body '{}' has no particles", ps.name, ps.body));
      for (int a = 0; a < dim; ++a) columns_.push_back(ps.name + "_d" + "xyz"[a]);
    } else {
      columns_.push_back(ps.name);
    }
    probes_.push_back(p);
  }
  if (probes_.empty() || path.empty()) return;
  out_.open(path, append ? std::ios::app : std::ios::trunc);
  path_ = path;
  check_written(out_, path_, "probe table");
  if (append) return;
  out_ << "time";
  for (const auto& c : columns_) out_ << "," << c;
  out_ << "\n";
}

std::vector<Real> ProbeWriter::evaluate(const ParticleSet& p, const Real t, MPI_Comm comm) const {
  // Each probe's terms over this rank's owned particles: sums (kernel averages) and maxima (extents, the
  // displacement of the one particle, -max elsewhere), reduced over the ranks below.
  const Real lowest = -std::numeric_limits<Real>::max();
  std::vector<Real> sums, maxima;
  const bool has_pressure = p.has_scalar_field(fluid_fields::pressure);
  for (const auto& probe : probes_) {
    switch (probe.spec.type) {
      case ProbeType::pressure: {
        // Kernel-weighted average (re = 2.1 dp) of the fluid and wall pressures around the point.
        const Real re = 2.1 * dp_;
        Real sw = 0, swp = 0;
        for (std::size_t i = 0; has_pressure && i < p.n_owned(); ++i) {
          if (p.kind[i] != ParticleKind::fluid && p.kind[i] != ParticleKind::wall) continue;
          const Real w = weight((p.position[i] - probe.spec.position).norm(), re);
          sw += w;
          swp += w * p.scalar_field(fluid_fields::pressure)[i];
        }
        sums.push_back(sw);
        sums.push_back(swp);
        break;
      }
      case ProbeType::surge_front:  // largest x of the fluid within 2 dp of the floor (the probe's height)
        maxima.push_back(fluid_extent(p, 0, up, probe.spec.position[up] + 2 * dp_));
        break;
      case ProbeType::column_height:  // largest height of the fluid within 2 dp of the back wall (probe x)
        maxima.push_back(fluid_extent(p, up, 0, probe.spec.position[0] + 2 * dp_));
        break;
      case ProbeType::wave_gauge:  // the fluid's top at the probe's horizontal position
        maxima.push_back(fluid_top(p, probe.spec.position, dp_));
        break;
      case ProbeType::displacement: {
        // Global: x - x0. Tank frame (the tank at rest at t = 0): R(-theta)(x - pivot) - (x0 - pivot).
        Vec d = Vec::Constant(lowest);
        const bool tank_frame = probe.spec.frame == ProbeFrame::tank;
        const Real theta = tank_frame ? tank_.angle(t) : 0;
        const LocalIndex i = p.local_index(probe.particle);
        if (i >= 0 && static_cast<std::size_t>(i) < p.n_owned()) {
          const Vec x = p.position[static_cast<std::size_t>(i)];
          d = tank_frame ? Vec(tank_.to_tank_frame(x, theta) - (probe.initial - tank_.pivot())) : Vec(x - probe.initial);
        }
        for (int a = 0; a < dim; ++a) maxima.push_back(d[a]);
        break;
      }
    }
  }
  int size = 1;
  MPI_Comm_size(comm, &size);
  if (size > 1) {
    MPI_Allreduce(MPI_IN_PLACE, sums.data(), static_cast<int>(sums.size()), MPI_DOUBLE, MPI_SUM, comm);
    MPI_Allreduce(MPI_IN_PLACE, maxima.data(), static_cast<int>(maxima.size()), MPI_DOUBLE, MPI_MAX, comm);
  }
  std::vector<Real> values;
  std::size_t ks = 0, km = 0;
  for (const auto& probe : probes_) {
    switch (probe.spec.type) {
      case ProbeType::pressure:
        values.push_back(sums[ks] > 0 ? sums[ks + 1] / sums[ks] : 0.0);
        ks += 2;
        break;
      case ProbeType::surge_front:
      case ProbeType::column_height:  // to the fluid's outer edge: half a particle further
        values.push_back(maxima[km++] + 0.5 * dp_);
        break;
      case ProbeType::wave_gauge: {  // to the fluid's top edge; dry (no fluid in the column): the probe's height
        const Real top = maxima[km++];
        values.push_back(top == lowest ? probe.spec.position[up] : top + 0.5 * dp_);
        break;
      }
      case ProbeType::displacement:
        for (int c = 0; c < dim; ++c, ++km)
          values.push_back(maxima[km] == lowest ? std::numeric_limits<Real>::quiet_NaN() : maxima[km]);
        break;
    }
  }
  return values;
}

void ProbeWriter::record(const Real t, const std::vector<Real>& values) {
  if (probes_.empty() || !out_.is_open()) return;
  out_ << fmt::format("{:.9g}", t);
  for (const Real v : values) out_ << fmt::format(",{:.9g}", v);
  out_ << "\n";
  out_.flush();
  check_written(out_, path_, "probe table");
}

}  // namespace mpsfsi
