// The accelerations of the implicit coupling (coupling/acceleration.hpp) on fixed-point problems with known
// answers: a scalar linear map (Aitken's secant is exact after two iterations), a linear map on 12 values
// whose plain iteration diverges (IQN-ILS converges within n + 2 evaluations, like GMRES; the same on 1 to 4
// ranks as on one), windows that reuse columns, and the filter. Runs on 1 to 4 ranks (ctest acceleration_np*).
#include "core/binary_io.hpp"
#include "core/collectives.hpp"
#include "coupling/acceleration.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <Eigen/Dense>

#include <cmath>
#include <stdexcept>
#include <vector>

using namespace mpsfsi;

namespace {

/// H(x) = A x + b on n values, rank r of R holding the ids [r n / R, (r + 1) n / R).
struct LinearMap {
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  MPI_Comm comm;

  long n() const { return static_cast<long>(b.size()); }
  long begin() const { return n() * rank_of(comm) / size_of(comm); }
  long end() const { return n() * (rank_of(comm) + 1) / size_of(comm); }
  std::vector<GlobalId> ids() const {
    std::vector<GlobalId> v;
    for (long i = begin(); i < end(); ++i) v.push_back(i);
    return v;
  }
  DataVector slice(const Eigen::VectorXd& full) const { return full.segment(begin(), end() - begin()); }
  DataVector apply(const DataVector& x) const {
    const std::vector<double> all = all_gather(comm, std::vector<double>(x.data(), x.data() + x.size()));
    const Eigen::VectorXd full = Eigen::Map<const Eigen::VectorXd>(all.data(), static_cast<Eigen::Index>(all.size()));
    return slice(a * full + b);
  }
  Eigen::VectorXd fixed_point() const {
    return (Eigen::MatrixXd::Identity(n(), n()) - a).fullPivLu().solve(b);
  }
};

/// A 12 x 12 map whose plain iteration diverges: A not symmetric, its eigenvalues spread around -0.5 to -4
/// (mass ratios 0.5 to 4 of an added-mass problem's modes), which one relaxation factor cannot all damp.
LinearMap divergent_map(MPI_Comm comm, const Real shift = 0) {
  const int n = 12;
  LinearMap m{Eigen::MatrixXd::Zero(n, n), Eigen::VectorXd::Zero(n), comm};
  for (int i = 0; i < n; ++i) {
    m.b(i) = 1.0 + 0.1 * i + shift * std::cos(i);
    for (int j = 0; j < n; ++j) m.a(i, j) = (i == j ? -0.5 - 3.5 * i / (n - 1.0) : 0.0) + 0.15 * std::sin(1.0 + i + 2.0 * j);
  }
  return m;
}

struct WindowResult {
  int iterations = 0;  ///< coupled steps run (evaluations of H)
  bool converged = false;
  DataVector x;  ///< H(x) of the converged iteration
};

/// Iterates one window from x0 until |H(x) - x| / |H(x)| < tolerance.
WindowResult iterate(Acceleration& acc, const LinearMap& map, DataVector x, const Real tolerance, const int max_iterations) {
  WindowResult res;
  for (int k = 0; k < max_iterations; ++k) {
    const DataVector hx = map.apply(x);
    ++res.iterations;
    if (relative_residual(x, hx, 0.0, map.comm) < tolerance) {
      res.converged = true;
      res.x = hx;
      break;
    }
    x = acc.next(map.ids(), x, hx);
    for (Eigen::Index i = 0; i < x.size(); ++i) EXPECT_TRUE(std::isfinite(x(i)));
  }
  acc.end_window();
  return res;
}

AccelerationParameters parameters(const AccelerationKind kind, const Real relaxation = 0.5) {
  AccelerationParameters p;
  p.kind = kind;
  p.relaxation = relaxation;
  return p;
}

}  // namespace

TEST(Acceleration, ConstantRelaxesByOmega) {
  auto acc = make_acceleration(parameters(AccelerationKind::constant, 0.25), 2, MPI_COMM_WORLD);
  DataVector x(2), hx(2);
  x << 1.0, -2.0;
  hx << 5.0, 2.0;
  const DataVector next = acc->next({7}, x, hx);
  EXPECT_EQ(next(0), 2.0);
  EXPECT_EQ(next(1), -1.0);
  EXPECT_EQ(acc->iteration(), 1);
  acc->end_window();
  EXPECT_EQ(acc->iteration(), 0);
}

