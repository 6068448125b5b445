// Unit tests of the fluid's standard scheme (fluid.scheme = standard): PPE assembly (seed 004 eq. 12, 23:
// symmetric, diagonally dominant, the lattice value of an interior row), the free-surface double check
// (§4.3), and the pressure solve's true residual for every solver / preconditioner choice. The projection's
// own tests are in test_fluid_projection.cpp.
#include "core/distribution.hpp"
#include "core/kernel.hpp"
#include "fluid/coarse_level.hpp"
#include "fluid/fluid_solver.hpp"
#include "fluid/pressure_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

using namespace mpsfsi;

namespace {

CaseSpec still_water_case() {
  return load_case(std::string(MPSFSI_SOURCE_DIR) + "/cases/hydrostatic.yaml",
                   {"dp=0.01", "fluid.preconditioner=jacobi", "fluid.scheme=standard"});
}

struct OneStep {
  CaseSpec spec = still_water_case();
  Scene scene = build_scene(spec);
  Distribution dist{MPI_COMM_SELF, {}};
  FluidSolver fluid{fluid_setup(spec), scene.particles, dist};
  Real dt = 0;
  FluidStepReport report;
  OneStep() {
    dt = fluid.stable_dt();
    report = fluid.advance(0.0, dt);
  }
};

Real entry(const LocalRows& s, const std::size_t row, const LocalIndex col) {
  for (std::size_t k = s.row_ptr[row]; k < s.row_ptr[row + 1]; ++k)
    if (s.col[k] == col) return s.value[k];
  return 0;
}

}  // namespace

TEST(FluidPpe, SymmetricDiagonallyDominantAndSorted) {
  OneStep run;
  const LocalRows& s = run.fluid.last_system();
  const auto& p = run.scene.particles;
  ASSERT_EQ(s.n_rows(), p.n_of_kind(ParticleKind::fluid) + p.n_of_kind(ParticleKind::wall));
  ASSERT_TRUE(s.remote_id.empty());
  for (std::size_t r = 0; r < s.n_rows(); ++r)
    ASSERT_EQ(s.row_id[r], p.global_id[static_cast<std::size_t>(run.fluid.row_particles()[r])]);
  const Real compress = 1.0 / std::pow(run.spec.fluid_materials[0].c * run.dt, 2);
  for (std::size_t r = 0; r < s.n_rows(); ++r) {
    Real diag = 0, off = 0;
    for (std::size_t k = s.row_ptr[r]; k < s.row_ptr[r + 1]; ++k) {
      if (k > s.row_ptr[r]) {
        ASSERT_LT(s.col[k - 1], s.col[k]) << "row " << r << " not sorted";
      }
      const auto c = static_cast<std::size_t>(s.col[k]);
      if (c == r) {
        diag = s.value[k];
        continue;
      }
      EXPECT_LT(s.value[k], 0.0);
      off += std::abs(s.value[k]);
      EXPECT_NEAR(entry(s, c, static_cast<LocalIndex>(r)), s.value[k], 1e-12 * std::abs(s.value[k])) << r << "," << c;
    }
    EXPECT_GE(diag, off + compress * (1 - 1e-9)) << "row " << r;
  }
}

