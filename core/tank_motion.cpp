// Prescribed tank roll: sine or measured angle table (TableSeries: linear interpolation, centred-difference omega);
// rigid rotation about the pivot (about the z axis through the pivot in 3D) with core/rotation.hpp; the
// reader of the case files' time tables (tank motion, wavelets).
#include "core/tank_motion.hpp"

#include "core/rotation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace mpsfsi {

namespace {

std::string trimmed(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

/// A plain decimal number ([+-]digits[.digits][e[+-]digits], as in the case files): no hex, inf or nan;
/// finite after conversion.
std::optional<Real> decimal(const std::string& s) {
  if (s.empty() || s.find_first_not_of("0123456789+-.eE") != std::string::npos) return std::nullopt;
  if (s.find_first_of("0123456789") == std::string::npos) return std::nullopt;
  char* end = nullptr;
  const Real value = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || !std::isfinite(value)) return std::nullopt;
  return value;
}

/// A line of the file as shown in messages: printable ASCII (anything else as '?'), at most 60 characters.
std::string shown(const std::string& line) {
  std::string out = line.size() > 60 ? line.substr(0, 57) + "..." : line;
  for (auto& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return out;
}

std::string g(const Real x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

}  // namespace

TimeTable read_time_table(const std::string& path, const TimeTableColumn& column) {
  namespace fs = std::filesystem;
  const std::string form = "a CSV file of time [s], " + column.name;
  const auto fail = [](const std::string& message) { throw TableError(message); };
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (!fs::exists(status)) fail("no such file '" + path + "'; expected " + form);
  if (!fs::is_regular_file(status))
    fail("'" + path + "' is not a regular file (" +
         (fs::is_directory(status) ? "a directory" : fs::is_fifo(status) ? "a FIFO" : "a device, socket or other special file") +
         "); expected " + form);
  const auto size = fs::file_size(path, ec);
  const std::string size_form = "expected a table file of at most " + std::to_string(max_table_bytes >> 20) + " MiB";
  if (!ec && size > max_table_bytes) fail("'" + path + "' has " + std::to_string(size) + " bytes; " + size_form);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail("cannot read '" + path + "'; expected " + form);

  TimeTable table;
  std::string line;
  std::uintmax_t bytes = 0;  // read so far: a file may grow while it is read
  std::size_t line_no = 0;
  bool header_allowed = true;
  while (std::getline(in, line)) {
    ++line_no;
    bytes += line.size() + 1;
    if (bytes > max_table_bytes + 1) fail("'" + path + "' has more than " + std::to_string(max_table_bytes) + " bytes; " + size_form);
    const std::string at = path + ":" + std::to_string(line_no) + ": ";
    std::string row = trimmed(line.substr(0, line.find('#')));
    if (row.empty()) continue;
    std::replace(row.begin(), row.end(), ',', ' ');
    std::istringstream ls(row);
    std::string a, b, extra;
    ls >> a >> b;
    const auto time = decimal(a), value = decimal(b);
    if (!time || !value || static_cast<bool>(ls >> extra)) {
      if (header_allowed && !time) {
        header_allowed = false;
        continue;
      }
      fail(at + "'" + shown(trimmed(line)) + "': expected a row of two numbers: time [s], " + column.name);
    }
    header_allowed = false;
    if (!(std::abs(*value) < column.bound)) fail(at + column.name + " = " + g(*value) + ": expected " + column.form);
    if (!table.time.empty() && !(*time > table.time.back()))
      fail(at + "time " + g(*time) + " s: expected times that increase strictly");
    if (table.time.size() == max_table_rows)
      fail(at + "more than " + std::to_string(max_table_rows) + " rows; expected at most " +
           std::to_string(max_table_rows) + " rows of time [s], " + column.name);
    table.time.push_back(*time);
    table.value.push_back(*value);
  }
  if (in.bad()) fail("cannot read '" + path + "'; expected " + form);
  if (table.time.size() < 2)
    fail("'" + path + "' has " + std::to_string(table.time.size()) + " row(s); expected at least two rows of time [s], " +
         column.name);
  return table;
}

TimeTableColumn angle_table_column() { return {"angle [deg]", 90, "an angle in (-90, 90) degrees"}; }

void read_angle_table(const std::string& path, TankMotionParams& params) {
  TimeTable table = read_time_table(path, angle_table_column());
  params.time = std::move(table.time);
  params.angle = std::move(table.value);
  for (auto& a : params.angle) a *= pi / 180;
}

TableSeries::TableSeries(std::vector<Real> time, std::vector<Real> value, const Real half_window)
    : time_(std::move(time)), value_(std::move(value)), half_window_(half_window) {
  if (time_.size() < 2 || value_.size() != time_.size())
    throw std::invalid_argument("a table needs at least two rows and as many values as times");
  for (std::size_t k = 1; k < time_.size(); ++k)
    if (!(time_[k] > time_[k - 1])) throw std::invalid_argument("table times must increase");
  if (!(half_window_ > 0)) throw std::invalid_argument("the half window must be positive");
}

Real TableSeries::value(const Real t) const {
  if (t <= time_.front()) return value_.front();
  if (t >= time_.back()) return value_.back();
  const auto k = static_cast<std::size_t>(std::upper_bound(time_.begin(), time_.end(), t) - time_.begin()) - 1;
  const Real s = (t - time_[k]) / (time_[k + 1] - time_[k]);
  return value_[k] + s * (value_[k + 1] - value_[k]);
}

Real TableSeries::rate(const Real t) const {
  if (empty() || t < time_.front() || t > time_.back()) return 0;
  const Real lo = std::max(t - half_window_, time_.front()), hi = std::min(t + half_window_, time_.back());
  if (!(hi > lo)) return 0;
  return (value(hi) - value(lo)) / (hi - lo);
}

Real TableSeries::largest_rate() const {
  Real largest = 0;
  for (std::size_t k = 1; k < time_.size(); ++k)
    largest = std::max(largest, std::abs(value_[k] - value_[k - 1]) / (time_[k] - time_[k - 1]));
  return largest;
}

TankMotion::TankMotion(TankMotionParams params) : params_(std::move(params)) {
  using Type = TankMotionParams::Type;
  if (params_.type == Type::sine_roll && !(params_.period > 0))
    throw std::invalid_argument("TankMotion: sine_roll needs a positive period");
  if (params_.type != Type::table) return;
  try {
    table_ = TableSeries(params_.time, params_.angle, params_.derivative_half_window);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("TankMotion: ") + e.what());
  }
}

Real TankMotion::angle(const Real t) const {
  switch (params_.type) {
    case TankMotionParams::Type::sine_roll: return params_.amplitude * std::sin(2 * pi * t / params_.period);
    case TankMotionParams::Type::table: return table_.value(t);
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
    case TankMotionParams::Type::table: return table_.rate(t);
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

#if MPSFSI_DIM == 2
Rotation TankMotion::rotation_at(const Real theta) const { return Rotation(theta); }
Angular TankMotion::spin(const Real omega) const { return omega; }
#else
Rotation TankMotion::rotation_at(const Real theta) const { return Rotation::about_axis(params_.axis, theta); }
Angular TankMotion::spin(const Real omega) const { return omega * params_.axis.normalized(); }
#endif

Vec TankMotion::place(const Vec& x0, const Real theta) const { return params_.pivot + matrix(theta) * (x0 - params_.pivot); }

Vec TankMotion::to_tank_frame(const Vec& x, const Real theta) const {
  return matrix(-theta) * (x - params_.pivot);
}

}  // namespace mpsfsi
