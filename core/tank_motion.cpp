// Prescribed tank roll: sine or measured angle table (linear interpolation, centred-difference omega);
// rigid rotation about the pivot (about the z axis through the pivot in 3D) with core/rotation.hpp.
#include "core/tank_motion.hpp"

#include "core/rotation.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace mpsfsi {

void read_angle_table(const std::string& path, TankMotionParams& params) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("tank_motion: cannot read " + path);
  params.time.clear();
  params.angle.clear();
  std::string line;
  while (std::getline(in, line)) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ls(line);
    Real t = 0, deg = 0;
    if (ls >> t >> deg) {
      params.time.push_back(t);
      params.angle.push_back(deg * pi / 180);
    }
  }
  if (params.time.size() < 2) throw std::runtime_error("tank_motion: " + path + " needs at least two rows of time, angle");
  for (std::size_t k = 1; k < params.time.size(); ++k)
    if (!(params.time[k] > params.time[k - 1]))
      throw std::runtime_error("tank_motion: " + path + ": times must increase (row " + std::to_string(k + 1) + ")");
}

TankMotion::TankMotion(TankMotionParams params) : params_(std::move(params)) {
  using Type = TankMotionParams::Type;
  if (params_.type == Type::sine_roll && !(params_.period > 0))
    throw std::invalid_argument("TankMotion: sine_roll needs a positive period");
  if (params_.type != Type::table) return;
  const auto& t = params_.time;
  if (t.size() < 2 || params_.angle.size() != t.size())
    throw std::invalid_argument("TankMotion: a table needs at least two rows and as many angles as times");
  for (std::size_t k = 1; k < t.size(); ++k)
    if (!(t[k] > t[k - 1])) throw std::invalid_argument("TankMotion: table times must increase");
  if (!(params_.derivative_half_window > 0)) throw std::invalid_argument("TankMotion: the half window must be positive");
}

Real TankMotion::interpolate(const Real t) const {
  const auto& ts = params_.time;
  const auto& a = params_.angle;
  if (t <= ts.front()) return a.front();
  if (t >= ts.back()) return a.back();
  const auto k = static_cast<std::size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin()) - 1;
  const Real s = (t - ts[k]) / (ts[k + 1] - ts[k]);
  return a[k] + s * (a[k + 1] - a[k]);
}

Real TankMotion::angle(const Real t) const {
  switch (params_.type) {
    case TankMotionParams::Type::sine_roll: return params_.amplitude * std::sin(2 * pi * t / params_.period);
    case TankMotionParams::Type::table: return interpolate(t);
    case TankMotionParams::Type::none: break;
  }
  return 0;
}

Real TankMotion::angular_velocity(const Real t) const {
  switch (params_.type) {
    case TankMotionParams::Type::sine_roll: {
      const Real w = 2 * pi / params_.period;
      return params_.amplitude * w * std::cos(w * t);
    }
    case TankMotionParams::Type::table: {
      const auto& ts = params_.time;
      if (t < ts.front() || t > ts.back()) return 0;
      const Real h = params_.derivative_half_window;
      const Real lo = std::max(t - h, ts.front()), hi = std::min(t + h, ts.back());
      if (!(hi > lo)) return 0;
      return (interpolate(hi) - interpolate(lo)) / (hi - lo);
    }
    case TankMotionParams::Type::none: break;
  }
  return 0;
}

Real TankMotion::end_time() const {
  return params_.type == TankMotionParams::Type::table ? params_.time.back() : std::numeric_limits<Real>::infinity();
}

#if MPSFSI_DIM == 2
Mat TankMotion::rotation(const Real theta) { return Rotation::about_z(theta).matrix(); }
Vec TankMotion::velocity_at(const Vec& x, const Real omega) const { return cross(about_z(omega), Vec(x - params_.pivot)); }
Mat TankMotion::matrix(const Real theta) const { return rotation(theta); }
#else
Mat TankMotion::matrix(const Real theta) const { return Rotation::about_axis(params_.axis, theta).matrix(); }
Vec TankMotion::velocity_at(const Vec& x, const Real omega) const {
  return cross(Vec(omega * params_.axis.normalized()), Vec(x - params_.pivot));
}
#endif

Vec TankMotion::place(const Vec& x0, const Real theta) const { return params_.pivot + matrix(theta) * (x0 - params_.pivot); }

Vec TankMotion::to_tank_frame(const Vec& x, const Real theta) const {
  return matrix(-theta) * (x - params_.pivot);
}

}  // namespace mpsfsi
