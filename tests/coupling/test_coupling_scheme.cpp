// The coupling schemes (coupling/coupling_scheme.hpp) on a small coupled case: water 0.1 m deep against an
// elastic plate clamped to the floor, which bends under it from the first step. A window of the implicit scheme
// repeated from its saved start with the same input gives the same state bit for bit (the save / restore holds everything a step changes); with IQN-ILS the
// windows converge; the run loop counts steps that do not converge, or stops. Runs on 1 to 4 ranks (ctest
// coupling_scheme_np1..4).
#include "core/distribution.hpp"
#include "coupling/acceleration.hpp"
#include "coupling/coupling_scheme.hpp"
#include "coupling/fsi_interface.hpp"
#include "coupling/simulation.hpp"
#include "coupling/time_step_policy.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"
#include "support/temp_dir.hpp"

#include <gtest/gtest.h>
#include <mpi.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>

using namespace mpsfsi;

namespace {

const char* plate_case = R"(name: plate_in_water
description: water 0.1 m deep against an elastic plate clamped to the floor
source: tests
dp: 0.005
domain: {min: [-0.05, -0.05], max: [0.25, 0.3]}
time: {end: 1.0, cfl: 0.2, dt_max: 1.0e-3}
gravity: [0, -9.81]
materials:
  water: {type: fluid, rho: 1000, nu: 1.0e-6, c: 20, kappa: 0.2}
  rubber: {type: solid, rho: 1100, E: 1.0e6, nu: 0.0}
bodies:
  - {name: water, kind: fluid, material: water, rectangle: {min: [0, 0], max: [0.1, 0.1]}}
  - name: plate
    kind: solid
    material: rubber
    rectangle: {min: [0.1, -0.0075], max: [0.11, 0.08]}
    clamp: {min: [0.099, -0.008], max: [0.111, 0.0]}
walls:
  - {name: tank, type: box, rectangle: {min: [0, 0], max: [0.2, 0.2]}, open_top: true}
coupling: {subcycles: auto, solid_damping: 0}
solid: {re: 2.1}
fluid: {solver: cg, preconditioner: jacobi, tolerance: 1.0e-10, max_iterations: 1000}
)";

/// The participants of a coupled run, built as the run loop builds them.
struct Coupled {
  CaseSpec spec;
  Scene scene;
  std::unique_ptr<Distribution> dist;
  std::unique_ptr<FluidSolver> fluid;
  std::unique_ptr<SolidSolver> solid;
  std::unique_ptr<FsiInterface> fsi;
  std::unique_ptr<CouplingScheme> scheme;
  Real t = 0;

  explicit Coupled(const std::vector<std::string>& overrides, std::unique_ptr<Acceleration> acceleration = nullptr)
      : spec(parse_case(plate_case, "plate_in_water", overrides)), scene(build_scene(spec)) {
    DistributionSettings ds;
    ds.skin = spec.parallel.skin * spec.dp;
    ds.halo_width = std::max(fluid_interaction_radius(fluid_setup(spec)), solid_interaction_radius(solid_setup(spec))) + ds.skin;
    dist = std::make_unique<Distribution>(MPI_COMM_WORLD, ds);
    std::vector<Real> w(scene.particles.size());
    for (std::size_t i = 0; i < w.size(); ++i) w[i] = fluid_work_weight(scene.particles.kind[i]);
    dist->distribute_replicated(scene.particles, w);
    fluid = std::make_unique<FluidSolver>(fluid_setup(spec), scene.particles, *dist, FsiInterface::fluid_options());
    solid = std::make_unique<SolidSolver>(solid_setup(spec), scene.particles, *dist);
    solid->set_damping(spec.coupling.solid_damping);
    fsi = std::make_unique<FsiInterface>(spec, scene.particles, FsiOptions{}, dist.get());
    fsi->initialize();
    scheme = make_coupling_scheme(spec.coupling, CouplingParticipants{spec.dp, scene.particles, *dist, *fluid, *solid, *fsi},
                                  std::move(acceleration));
  }

  /// n windows of the fluid's stable dt (the same on every rank: fluid_stable_dt reduces over them).
  std::vector<CouplingWindow> run(const int n) {
    std::vector<CouplingWindow> windows;
    for (int k = 0; k < n; ++k) {
      const Real dt = fluid->stable_dt();
      const int n_sub = choose_subcycles(spec.coupling.subcycles, dt, solid->stable_dt()).n;
      windows.push_back(scheme->advance(t, dt, n_sub));
      t += dt;
    }
    return windows;
  }

