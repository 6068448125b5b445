// The accelerations of an implicit coupling's iterations: constant relaxation, Aitken, IQN-ILS (acceleration.hpp).
#include "coupling/acceleration.hpp"

#include "core/binary_io.hpp"
#include "core/collectives.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace mpsfsi {

void Acceleration::save_state(BinaryWriter& out) const {
  out.section("acceleration");
  out.string(name());
}

void Acceleration::load_state(BinaryReader& in, const std::vector<GlobalId>&) {
  in.expect_section("acceleration");
  const std::string got = in.string("the acceleration");
  if (got != name()) in.fail("the checkpoint's acceleration is " + got + ", this run's " + name());
  iteration_ = 0;
}

Real global_dot(const DataVector& a, const DataVector& b, MPI_Comm comm) {
  Real d = a.dot(b);
  MPI_Allreduce(MPI_IN_PLACE, &d, 1, MPI_DOUBLE, MPI_SUM, comm);
  return d;
}

Real relative_residual(const DataVector& x, const DataVector& hx, const Real floor, MPI_Comm comm) {
  Real sums[2] = {(hx - x).squaredNorm(), hx.squaredNorm()};
  MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_DOUBLE, MPI_SUM, comm);
  const Real scale = std::max(std::sqrt(sums[1]), floor);
  if (!(scale > 0)) return sums[0] > 0 ? std::numeric_limits<Real>::infinity() : 0.0;
  return std::sqrt(sums[0]) / scale;
}

namespace {

/// Throws std::logic_error unless x and hx hold width values per id.
void check_sizes(const char* who, const std::vector<GlobalId>& ids, const DataVector& x, const DataVector& hx, const int width) {
  const auto n = static_cast<Eigen::Index>(ids.size()) * width;
  if (x.size() != n || hx.size() != n)
    throw std::logic_error(std::string(who) + ": x and H(x) must hold " + std::to_string(width) +
                           " values per interface id (" + std::to_string(n) + "), got " + std::to_string(x.size()) +
                           " and " + std::to_string(hx.size()));
}

class ConstantRelaxation : public Acceleration {
 public:
  ConstantRelaxation(const AccelerationParameters& parameters, const int width) : omega_(parameters.relaxation), width_(width) {}

  DataVector next(const std::vector<GlobalId>& ids, const DataVector& x, const DataVector& hx) override {
    check_sizes("constant relaxation", ids, x, hx, width_);
    ++iteration_;
    return x + omega_ * (hx - x);
  }
  void end_window() override { iteration_ = 0; }
  std::string name() const override { return "constant"; }

 private:
  Real omega_;
  int width_;
};

class AitkenRelaxation : public Acceleration {
 public:
  AitkenRelaxation(const AccelerationParameters& parameters, const int width, MPI_Comm comm)
      : initial_(parameters.relaxation), omega_(parameters.relaxation), width_(width), comm_(comm) {}

  DataVector next(const std::vector<GlobalId>& ids, const DataVector& x, const DataVector& hx) override {
    check_sizes("Aitken relaxation", ids, x, hx, width_);
    DataVector r = hx - x;
    if (iteration_ == 0) {
      omega_ = std::copysign(std::min(initial_, std::abs(omega_)), omega_);
    } else {
      if (r.size() != last_r_.size()) throw std::logic_error("Aitken relaxation: the interface changed within a window");
      const DataVector dr = r - last_r_;
      Real sums[2] = {last_r_.dot(dr), dr.squaredNorm()};
      MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_DOUBLE, MPI_SUM, comm_);
      if (sums[1] > 0) omega_ = -omega_ * sums[0] / sums[1];  // Kuttler & Wall 2008, eq. 44
    }
    last_r_ = std::move(r);
    ++iteration_;
    return x + omega_ * last_r_;
  }
  void end_window() override { iteration_ = 0; }
  std::string name() const override { return "aitken"; }
  void save_state(BinaryWriter& out) const override {
    Acceleration::save_state(out);
    out.f64(omega_);
  }
  void load_state(BinaryReader& in, const std::vector<GlobalId>& ids) override {
    Acceleration::load_state(in, ids);
    omega_ = in.f64("Aitken's factor");
  }

 private:
  Real initial_, omega_;
  int width_;
  MPI_Comm comm_;
  DataVector last_r_;
};

}  // namespace

IqnIlsAcceleration::IqnIlsAcceleration(const AccelerationParameters& parameters, const int width, MPI_Comm comm)
    : parameters_(parameters), width_(width), comm_(comm) {}