TEST(Acceleration, PlainIterationOfTheTestMapDiverges) {
  // The problems below need an acceleration: relaxation 1 (no acceleration) runs away.
  const LinearMap map = divergent_map(MPI_COMM_WORLD);
  auto acc = make_acceleration(parameters(AccelerationKind::constant, 1.0), 1, MPI_COMM_WORLD);
  const WindowResult res = iterate(*acc, map, map.slice(Eigen::VectorXd::Zero(map.n())), 1e-10, 30);
  EXPECT_FALSE(res.converged);
}

TEST(Acceleration, AitkenSolvesAScalarLinearMapInThreeSteps) {
  // H(x) = -2 x + 3 on rank 0 only (the other ranks hold no entry): fixed point 1. The first iteration
  // relaxes by 0.5, the second is the secant of a linear residual and lands on 1; the third step confirms.
  LinearMap map{Eigen::MatrixXd::Constant(1, 1, -2.0), Eigen::VectorXd::Constant(1, 3.0), MPI_COMM_WORLD};
  auto acc = make_acceleration(parameters(AccelerationKind::aitken), 1, MPI_COMM_WORLD);
  const WindowResult res = iterate(*acc, map, map.slice(Eigen::VectorXd::Zero(1)), 1e-12, 10);
  EXPECT_TRUE(res.converged);
  EXPECT_EQ(res.iterations, 3);
  if (res.x.size() == 1) {
    EXPECT_NEAR(res.x(0), 1.0, 1e-14);
  }
}

TEST(Acceleration, AitkenConvergesWherePlainIterationDiverges) {
  const LinearMap map = divergent_map(MPI_COMM_WORLD);
  auto acc = make_acceleration(parameters(AccelerationKind::aitken), 1, MPI_COMM_WORLD);
  const WindowResult res = iterate(*acc, map, map.slice(Eigen::VectorXd::Zero(map.n())), 1e-10, 60);
  ASSERT_TRUE(res.converged);
  EXPECT_LE((res.x - map.slice(map.fixed_point())).lpNorm<Eigen::Infinity>(), 1e-9);
}

TEST(Acceleration, IqnIlsConvergesWithinNPlusTwoEvaluationsOnAnyRankCount) {
  // On a linear map IQN-ILS is GMRES in disguise: n + 1 evaluations of H give n columns, which make the
  // inverse Jacobian exact, and one more confirms the fixed point (n = 12). Without the filter that bound
  // holds; the default filter leaves out a nearly dependent column and may cost an evaluation. Both take far
  // fewer than Aitken, whose one factor cannot damp eigenvalues from -0.5 to -4 at once.
  const LinearMap map = divergent_map(MPI_COMM_WORLD);
  const DataVector x0 = map.slice(Eigen::VectorXd::Zero(map.n()));
  AccelerationParameters unfiltered = parameters(AccelerationKind::iqn_ils);
  unfiltered.filter = 0;
  auto exact = make_acceleration(unfiltered, 1, MPI_COMM_WORLD);
  const WindowResult plain = iterate(*exact, map, x0, 1e-10, 40);
  ASSERT_TRUE(plain.converged);
  EXPECT_LE(plain.iterations, map.n() + 2);
  auto acc = make_acceleration(parameters(AccelerationKind::iqn_ils), 1, MPI_COMM_WORLD);
  const WindowResult res = iterate(*acc, map, x0, 1e-10, 40);
  ASSERT_TRUE(res.converged);
  EXPECT_LE((res.x - map.slice(map.fixed_point())).lpNorm<Eigen::Infinity>(), 1e-9);
  auto aitken = make_acceleration(parameters(AccelerationKind::aitken), 1, MPI_COMM_WORLD);
  const WindowResult ait = iterate(*aitken, map, x0, 1e-10, 60);
  ASSERT_TRUE(ait.converged);
  EXPECT_LT(res.iterations, ait.iterations * 2 / 3);
  // The same iterations as one rank holding every value (MPI_COMM_SELF), to the sums' rounding.
  LinearMap whole = map;
  whole.comm = MPI_COMM_SELF;
  auto serial = make_acceleration(parameters(AccelerationKind::iqn_ils), 1, MPI_COMM_SELF);
  const WindowResult one = iterate(*serial, whole, Eigen::VectorXd::Zero(map.n()), 1e-10, 40);
  EXPECT_EQ(one.iterations, res.iterations);
  EXPECT_LE((res.x - map.slice(one.x)).lpNorm<Eigen::Infinity>(), 1e-12);
}