  /// Every owned particle's position and velocity and the pressure, by global id (this rank's), and under id
  /// -1 the interface's force and work per body.
  std::map<GlobalId, std::vector<Real>> state() const {
    std::map<GlobalId, std::vector<Real>> s;
    for (const InterfaceBody& b : fsi->bodies()) {
      for (int a = 0; a < dim; ++a) s[-1].push_back(b.force[a]);
      s[-1].push_back(b.work_step);
      s[-1].push_back(b.work_total);
    }
    const ParticleSet& p = scene.particles;
    const auto& pressure = p.scalar_field(fluid_fields::pressure);
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      auto& v = s[p.global_id[i]];
      for (int a = 0; a < dim; ++a) v.push_back(p.position[i][a]);
      for (int a = 0; a < dim; ++a) v.push_back(p.velocity[i][a]);
      v.push_back(pressure[i]);
    }
    return s;
  }
};

/// An acceleration that gives back the input it was given: the next iteration repeats the last one.
class Repeat : public Acceleration {
 public:
  DataVector next(const std::vector<GlobalId>&, const DataVector& x, const DataVector&) override {
    ++iteration_;
    return x;
  }
  void end_window() override { iteration_ = 0; }
  std::string name() const override { return "repeat"; }
};

Real largest_solid_speed(const ParticleSet& p) {
  Real v = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    if (p.kind[i] == ParticleKind::solid) v = std::max(v, p.velocity[i].norm());
  MPI_Allreduce(MPI_IN_PLACE, &v, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return v;
}

}  // namespace

TEST(CouplingScheme, TheExplicitSchemeMovesThePlate) {
  // The case loads the plate from the first step (the tests below compare states that have moved).
  Coupled explicit_run({"coupling.scheme=explicit"});
  const std::vector<CouplingWindow> w = explicit_run.run(30);
  EXPECT_EQ(w.back().iterations, 1);
  EXPECT_GT(largest_solid_speed(explicit_run.scene.particles), 1e-3);
}

TEST(CouplingScheme, AWindowRepeatedFromItsStartGivesTheSameState) {
  // Three iterations of the same input: the second and third start from the restored state and must end
  // where the first did (to the last bit), and so the run where each window has one iteration (with the same
  // tolerance: it sets the fluid's, ImplicitScheme::fluid_density_tolerance).
  Coupled once({"coupling.scheme=implicit", "coupling.implicit.max_iterations=1", "coupling.implicit.tolerance=1e-300"});
  Coupled thrice({"coupling.scheme=implicit", "coupling.implicit.max_iterations=3", "coupling.implicit.tolerance=1e-300"},
                 std::make_unique<Repeat>());
  once.run(30);
  const std::vector<CouplingWindow> w = thrice.run(30);
  EXPECT_GT(largest_solid_speed(once.scene.particles), 1e-3);
  EXPECT_EQ(w.back().iterations, 3);
  EXPECT_FALSE(w.back().converged);
  EXPECT_EQ(once.state(), thrice.state());
}

TEST(CouplingScheme, ImplicitWindowsConvergeWithIqnIls) {
  Coupled run({"coupling.scheme=implicit", "coupling.implicit.tolerance=1e-4", "coupling.implicit.max_iterations=30"});
  const std::vector<CouplingWindow> windows = run.run(30);
  int most = 0;
  for (const CouplingWindow& w : windows) {
    EXPECT_TRUE(w.converged) << "residual " << w.residual;
    EXPECT_LE(w.residual, 1e-4);
    most = std::max(most, w.iterations);
  }
  EXPECT_GT(most, 1);  // the plate moves: one iteration is not enough
  EXPECT_LE(most, 10);
}

