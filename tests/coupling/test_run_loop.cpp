// Unit tests of the run loop (coupling/simulation.cpp) on small cases: the output times never stall, a fluid
// body that falls out of the domain stops the run, the fluid's dt limits (acceleration, end time), the
// projection of a run's cost, and the diagnosis of a pressure system that overflows.
#include "core/distribution.hpp"
#include "coupling/simulation.hpp"
#include "fluid/fluid_solver.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"
#include "io/vtk_writer.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <filesystem>
#include <string>

using namespace mpsfsi;
using ::testing::HasSubstr;

namespace {

/// A water block of 10 x 10 particles in a box, 1 cm spacing; `extra` is appended to the case text.
std::string water_case(const std::string& time, const std::string& extra = "") {
  return "name: block\ndescription: a water block\nsource: tests\ndp: 0.01\n"
         "domain: {min: [-0.05, -0.05], max: [0.25, 0.25]}\ntime: " + time + "\ngravity: [0, -9.81]\n"
         "materials:\n  water: {type: fluid, rho: 1000, nu: 1.0e-6, c: 20}\n"
         "bodies:\n  - {name: water, kind: fluid, material: water, rectangle: {min: [0, 0], max: [0.1, 0.1]}}\n"
         "walls:\n  - {name: tank, type: box, rectangle: {min: [0, 0], max: [0.2, 0.2]}}\n"
         "fluid: {preconditioner: jacobi}\n" + extra;
}

std::string fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("mpsfsi_test_run_loop_" + name);
  std::filesystem::remove_all(dir);
  return dir.string();
}

RunSettings quiet_settings(const std::string& dir) {
  RunSettings s;
  s.output_dir = dir;
  s.quiet = true;
  return s;
}

}  // namespace

// An output interval below the resolution of t (1e-300 s) gives a frame after every step and ends; it used to
// loop forever in the advance of the next output time.
TEST(RunLoop, OutputIntervalBelowTheResolutionOfTimeDoesNotStall) {
  CaseSpec spec = parse_case(water_case("{end: 5.0e-3, dt: 1.0e-3}"), "block.yaml");
  spec.output.interval = 1e-300;
  const std::string dir = fresh_dir("interval");
  const RunSummary s = run_case(spec, build_scene(spec), quiet_settings(dir), MPI_COMM_SELF);
  EXPECT_EQ(s.n_steps, 5u);
  EXPECT_EQ(read_pvd(dir + "/particles.pvd").size(), 6u);  // t = 0 and after each step
}

// Output times are the multiples of the interval (accumulated), one frame per interval however dt falls.
TEST(RunLoop, OneFramePerInterval) {
  CaseSpec spec = parse_case(water_case("{end: 1.0e-2, dt: 1.0e-3}"), "block.yaml");
  spec.output.interval = 2.5e-3;
  const std::string dir = fresh_dir("frames");
  run_case(spec, build_scene(spec), quiet_settings(dir), MPI_COMM_SELF);
  const auto frames = read_pvd(dir + "/particles.pvd");
  ASSERT_EQ(frames.size(), 5u);  // 0, 3, 5, 8, 10 ms: the first step at or past each multiple of 2.5 ms
  EXPECT_NEAR(frames[1].first, 3e-3, 1e-12);
  EXPECT_NEAR(frames[4].first, 1e-2, 1e-12);
}

// A run whose end time falls between two output times still ends with a frame of its last state.
TEST(RunLoop, EndTimeBetweenOutputTimesWritesTheEndState) {
  CaseSpec spec = parse_case(water_case("{end: 7.0e-3, dt: 1.0e-3}"), "block.yaml");
  spec.output.interval = 5e-3;
  const std::string dir = fresh_dir("end_frame");
  const RunSummary s = run_case(spec, build_scene(spec), quiet_settings(dir), MPI_COMM_SELF);
  EXPECT_EQ(s.n_steps, 7u);
  const auto frames = read_pvd(dir + "/particles.pvd");
  ASSERT_EQ(frames.size(), 3u);  // 0, 5 ms and the end, 7 ms
  EXPECT_NEAR(frames[1].first, 5e-3, 1e-12);
  EXPECT_NEAR(frames[2].first, 7e-3, 1e-12);
}