TEST(Acceleration, IqnIlsReusedColumnsSpeedUpLaterWindows) {
  // Five windows of the same Jacobian with a changing b (time steps of a linear problem): with the columns
  // of past windows kept, a later window needs a few iterations; with reuse 0 as many as the first.
  const auto run = [](const int reuse) {
    AccelerationParameters p = parameters(AccelerationKind::iqn_ils);
    p.reuse = reuse;
    auto acc = make_acceleration(p, 1, MPI_COMM_WORLD);
    std::vector<int> iterations;
    for (int window = 0; window < 5; ++window) {
      const LinearMap map = divergent_map(MPI_COMM_WORLD, 0.2 * window);
      const WindowResult res = iterate(*acc, map, map.slice(Eigen::VectorXd::Zero(map.n())), 1e-10, 40);
      EXPECT_TRUE(res.converged);
      iterations.push_back(res.iterations);
    }
    return iterations;
  };
  const std::vector<int> fresh = run(0), reused = run(8);
  EXPECT_EQ(fresh[0], reused[0]);
  for (int window = 1; window < 5; ++window) {
    EXPECT_GE(fresh[static_cast<std::size_t>(window)], fresh[0] - 1) << "window " << window;
    EXPECT_LE(reused[static_cast<std::size_t>(window)], 3) << "window " << window;
  }
}

TEST(Acceleration, IqnIlsDropsKeptColumnsWhenTheIdsChange) {
  const LinearMap map = divergent_map(MPI_COMM_WORLD);
  IqnIlsAcceleration acc(parameters(AccelerationKind::iqn_ils, 0.5), 1, MPI_COMM_WORLD);
  iterate(acc, map, map.slice(Eigen::VectorXd::Zero(map.n())), 1e-10, 40);
  const int kept = acc.columns();
  EXPECT_GT(kept, 0);
  // The same values under other ids on the last rank (a particle that changed): the first iteration of the
  // next window is a plain relaxation again, on every rank.
  std::vector<GlobalId> ids = map.ids();
  if (rank_of(MPI_COMM_WORLD) == size_of(MPI_COMM_WORLD) - 1) ids.back() += 1000;
  const DataVector x = map.slice(Eigen::VectorXd::Zero(map.n()));
  const DataVector hx = map.apply(x);
  const DataVector next = acc.next(ids, x, hx);
  EXPECT_EQ(acc.dropped_by_ids(), kept);
  EXPECT_EQ(acc.columns(), 0);
  EXPECT_LE((next - (x + 0.5 * (hx - x))).lpNorm<Eigen::Infinity>(), 0.0);
  // Within a window the ids must not change.
  std::vector<GlobalId> other = ids;
  if (!other.empty()) other.front() -= 1000;
  if (!other.empty()) {
    EXPECT_THROW(acc.next(other, x, hx), std::logic_error);
  }
}

TEST(Acceleration, IqnIlsFilterLeavesOutDependentColumns) {
  // Repeating an iterate gives a zero column, and a residual change parallel to an earlier one a dependent
  // column: both are left out of the least squares, and the update stays finite.
  IqnIlsAcceleration acc(parameters(AccelerationKind::iqn_ils), 2, MPI_COMM_SELF);
  const std::vector<GlobalId> ids = {1, 2};
  DataVector x(4), hx(4);
  x << 0, 0, 0, 0;
  hx << 1, 2, 3, 4;
  acc.next(ids, x, hx);
  acc.next(ids, x, hx);  // the same again: V gets a zero column
  EXPECT_EQ(acc.columns(), 1);
  const DataVector x2 = x, hx2 = 2 * hx;  // r doubles: a column h
  DataVector next = acc.next(ids, x2, hx2);
  const DataVector hx3 = 3 * hx;  // r triples: the newest column is parallel to the previous one
  next = acc.next(ids, x2, hx3);
  EXPECT_EQ(acc.columns(), 3);
  EXPECT_EQ(acc.filtered(), 2);  // the zero column and the parallel one
  for (Eigen::Index i = 0; i < next.size(); ++i) EXPECT_TRUE(std::isfinite(next(i)));
}