TEST(CouplingScheme, RunLoopCountsOrStopsOnStepsThatDoNotConverge) {
  // Through the run loop: 20 steps whose tolerance no iteration meets. on_max_iterations continue: the run
  // ends and its summary counts them; stop: the first such step stops the run with a diagnosis (exit 3).
  const auto dir = test::fresh_temp_dir("coupling_scheme");
  RunSettings settings;
  settings.output_dir = dir.string();
  settings.quiet = true;
  settings.max_steps = 20;
  const std::vector<std::string> strict = {"coupling.scheme=implicit", "coupling.implicit.tolerance=1e-15",
                                           "coupling.implicit.max_iterations=2", "output.interval=1"};
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  const CaseSpec going_on = parse_case(plate_case, "plate_in_water", strict);
  const RunSummary s = run_case(going_on, build_scene(going_on), settings, MPI_COMM_WORLD);
  EXPECT_EQ(s.n_steps, 20u);
  EXPECT_EQ(s.coupling_windows, 20u);
  EXPECT_EQ(s.coupling_iterations, 40u);
  EXPECT_EQ(s.coupling_iterations_max, 2);
  EXPECT_GE(s.n_unconverged, 19u);  // (the first step, the solid at rest, may meet it)
  if (rank == 0) std::filesystem::remove_all(dir);
  MPI_Barrier(MPI_COMM_WORLD);
  std::vector<std::string> stopping = strict;
  stopping.push_back("coupling.implicit.on_max_iterations=stop");
  const CaseSpec stop = parse_case(plate_case, "plate_in_water", stopping);
  try {
    run_case(stop, build_scene(stop), settings, MPI_COMM_WORLD);
    ADD_FAILURE() << "the run did not stop";
  } catch (const RunFailure& e) {
    EXPECT_NE(std::string(e.what()).find("the implicit coupling did not converge in coupling.implicit.max_iterations = 2"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("on_max_iterations = stop"), std::string::npos) << e.what();
  }
  if (rank == 0) std::filesystem::remove_all(dir);
}

// The run loop's time-step policy (coupling/time_step_policy.hpp) on the same participants: the fluid's stable dt
// and limit, clipped to the end time; the sub-cycles that keep the solid below its stable dt (auto), a requested
// count raised when it would exceed it; without fluid the solid's stable dt or the case's fixed one. The same
// plan on every rank.
TEST(TimeStepPolicy, FluidDtEndTimeAndSubcycles) {
  Coupled c({"coupling.scheme=explicit"});
  c.run(2);
  std::string limit;
  const Real dt_fluid = c.fluid->stable_dt(&limit), dt_solid = c.solid->stable_dt();
  ASSERT_GT(dt_fluid, 2 * dt_solid);
  const TimeStepPolicy automatic({1.0, std::nullopt, 0}, MPI_COMM_WORLD);
  StepPlan s = automatic.plan(c.t, c.fluid.get(), c.solid.get());
  EXPECT_EQ(s.dt, dt_fluid);
  EXPECT_EQ(s.limit, limit);
  EXPECT_EQ(s.n_sub, static_cast<int>(std::ceil(dt_fluid / dt_solid)));
  EXPECT_FALSE(s.subcycles_raised);
  EXPECT_EQ(s.solid_stable_dt, dt_solid);
  s = automatic.plan(1.0 - 0.25 * dt_fluid, c.fluid.get(), c.solid.get());
  EXPECT_EQ(s.limit, "end time");
  EXPECT_EQ(s.dt, 1.0 - (1.0 - 0.25 * dt_fluid));  // the time left, exactly
  const TimeStepPolicy one({1.0, std::nullopt, 1}, MPI_COMM_WORLD);
  s = one.plan(c.t, c.fluid.get(), c.solid.get());
  EXPECT_TRUE(s.subcycles_raised);
  EXPECT_LE(s.dt / s.n_sub, dt_solid);
  const TimeStepPolicy solid_only({1.0, std::nullopt, 1}, MPI_COMM_WORLD), fixed({1.0, 1e-6, 1}, MPI_COMM_WORLD);
  s = solid_only.plan(c.t, nullptr, c.solid.get());
  EXPECT_EQ(s.limit, "solid stability");
  EXPECT_EQ(s.dt, dt_solid);
  EXPECT_EQ(s.n_sub, 1);
  s = fixed.plan(c.t, nullptr, c.solid.get());
  EXPECT_EQ(s.limit, "fixed");
  EXPECT_EQ(s.dt, 1e-6);
  Real mine = automatic.plan(c.t, c.fluid.get(), c.solid.get()).dt, lo = mine, hi = mine;
  MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  EXPECT_EQ(lo, hi);
}