// Without walls the block falls out of the domain: the run stops (RunFailure) once more than fluid.max_loss of
// it has left, naming the body and the limit; with max_loss = 1 it runs to the end.
TEST(RunLoop, FluidBodyThatFallsOutOfTheDomainStopsTheRun) {
  const std::string no_walls = "name: drop\ndescription: a falling block\nsource: tests\ndp: 0.01\n"
                               "domain: {min: [-0.05, -0.02], max: [0.15, 0.15]}\ntime: {end: 0.5, dt: 1.0e-3}\n"
                               "gravity: [0, -9.81]\nmaterials:\n  water: {type: fluid, rho: 1000, nu: 1.0e-6}\n"
                               "bodies:\n  - {name: water, kind: fluid, material: water, "
                               "rectangle: {min: [0, 0], max: [0.1, 0.1]}}\nfluid: {preconditioner: jacobi}\n";
  CaseSpec spec = parse_case(no_walls, "drop.yaml");
  try {
    run_case(spec, build_scene(spec), quiet_settings(fresh_dir("loss")), MPI_COMM_SELF);
    FAIL() << "the run did not stop";
  } catch (const RunFailure& e) {
    EXPECT_THAT(e.what(), HasSubstr("of fluid body 'water' have left the domain"));
    EXPECT_THAT(e.what(), HasSubstr("more than fluid.max_loss = 5 %"));
  }
  spec.fluid.max_loss = 1;
  const RunSummary s = run_case(spec, build_scene(spec), quiet_settings(fresh_dir("loss_allowed")), MPI_COMM_SELF);
  EXPECT_EQ(s.n_removed, 100u);
}

// Seed 004 eq. 52 for a particle that starts at rest: dt <= sqrt(C dp / |g|); the viscous limit below it wins.
TEST(FluidStableDt, AccelerationLimit) {
  TimeSpec time;
  time.cfl = 0.2;
  time.dt_max = 1e10;
  std::string limit;
  EXPECT_DOUBLE_EQ(fluid_stable_dt(time, 0.004, 1e-6, 9.81, 0, 0.2, &limit), std::sqrt(0.2 * 0.004 / 9.81));
  EXPECT_EQ(limit, "acceleration");
  EXPECT_DOUBLE_EQ(fluid_stable_dt(time, 0.004, 1e-6, 9.81, 10, 0.2, &limit), 0.2 * 0.004 / 10);
  EXPECT_EQ(limit, "cfl");
  EXPECT_DOUBLE_EQ(fluid_stable_dt(time, 0.004, 1e3, 9.81, 0, 0.2, &limit), 0.2 * 0.004 * 0.004 / 1e3);
  EXPECT_EQ(limit, "viscous");
  time.dt_max = 1e-3;
  EXPECT_DOUBLE_EQ(fluid_stable_dt(time, 0.004, 1e-6, 9.81, 0, 0.2, &limit), 1e-3);
  EXPECT_EQ(limit, "dt_max");
  time.dt = 1e-5;
  EXPECT_DOUBLE_EQ(fluid_stable_dt(time, 0.004, 1e-6, 9.81, 100, 0.2, &limit), 1e-5);
  EXPECT_EQ(limit, "fixed");
}

// With dt_max = 1e10 s the first step is limited by the gravity, not by the end time: the water stays in the
// tank (it used to take one 0.3 s step and fall through the floor).
TEST(RunLoop, FirstStepLimitedByGravity) {
  CaseSpec spec = parse_case(water_case("{end: 0.05, cfl: 0.2, dt_max: 1.0}"), "block.yaml");
  spec.time.dt_max = 1e10;
  const RunSummary s = run_case(spec, build_scene(spec), quiet_settings(fresh_dir("gravity_dt")), MPI_COMM_SELF);
  EXPECT_EQ(s.n_removed, 0u);
  EXPECT_GT(s.n_steps, 3u);
}

// The projection counts steps and solid sub-steps at the first dt, and calls 1e12 particle-steps absurd.
TEST(RunProjection, CountsStepsAndFlagsAbsurdRuns) {
  CaseSpec spec = parse_case(water_case("{end: 1.0, dt: 1.0e-3}"), "block.yaml");
  const Scene scene = build_scene(spec);
  RunProjection r = project_run(spec, scene.particles);
  EXPECT_DOUBLE_EQ(r.dt, 1e-3);
  EXPECT_EQ(r.limit, "fixed");
  EXPECT_NEAR(r.n_steps, 1000, 1e-9);
  EXPECT_NEAR(r.particle_steps, 1000.0 * static_cast<double>(scene.particles.size()), 1e-6);
  EXPECT_FALSE(r.absurd);
  spec.time.dt = 1e-12;
  r = project_run(spec, scene.particles);
  EXPECT_TRUE(r.absurd);
  EXPECT_THAT(r.text(), HasSubstr("warning:"));
}

// A dt that makes rho / dt^2 overflow gives a diagnosis naming dt, not the Krylov solver's NaN text.
TEST(FluidSolver, OverflowingPressureSystemNamesDt) {
  CaseSpec spec = parse_case(water_case("{end: 1.0, dt: 1.0e-3}"), "block.yaml");
  Scene scene = build_scene(spec);
  Distribution self(MPI_COMM_SELF, {});
  FluidSolver fluid(fluid_setup(spec), scene.particles, self);
  try {
    fluid.advance(0, 1e-300);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("the pressure system is not finite at dt = 1e-300 s"));
  }
}
