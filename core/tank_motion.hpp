// Prescribed rigid roll of a tank about a pivot (seed 004 §5.4): the angle theta(t) [rad, counter-
// clockwise positive] and angular velocity omega(t) [rad/s] of a sine roll or of a measured angle series
// (a table of time, angle). The fluid moves its walls with it, the solid its clamped particles, and the
// probes use it to express displacements in the tank's frame. Knows nothing of case files:
// make_tank_motion() below builds it from the case's TankMotionSpec (filled by io/case_file.cpp). In 3D the tank
// rolls about the line through the pivot along TankMotionParams::axis (default e_z; theta and omega stay
// scalars, right-handed about the axis). With z up a roll axis is horizontal: -e_y rolls the x-z section
// exactly as the 2D tank rolls in the x-y plane. Also holds the reader of time tables (read_time_table),
// which the case parser uses for every table a case names.
#pragma once

#include "core/rotation.hpp"
#include "core/types.hpp"

#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace mpsfsi {

struct TankMotionParams {
  enum class Type { none, sine_roll, table };
  Type type = Type::none;
  Vec pivot = Vec::Zero();    ///< rotation centre [m]
#if MPSFSI_DIM == 3
  Vec axis = Vec::UnitZ();    ///< 3D: roll axis through the pivot (normalised when used)
#endif
  Real amplitude = 0;         ///< sine_roll: amplitude [rad]
  Real period = 1;            ///< sine_roll: period [s]
  std::vector<Real> time;     ///< table: sample times [s], strictly increasing
  std::vector<Real> angle;    ///< table: angles [rad] at those times
  /// table: omega(t) = (theta(t + h) - theta(t - h)) / 2h on the linear interpolant (a centred difference
  /// over a window of 2h, i.e. the exact derivative of theta averaged over [t - h, t + h]); h [s].
  Real derivative_half_window = 0.025;
};

/// A table of time [s] and one value per row, as read by read_time_table.
struct TimeTable {
  std::vector<Real> time, value;
};

/// A measured series: values at increasing times and, between them, their linear interpolant. value(t) is the
/// first value before the first time and the last after the last. rate(t) is the centred difference
/// (value(t + h) - value(t - h)) / 2h over the interpolant, i.e. its exact derivative averaged over [t - h, t + h]
/// (the window clipped to the table; zero outside it). The tank's measured roll and the walls' motion tables use it.
class TableSeries {
 public:
  TableSeries() = default;
  /// Throws std::invalid_argument for fewer than two rows, unequal columns, times that do not increase, or a
  /// half window h that is not positive.
  TableSeries(std::vector<Real> time, std::vector<Real> value, Real half_window);
  bool empty() const { return time_.empty(); }
  Real value(Real t) const;
  Real rate(Real t) const;
  Real first_time() const { return time_.front(); }
  Real last_time() const { return time_.back(); }
  /// The largest |rate| of the interpolant, max_k |v_k+1 - v_k| / (t_k+1 - t_k) (rate(t) never exceeds it).
  Real largest_rate() const;

 private:
  std::vector<Real> time_, value_;
  Real half_window_ = 0;
};

/// What read_time_table accepts in the value column.
struct TimeTableColumn {
  std::string name = "value";                           ///< for messages, e.g. "angle [deg]"
  Real bound = std::numeric_limits<Real>::infinity();  ///< values must have |value| < bound
  std::string form = "a number";                        ///< the allowed values, for messages
};

/// An unreadable or malformed table file; the message names the file (and the line) and the expected form.
class TableError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Largest table file read, and most rows (a measured series at 1 kHz for over 15 minutes fits both).
constexpr std::uintmax_t max_table_bytes = 16u << 20;
constexpr std::size_t max_table_rows = 1000000;

/// Reads the one table format of the case files (tank_motion.file, sources[].wavelet.file, the walls' motion
/// tables): CSV (or
/// whitespace-separated) rows of time [s], value; '#' comments, empty lines and one header line before the
/// data are skipped; every other line must be two plain decimal numbers. At least two rows, times strictly
/// increasing. Throws TableError for a missing or non-regular file (a FIFO or device would block or never
/// end), a file over max_table_bytes or max_table_rows, a bad row, a value outside `column`, or times that
/// do not increase.
TimeTable read_time_table(const std::string& path, const TimeTableColumn& column = {});