TEST(FluidPpe, InteriorRowMatchesLattice) {
  OneStep run;
  const LocalRows& s = run.fluid.last_system();
  const auto& p = run.scene.particles;
  const auto& lat_l = run.fluid.lattice_laplacian();
  const Real a = 2.0 * dim / (lat_l.lambda * lat_l.n0);
  const Real compress = 1.0 / std::pow(run.spec.fluid_materials[0].c * run.dt, 2);
  const Real source_scale = run.spec.fluid_materials[0].kappa * run.spec.fluid_materials[0].rho / (run.dt * run.dt);
  std::size_t n_checked = 0;
  for (std::size_t r = 0; r < s.n_rows(); ++r) {
    const auto i = static_cast<std::size_t>(run.fluid.row_particles()[r]);
    const Vec x = p.position[i];
    // Deep interior: more than re_l + 1 dp from the walls (x = 0, 0.2; y = 0) and from the surface (y = 0.2).
    const Real margin = 5 * run.spec.dp;
    if (p.kind[i] != ParticleKind::fluid || x[0] < margin || x[0] > 0.2 - margin || x[1] < margin || x[1] > 0.2 - margin)
      continue;
    ++n_checked;
    EXPECT_NEAR(entry(s, r, static_cast<LocalIndex>(r)), a * lat_l.n0 + compress, 1e-9 * (a * lat_l.n0));
    EXPECT_EQ(s.row_ptr[r + 1] - s.row_ptr[r], static_cast<std::size_t>(lat_l.n_neighbours + 1));
    EXPECT_LT(std::abs(s.rhs[r]), 1e-9 * source_scale);  // rigid translation: n* = n0
  }
  EXPECT_GT(n_checked, 50u);
}

TEST(FluidFreeSurface, DoubleCheckFlagsTheTopRowOnly) {
  OneStep run;
  const auto& p = run.scene.particles;
  const auto& surface = p.scalar_field("free_surface");
  const auto& pressure = p.scalar_field("pressure");
  Real y_top = -1;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.kind[i] == ParticleKind::fluid) y_top = std::max(y_top, p.position[i][1]);
  std::size_t n_top = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.kind[i] == ParticleKind::fluid) {
      const Real depth = y_top - p.position[i][1];
      if (depth < 0.1 * run.spec.dp) {
        EXPECT_EQ(surface[i], 1.0) << "top particle at " << p.position[i].transpose();
        EXPECT_EQ(pressure[i], 0.0);
        ++n_top;
      }
      if (depth > 2.5 * run.spec.dp) {
        EXPECT_EQ(surface[i], 0.0) << "interior particle at " << p.position[i].transpose();
      }
    }
    if (p.kind[i] == ParticleKind::dummy) {
      EXPECT_EQ(surface[i], 0.0);
    }
    // Wall particles under the water (the floor) are not on the surface.
    if (p.kind[i] == ParticleKind::wall && p.position[i][1] < 0 && p.position[i][0] > 0.02 && p.position[i][0] < 0.18) {
      EXPECT_EQ(surface[i], 0.0);
    }
  }
  EXPECT_GE(n_top, 15u);
  EXPECT_EQ(run.report.n_surface, static_cast<std::size_t>(std::count(surface.begin(), surface.end(), 1.0)));
}

// A 2D 5-point Poisson matrix plus a shift (SPD like the PPE) solved with each choice; the true residual
// is recomputed here from the CRS arrays.
class PressureSolve : public ::testing::TestWithParam<std::pair<const char*, const char*>> {
 protected:
  /// The parameter's solver and preconditioner with this relative tolerance and 2000 iterations at most.
  PressureSolverSettings settings_with(const Real tolerance) const {
    PressureSolverSettings settings;
    settings.solver = *value_of(krylov_solver_names(), GetParam().first);
    settings.preconditioner = *value_of(preconditioner_names(), GetParam().second);
    settings.tolerance = tolerance;
    settings.max_iterations = 2000;
    return settings;
  }
};