int IqnIlsAcceleration::columns() const {
  std::size_t n = current_.v.size();
  for (const Window& w : past_) n += w.v.size();
  return static_cast<int>(std::min<std::size_t>(n, static_cast<std::size_t>(parameters_.max_columns)));
}

void IqnIlsAcceleration::check_ids(const std::vector<GlobalId>& ids) {
  int changed = ids != ids_ ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_MAX, comm_);
  if (!changed) return;
  for (const Window& w : past_) dropped_by_ids_ += static_cast<long>(w.v.size());
  past_.clear();
  ids_ = ids;
}

DataVector IqnIlsAcceleration::next(const std::vector<GlobalId>& ids, const DataVector& x, const DataVector& hx) {
  check_sizes("IQN-ILS", ids, x, hx, width_);
  if (iteration_ == 0)
    check_ids(ids);
  else if (ids != ids_)
    throw std::logic_error("IQN-ILS: the interface's ids changed within a window");
  DataVector r = hx - x;
  if (iteration_ > 0) {
    current_.v.insert(current_.v.begin(), r - last_r_);
    current_.w.insert(current_.w.begin(), hx - last_hx_);
  }
  last_r_ = r;
  last_hx_ = hx;
  ++iteration_;
  if (columns() == 0) return x + parameters_.relaxation * r;
  return hx + quasi_newton_update(r);
}

DataVector IqnIlsAcceleration::quasi_newton_update(const DataVector& r) {
  // The columns, newest first: this window's, then the kept windows' in order.
  std::vector<const DataVector*> v, w;
  const auto take = [&](const Window& win) {
    for (std::size_t q = 0; q < win.v.size() && static_cast<int>(v.size()) < parameters_.max_columns; ++q) {
      v.push_back(&win.v[q]);
      w.push_back(&win.w[q]);
    }
  };
  take(current_);
  for (const Window& win : past_) take(win);
  const auto m = static_cast<Eigen::Index>(v.size());
  // V^T V and V^T r, reduced over the ranks in one message.
  Eigen::MatrixXd gram(m, m);
  DataVector vr(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    vr(i) = v[static_cast<std::size_t>(i)]->dot(r);
    for (Eigen::Index j = 0; j <= i; ++j) gram(i, j) = v[static_cast<std::size_t>(i)]->dot(*v[static_cast<std::size_t>(j)]);
  }
  std::vector<Real> buffer(static_cast<std::size_t>(m * (m + 1) / 2 + m));
  std::size_t e = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    buffer[e++] = vr(i);
    for (Eigen::Index j = 0; j <= i; ++j) buffer[e++] = gram(i, j);
  }
  MPI_Allreduce(MPI_IN_PLACE, buffer.data(), static_cast<int>(buffer.size()), MPI_DOUBLE, MPI_SUM, comm_);
  e = 0;
  for (Eigen::Index i = 0; i < m; ++i) {
    vr(i) = buffer[e++];
    for (Eigen::Index j = 0; j <= i; ++j) gram(i, j) = gram(j, i) = buffer[e++];
  }
  // The filter, column by column from the newest: the squared norm of a column's part orthogonal to the
  // accepted ones is its pivot in the Cholesky factor of the accepted columns' Gram matrix (= R_ii^2 of V's QR).
  const Real limit = std::max(parameters_.filter * parameters_.filter, 1e-14);
  std::vector<Eigen::Index> kept;
  Eigen::MatrixXd chol(m, m);  // lower factor of the kept columns' Gram matrix, kept.size() square in use
  for (Eigen::Index i = 0; i < m; ++i) {
    const Real norm2 = gram(i, i);
    if (!(norm2 > 0)) continue;
    const auto k = static_cast<Eigen::Index>(kept.size());
    DataVector g(k);
    for (Eigen::Index a = 0; a < k; ++a) g(a) = gram(kept[static_cast<std::size_t>(a)], i);
    const DataVector y = chol.topLeftCorner(k, k).triangularView<Eigen::Lower>().solve(g);
    const Real pivot = norm2 - y.squaredNorm();
    if (pivot < limit * norm2) continue;
    chol.block(k, 0, 1, k) = y.transpose();
    chol(k, k) = std::sqrt(pivot);
    kept.push_back(i);
  }
  filtered_ = static_cast<int>(m) - static_cast<int>(kept.size());
  const auto k = static_cast<Eigen::Index>(kept.size());
  DataVector b(k);
  for (Eigen::Index a = 0; a < k; ++a) b(a) = -vr(kept[static_cast<std::size_t>(a)]);
  const auto factor = chol.topLeftCorner(k, k).triangularView<Eigen::Lower>();
  const DataVector c = factor.transpose().solve(factor.solve(b));  // (V^T V) c = -V^T r over the kept columns
  DataVector update = DataVector::Zero(r.size());
  for (Eigen::Index a = 0; a < k; ++a) update += c(a) * *w[static_cast<std::size_t>(kept[static_cast<std::size_t>(a)])];
  return update;
}