/// The column of a tank-motion table: angles in degrees within (-90, 90) (as a sine roll's amplitude).
TimeTableColumn angle_table_column();

/// Reads a tank-motion table (read_time_table with angle_table_column) into params.time / params.angle,
/// the angles converted to radians. Throws TableError.
void read_angle_table(const std::string& path, TankMotionParams& params);

enum class TankMotionType { none, sine_roll, table };

/// The tank motion as the case file gives it (key `tank_motion`, filled and checked by io/case_file.cpp).
struct TankMotionSpec {
  TankMotionType type = TankMotionType::none;
  Vec pivot = Vec::Zero();      ///< rotation centre [m]
#if MPSFSI_DIM == 3
  Vec axis = Vec::UnitZ();      ///< 3D: roll axis through the pivot, normalised (tank_motion.axis)
#endif
  Real amplitude = 0;           ///< sine_roll: amplitude [rad] (case file in degrees)
  Real period = 1;              ///< sine_roll: period [s]
  std::string file;             ///< table: CSV of time [s], angle [deg], resolved relative to the case file
  std::vector<Real> time;       ///< table: the rows read from `file` when the case was parsed, times [s] ...
  std::vector<Real> angle;      ///< ... and angles [rad]
};

class TankMotion {
 public:
  /// No motion: theta = omega = 0.
  TankMotion() = default;
  /// Throws std::invalid_argument for a table with fewer than two rows, unequal columns, times that
  /// do not increase, or a non-positive period / half window.
  explicit TankMotion(TankMotionParams params);

  bool moving() const { return params_.type != TankMotionParams::Type::none; }
  const Vec& pivot() const { return params_.pivot; }
  const TankMotionParams& params() const { return params_; }

  /// theta(t) [rad]. sine_roll: A sin(2 pi t / T). table: linear interpolation; before the first row the
  /// first angle, after the last row the last angle (the tank stops).
  Real angle(Real t) const;
  /// omega(t) = d theta / dt [rad/s]. sine_roll: exact. table: centred difference over [t - h, t + h]
  /// (clipped to the table; zero before the first and after the last row).
  Real angular_velocity(Real t) const;
  /// {theta(t), omega(t)}.
  std::pair<Real, Real> at(Real t) const { return {angle(t), angular_velocity(t)}; }
  /// Last time of a table (the motion stops afterwards); +inf for sine_roll and none.
  Real end_time() const;

#if MPSFSI_DIM == 2
  /// 2D: the plane rotation matrix R(theta) (3D: use matrix(theta), which knows the roll axis).
  static Mat rotation(Real theta);
#endif
  /// Rotation matrix R(theta) about the roll axis.
  Mat matrix(Real theta) const;
  /// The tank's rotation at angle theta (about e_z in 2D, the roll axis in 3D).
  Rotation rotation_at(Real theta) const;
  /// The angular velocity omega e of the tank at rate omega (e = e_z in 2D, the roll axis in 3D).
  Angular spin(Real omega) const;
  /// Where a point x0 of the tank at rest is at angle theta: pivot + R(theta) (x0 - pivot).
  Vec place(const Vec& x0, Real theta) const;
  /// Velocity of the tank point now at x, rotating with omega about the pivot: omega e x (x - pivot),
  /// e = e_z in 2D, the roll axis in 3D.
  Vec velocity_at(const Vec& x, Real omega) const;
  /// x (global) in the tank frame at angle theta, relative to the pivot: R(-theta) (x - pivot).
  Vec to_tank_frame(const Vec& x, Real theta) const;

 private:
  TankMotionParams params_;
  TableSeries table_;  ///< table: params_.time and params_.angle
};

/// The tank motion of a case; a table is the one read and checked when the case was parsed.
inline TankMotion make_tank_motion(const TankMotionSpec& spec) {
  TankMotionParams q;
  q.pivot = spec.pivot;
#if MPSFSI_DIM == 3
  q.axis = spec.axis;
#endif
  switch (spec.type) {
    case TankMotionType::none: return TankMotion();
    case TankMotionType::sine_roll:
      q.type = TankMotionParams::Type::sine_roll;
      q.amplitude = spec.amplitude;
      q.period = spec.period;
      break;
    case TankMotionType::table:
      q.type = TankMotionParams::Type::table;
      q.time = spec.time;
      q.angle = spec.angle;
      break;
  }
  return TankMotion(std::move(q));
}

}  // namespace mpsfsi