namespace {
/// The shifted 5-point system on an m x m grid held whole (row ids 1000 + 3 r: ids are names, not positions),
/// right-hand side uniform in [-1, 1]. With `coarse` > 0 the rows are in groups of coarse x coarse grid points;
/// with `dirichlet_top` the top row of points are identity rows, dropped from the other rows (like the free
/// surface).
LocalRows model_system(const int m, const int coarse, const bool dirichlet_top) {
  LocalRows whole;
  whole.row_ptr.push_back(0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (std::size_t r = 0; r < static_cast<std::size_t>(m * m); ++r) {
    whole.row_id.push_back(1000 + 3 * static_cast<GlobalId>(r));
    const int ix = static_cast<int>(r) % m, iy = static_cast<int>(r) / m;
    if (coarse > 0) whole.group.push_back(static_cast<std::int64_t>(iy / coarse) * 1000 + ix / coarse);
    const auto add = [&](int jx, int jy, Real v) {
      if (jx < 0 || jy < 0 || jx >= m || jy >= m) return;
      if (dirichlet_top && jy == m - 1 && jy != iy) return;
      whole.col.push_back(jy * m + jx);
      whole.value.push_back(v);
    };
    if (dirichlet_top && iy == m - 1) {
      add(ix, iy, 4.01);
    } else {
      add(ix, iy - 1, -1);
      add(ix - 1, iy, -1);
      add(ix, iy, 4.01);
      add(ix + 1, iy, -1);
      add(ix, iy + 1, -1);
    }
    whole.row_ptr.push_back(whole.col.size());
    whole.rhs.push_back(u(rng));
  }
  return whole;
}

/// Solves model_system(40, coarse, dirichlet_top) with `settings` and `absolute_tolerance`; returns the
/// solver's result and the true ||b - Ax|| / ||b|| recomputed from the CRS arrays. With `coarse` > 0 the
/// rows are in groups of coarse x coarse grid points (the two-level sgs / ssor); with `dirichlet_top` the
/// top row of points are identity rows, dropped from the other rows (like the free surface).
std::pair<PressureSolveResult, Real> solve_model_problem(const PressureSolverSettings& settings,
                                                         const Real absolute_tolerance, Real* b_norm = nullptr,
                                                         const int coarse = 0, const bool dirichlet_top = false) {
  auto solver = make_pressure_solver(settings, MPI_COMM_WORLD);
  int rank = 0, n_ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &n_ranks);
  const int m = 40;
  const std::size_t n = static_cast<std::size_t>(m * m);
  const LocalRows whole = model_system(m, coarse, dirichlet_top);
  LocalRows s = split_system(whole, rank, n_ranks);
  s.absolute_tolerance = absolute_tolerance;
  std::vector<Real> x(s.n_rows(), 0.0);
  const PressureSolveResult res = solver->solve(s, x);
  // True residual of the whole system from the solution gathered in row order (the blocks are in order).
  std::vector<int> counts(static_cast<std::size_t>(n_ranks)), displs(static_cast<std::size_t>(n_ranks), 0);
  const int mine = static_cast<int>(x.size());
  MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  for (std::size_t q = 1; q < counts.size(); ++q) displs[q] = displs[q - 1] + counts[q - 1];
  std::vector<Real> x_all(n);
  MPI_Allgatherv(x.data(), mine, MPI_DOUBLE, x_all.data(), counts.data(), displs.data(), MPI_DOUBLE, MPI_COMM_WORLD);
  Real r2 = 0, b2 = 0;
  const auto begin = static_cast<std::size_t>(displs[static_cast<std::size_t>(rank)]);
  for (std::size_t r = begin; r < begin + x.size(); ++r) {
    Real ax = 0;
    for (std::size_t k = whole.row_ptr[r]; k < whole.row_ptr[r + 1]; ++k)
      ax += whole.value[k] * x_all[static_cast<std::size_t>(whole.col[k])];
    r2 += std::pow(whole.rhs[r] - ax, 2);
    b2 += whole.rhs[r] * whole.rhs[r];
  }
  Real sums[2] = {r2, b2}, global[2] = {0, 0};
  MPI_Allreduce(sums, global, 2, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  if (b_norm) *b_norm = std::sqrt(global[1]);
  return {res, std::sqrt(global[0] / global[1])};
}
}  // namespace

TEST_P(PressureSolve, TrueResidualBelowTolerance) {
  PressureSolverSettings settings = settings_with(1e-8);
  const auto [res, true_residual] = solve_model_problem(settings, 0);
  EXPECT_TRUE(res.converged);
  EXPECT_GT(res.iterations, 0);
  EXPECT_EQ(res.tolerance, settings.tolerance);
  EXPECT_LT(true_residual, 10 * settings.tolerance);
  EXPECT_NEAR(res.residual, true_residual, 1e-3 * true_residual + 1e-14);
}

// The absolute stop (fluid.density_tolerance): a looser absolute bound stops earlier, with the true
// residual below it; a tighter one than the relative tolerance changes nothing.
TEST_P(PressureSolve, AbsoluteToleranceStopsEarlier) {
  PressureSolverSettings settings = settings_with(1e-10);
  Real b_norm = 0;
  const auto [strict, strict_residual] = solve_model_problem(settings, 0, &b_norm);
  const Real absolute = 1e-4 * b_norm;
  const auto [loose, loose_residual] = solve_model_problem(settings, absolute);
  EXPECT_TRUE(loose.converged);
  EXPECT_DOUBLE_EQ(loose.tolerance, 1e-4);
  EXPECT_LT(loose.iterations, strict.iterations);
  EXPECT_LT(loose_residual * b_norm, 10 * absolute);
  EXPECT_GT(loose_residual, strict_residual);
  const auto [tight, tight_residual] = solve_model_problem(settings, 1e-3 * settings.tolerance * b_norm);
  EXPECT_EQ(tight.iterations, strict.iterations);
  EXPECT_EQ(tight.tolerance, settings.tolerance);
}

INSTANTIATE_TEST_SUITE_P(AllChoices, PressureSolve,
                         ::testing::Values(std::make_pair("cg", "muelu"), std::make_pair("cg", "chebyshev"),
                                           std::make_pair("cg", "ilu"), std::make_pair("cg", "jacobi"),
                                           std::make_pair("cg", "none"), std::make_pair("gmres", "muelu"),
                                           std::make_pair("gmres", "ilu"), std::make_pair("cg", "sgs"),
                                           std::make_pair("cg", "ssor"), std::make_pair("gmres", "ssor")));

// The two-level sgs / ssor (rows in groups of 4 x 4 points, fluid.coarse_size): the same true residual in
// at most 0.6 times the iterations of one level (measured: sgs 31 -> 18 on one rank, ssor 37 -> 19), with identity rows (in no group) and groups that span the ranks' blocks of
// rows (this test also runs on 2 and 3 ranks).
TEST(PressureSolve, TwoLevelSsorNeedsFewerIterations) {
  for (const Preconditioner prec : {Preconditioner::sgs, Preconditioner::ssor}) {
    PressureSolverSettings settings;
    settings.preconditioner = prec;
    settings.tolerance = 1e-10;
    settings.max_iterations = 2000;
    for (const bool dirichlet_top : {false, true}) {
      const auto [one, one_residual] = solve_model_problem(settings, 0, nullptr, 0, dirichlet_top);
      const auto [two, two_residual] = solve_model_problem(settings, 0, nullptr, 4, dirichlet_top);
      SCOPED_TRACE(std::string(to_string(prec)) + (dirichlet_top ? ", identity rows" : ""));
      EXPECT_TRUE(one.converged);
      EXPECT_TRUE(two.converged);
      EXPECT_LT(one_residual, 10 * settings.tolerance);
      EXPECT_LT(two_residual, 10 * settings.tolerance);
      EXPECT_NEAR(two.residual, two_residual, 1e-3 * two_residual + 1e-14);
      EXPECT_LT(5 * two.iterations, 3 * one.iterations) << two.iterations << " vs " << one.iterations;
    }
  }
}

namespace {
/// The shifted 5-point system of solve_model_problem on an m x m grid, rows in groups of 4 x 4 points,
/// with the rows of `dirichlet` (y index) identity rows; unlike solve_model_problem's, their entries and
/// the other rows' entries in their columns stay in the pattern with the value 0 (as the projection's
/// active set lays out its rows).
LocalRows padded_model_system(const int m, const std::vector<int>& dirichlet) {
  const auto is_dirichlet = [&](const int iy) { return std::find(dirichlet.begin(), dirichlet.end(), iy) != dirichlet.end(); };
  LocalRows whole;
  whole.row_ptr.push_back(0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<Real> u(-1, 1);
  for (int r = 0; r < m * m; ++r) {
    whole.row_id.push_back(1000 + 3 * static_cast<GlobalId>(r));
    const int ix = r % m, iy = r / m;
    whole.group.push_back(static_cast<std::int64_t>(iy / 4) * 1000 + ix / 4);
    const auto add = [&](int jx, int jy, Real v) {
      if (jx < 0 || jy < 0 || jx >= m || jy >= m) return;
      const bool diagonal = jx == ix && jy == iy;
      whole.col.push_back(jy * m + jx);
      whole.value.push_back(diagonal || (!is_dirichlet(iy) && !is_dirichlet(jy)) ? v : 0.0);
    };
    add(ix, iy - 1, -1);
    add(ix - 1, iy, -1);
    add(ix, iy, 4.01);
    add(ix + 1, iy, -1);
    add(ix, iy + 1, -1);
    whole.row_ptr.push_back(whole.col.size());
    whole.rhs.push_back(is_dirichlet(iy) ? 0.0 : u(rng));
  }
  return whole;
}
}  // namespace

// The projection's active set re-solves with a few rows changed on the same pattern (LocalRows::values_only):
// the solver that updates those rows of its setup gives the solution of a solver set up anew, bit for bit
// with the two-level ssor and sgs (Eisenstat's system, updated row by row), to the tolerance with the
// others (set up anew). Runs on 1, 2 and 3 ranks.
TEST(PressureSolve, ReSolveWithChangedRowsEqualsANewSetup) {
  int rank = 0, n_ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &n_ranks);
  const int m = 24;
  const LocalRows first = split_system(padded_model_system(m, {m - 1}), rank, n_ranks);
  LocalRows second = split_system(padded_model_system(m, {m - 2, m - 5}), rank, n_ranks);
  // The rows whose values differ: y = m - 1 (a row again), m - 2 and m - 5 (now identity rows) and their
  // neighbours.
  for (std::size_t k = 0; k < second.n_rows(); ++k) {
    const auto iy = static_cast<int>((second.row_id[k] - 1000) / 3) / m;
    if (iy >= m - 6) second.changed_rows.push_back(static_cast<LocalIndex>(k));
  }
  for (const Preconditioner prec : {Preconditioner::ssor, Preconditioner::sgs, Preconditioner::muelu, Preconditioner::jacobi}) {
    SCOPED_TRACE(to_string(prec));
    PressureSolverSettings settings;
    settings.preconditioner = prec;
    settings.tolerance = 1e-10;
    settings.max_iterations = 2000;
    auto updated = make_pressure_solver(settings, MPI_COMM_WORLD);
    auto fresh = make_pressure_solver(settings, MPI_COMM_WORLD);
    std::vector<Real> x(first.n_rows(), 0.0);
    EXPECT_TRUE(updated->solve(first, x).converged);
    std::vector<Real> x_fresh = x;
    second.values_only = true;
    const PressureSolveResult a = updated->solve(second, x);
    second.values_only = false;
    const PressureSolveResult b = fresh->solve(second, x_fresh);
    EXPECT_TRUE(a.converged);
    EXPECT_TRUE(b.converged);
    EXPECT_LT(a.residual, 10 * settings.tolerance);
    const bool row_by_row = prec == Preconditioner::ssor || prec == Preconditioner::sgs;
    Real largest = 0;
    for (const Real v : x_fresh) largest = std::max(largest, std::abs(v));
    for (std::size_t k = 0; k < x.size(); ++k) {
      if (row_by_row) {
        EXPECT_EQ(x[k], x_fresh[k]) << "row " << k;
      } else {
        EXPECT_NEAR(x[k], x_fresh[k], 1e-7 * largest) << "row " << k;
      }
    }
    if (row_by_row) {
      EXPECT_EQ(a.iterations, b.iterations);
    }
  }
}

TEST(PressureSolve, RejectsUnknownChoices) {
  PressureSolverSettings settings;
  settings.preconditioner = static_cast<Preconditioner>(99);  // no such preconditioner
  EXPECT_THROW(make_pressure_solver(settings, MPI_COMM_WORLD), std::invalid_argument);
}

namespace {
/// model_system on an m x m grid in groups of 4 x 4 points (split_system adds each row's rank to the keys):
/// this rank's block, and its coarse level set up and factorised.
LocalRows coarse_model_block(const int m, trilinos_detail::CoarseLevel& coarse, const bool owner_in_key = true) {
  int rank = 0, n_ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &n_ranks);
  LocalRows s = split_system(model_system(m, 4, false), rank, n_ranks);
  if (!owner_in_key)
    for (auto& key : s.group) key &= (std::int64_t{1} << 44) - 1;
  coarse.set_groups(s, MPI_COMM_WORLD, n_ranks);
  for (std::size_t i = 0; i < s.n_rows(); ++i)
    coarse.add_row(&s.col[s.row_ptr[i]], &s.value[s.row_ptr[i]], s.row_ptr[i + 1] - s.row_ptr[i]);
  coarse.factorise();
  return s;
}
}  // namespace