void IqnIlsAcceleration::end_window() {
  if (!current_.v.empty()) past_.push_front(std::move(current_));
  current_ = Window{};
  while (past_.size() > static_cast<std::size_t>(parameters_.reuse)) past_.pop_back();
  iteration_ = 0;
}

void IqnIlsAcceleration::save_state(BinaryWriter& out) const {
  if (iteration_ != 0) throw std::logic_error("IQN-ILS: save_state within a window");
  Acceleration::save_state(out);
  std::vector<std::int64_t> mine(ids_.begin(), ids_.end());
  out.array(all_gather(comm_, mine));
  out.u64(past_.size());
  for (const Window& win : past_) {
    out.u64(win.v.size());
    for (const auto* columns : {&win.v, &win.w})
      for (const DataVector& col : *columns)
        out.array(all_gather(comm_, std::vector<double>(col.data(), col.data() + col.size())));
  }
  out.i64(dropped_by_ids_);
}

void IqnIlsAcceleration::load_state(BinaryReader& in, const std::vector<GlobalId>& ids) {
  Acceleration::load_state(in, ids);
  const std::vector<std::int64_t> all_ids = in.array<std::int64_t>("the IQN-ILS interface ids");
  std::unordered_map<GlobalId, std::size_t> row_of;
  for (std::size_t r = 0; r < all_ids.size(); ++r) row_of[static_cast<GlobalId>(all_ids[r])] = r;
  bool mapped = true;
  std::vector<std::size_t> rows;
  for (const GlobalId id : ids) {
    const auto it = row_of.find(id);
    mapped = mapped && it != row_of.end();
    rows.push_back(it == row_of.end() ? 0 : it->second);
  }
  const std::size_t n_windows = in.u64("the IQN-ILS windows");
  std::deque<Window> past;
  const auto w = static_cast<std::size_t>(width_);
  for (std::size_t k = 0; k < n_windows; ++k) {
    const std::size_t n_columns = in.u64("the IQN-ILS columns");
    Window win;
    for (auto* columns : {&win.v, &win.w})
      for (std::size_t q = 0; q < n_columns; ++q) {
        const std::vector<double> all = in.array<double>("an IQN-ILS column", all_ids.size() * w);
        DataVector col(static_cast<Eigen::Index>(ids.size() * w));
        for (std::size_t i = 0; i < ids.size(); ++i)
          for (std::size_t a = 0; a < w; ++a) col(static_cast<Eigen::Index>(i * w + a)) = all[rows[i] * w + a];
        columns->push_back(std::move(col));
      }
    past.push_back(std::move(win));
  }
  dropped_by_ids_ = in.i64("the dropped-column count");
  int all_mapped = mapped ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &all_mapped, 1, MPI_INT, MPI_MIN, comm_);
  current_ = Window{};
  past_ = all_mapped ? std::move(past) : std::deque<Window>{};
  ids_ = ids;
}

std::unique_ptr<Acceleration> make_acceleration(const AccelerationParameters& parameters, const int width, MPI_Comm comm) {
  if (!(parameters.relaxation > 0 && parameters.relaxation <= 1))
    throw std::invalid_argument("acceleration: relaxation must lie in (0, 1], got " + std::to_string(parameters.relaxation));
  if (parameters.reuse < 0) throw std::invalid_argument("acceleration: reuse must be >= 0");
  if (parameters.max_columns < 1) throw std::invalid_argument("acceleration: max_columns must be >= 1");
  if (!(parameters.filter >= 0 && parameters.filter < 1)) throw std::invalid_argument("acceleration: filter must lie in [0, 1)");
  if (width < 1) throw std::invalid_argument("acceleration: width must be >= 1");
  switch (parameters.kind) {
    case AccelerationKind::constant:
      return std::make_unique<ConstantRelaxation>(parameters, width);
    case AccelerationKind::aitken:
      return std::make_unique<AitkenRelaxation>(parameters, width, comm);
    case AccelerationKind::iqn_ils:
      return std::make_unique<IqnIlsAcceleration>(parameters, width, comm);
  }
  throw std::invalid_argument("acceleration: unknown kind");
}

}  // namespace mpsfsi