TEST(Acceleration, RelativeResidualAndParameterChecks) {
  DataVector x = DataVector::Zero(3), hx = DataVector::Zero(3);
  EXPECT_EQ(relative_residual(x, hx, 0.0, MPI_COMM_SELF), 0.0);
  x(0) = 3e-3;
  hx(1) = 4e-3;  // |hx - x| = 5e-3, |hx| = 4e-3
  EXPECT_DOUBLE_EQ(relative_residual(x, hx, 0.0, MPI_COMM_SELF), 1.25);
  EXPECT_DOUBLE_EQ(relative_residual(x, hx, 1.0, MPI_COMM_SELF), 5e-3);  // the floor sets the scale
  AccelerationParameters p;
  p.relaxation = 0;
  EXPECT_THROW(make_acceleration(p, 1, MPI_COMM_SELF), std::invalid_argument);
  p = AccelerationParameters{};
  p.filter = 1;
  EXPECT_THROW(make_acceleration(p, 1, MPI_COMM_SELF), std::invalid_argument);
  p = AccelerationParameters{};
  p.max_columns = 0;
  EXPECT_THROW(make_acceleration(p, 1, MPI_COMM_SELF), std::invalid_argument);
  EXPECT_EQ(make_acceleration(AccelerationParameters{}, 1, MPI_COMM_SELF)->name(), "iqn-ils");
}

TEST(Acceleration, IqnIlsStateLoadsOnAnotherPartition) {
  // The kept columns of a run on every rank, saved and loaded by one rank that holds every value (a restart
  // on another number of ranks): the next window takes the same iterations to the same answer.
  const LinearMap first = divergent_map(MPI_COMM_WORLD), second = divergent_map(MPI_COMM_WORLD, 0.3);
  IqnIlsAcceleration acc(parameters(AccelerationKind::iqn_ils), 1, MPI_COMM_WORLD);
  iterate(acc, first, first.slice(Eigen::VectorXd::Zero(first.n())), 1e-10, 40);
  BinaryWriter out;
  acc.save_state(out);
  IqnIlsAcceleration loaded(parameters(AccelerationKind::iqn_ils), 1, MPI_COMM_SELF);
  LinearMap whole = second;
  whole.comm = MPI_COMM_SELF;
  BinaryReader in(out.bytes(), "the saved acceleration");
  loaded.load_state(in, whole.ids());
  EXPECT_TRUE(in.at_end());
  int columns = acc.columns();
  MPI_Allreduce(MPI_IN_PLACE, &columns, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  EXPECT_EQ(loaded.columns(), columns);
  const WindowResult distributed = iterate(acc, second, second.slice(Eigen::VectorXd::Zero(second.n())), 1e-10, 40);
  const WindowResult serial = iterate(loaded, whole, Eigen::VectorXd::Zero(second.n()), 1e-10, 40);
  EXPECT_LE(distributed.iterations, 3);  // the kept columns know the Jacobian
  EXPECT_EQ(serial.iterations, distributed.iterations);
  EXPECT_LE((distributed.x - second.slice(serial.x)).lpNorm<Eigen::Infinity>(), 1e-12);
  // A checkpoint whose ids do not cover this interface: the columns are dropped, not mis-mapped.
  IqnIlsAcceleration other(parameters(AccelerationKind::iqn_ils), 1, MPI_COMM_SELF);
  BinaryReader again(out.bytes(), "the saved acceleration");
  std::vector<GlobalId> foreign = whole.ids();
  foreign.back() += 1000;
  other.load_state(again, foreign);
  EXPECT_EQ(other.columns(), 0);
}