// The coarse level factorised apart by rank (the interiors on their ranks, the Schur complement of the groups
// along the cuts on every rank) solves E x = v: on every rank, each own group's row of E = Z^T (A Z) applied to
// the x the solve gives (own groups and the interface) returns v to round-off.
TEST(PressureSolve, CoarseLevelSolvesTheCoarseMatrix) {
  trilinos_detail::CoarseLevel coarse;
  coarse_model_block(36, coarse);
  ASSERT_GE(coarse.m, 81);  // 9 x 9 groups, more where the ranks' blocks cut them
  // v on each group's owner (the other ranks add 0 there), v_k = sin(k + 1).
  std::vector<double> x(static_cast<std::size_t>(coarse.m), 0.0);
  for (const int k : coarse.of_row)
    if (k >= 0) x[static_cast<std::size_t>(k)] = std::sin(k + 1.0);
  coarse.solve(x);
  std::vector<double> ex(static_cast<std::size_t>(coarse.m), 0.0);  // the own groups' rows of E x
  for (std::size_t i = 0; i < coarse.of_row.size(); ++i)
    if (coarse.of_row[i] >= 0)
      ex[static_cast<std::size_t>(coarse.of_row[i])] += coarse.az.row_dot(i, x.data());
  double worst = 0;
  int n_checked = 0;
  for (int k = 0; k < coarse.m; ++k)
    if (std::find(coarse.of_row.begin(), coarse.of_row.end(), k) != coarse.of_row.end()) {
      worst = std::max(worst, std::abs(ex[static_cast<std::size_t>(k)] - std::sin(k + 1.0)));
      ++n_checked;
    }
  int n_ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n_ranks);
  MPI_Allreduce(MPI_IN_PLACE, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &n_checked, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(n_checked, coarse.m);  // every group checked once, on its owner
  EXPECT_LT(worst, 1e-12);
  if (n_ranks > 1) {
    EXPECT_FALSE(coarse.iface.empty());
  }
}

// A group whose rows are on two ranks breaks the coarse level's contract (LocalRows::group): every rank throws.
TEST(PressureSolve, CoarseGroupsOnTwoRanksAreRefused) {
  int n_ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n_ranks);
  trilinos_detail::CoarseLevel coarse;
  if (n_ranks == 1) {
    EXPECT_NO_THROW(coarse_model_block(38, coarse, false));
    return;
  }
  EXPECT_THROW(coarse_model_block(38, coarse, false), std::logic_error);  // 38 x 38 rows in 2-4 blocks cut groups
}
