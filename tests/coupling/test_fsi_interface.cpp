// Interface force of the fluid-solid coupling (seed 004 eq. 50-51, coupling/fsi_interface.hpp): a plate of
// solid particles beside water with a prescribed hydrostatic pressure field carries rho g h^2 / 2 per unit
// width, pushed away from the water; no fluid, no force; the work of the load equals the energy the solid
// gains; the sub-cycling ratio; the fluid sees the solid through the typed data the interface gives it.
#include "core/distribution.hpp"
#include "coupling/fsi_interface.hpp"
#include "io/case.hpp"
#include "io/scene.hpp"
#include "solid/solid_solver.hpp"

#include <gtest/gtest.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>

using namespace mpsfsi;

namespace {

constexpr Real rho = 1000, g = 9.81, h = 0.1, dp = 0.002;

/// Water 0.1 m deep beside a plate 12 mm thick and 0.15 m high clamped 3 dp deep into the floor of a tank
/// 0.3 m wide (as cases/dam_break_elastic_plate.yaml); `water_left`: the water is left of the plate.
CaseSpec plate_case(const bool with_water, const bool water_left, const Real gravity = g) {
  std::string bodies;
  const Real x_plate = water_left ? 0.1 : 0.15, x_water = water_left ? 0.0 : 0.162;
  if (with_water)
    bodies += fmt::format("  - {{name: water, kind: fluid, material: water, rectangle: {{min: [{}, 0], max: [{}, {}]}}}}\n",
                          x_water, x_water + 0.1, h);
  bodies += fmt::format(
      "  - {{name: plate, kind: solid, material: plate, rectangle: {{min: [{}, {}], max: [{}, 0.15]}},\n"
      "     clamp: {{min: [{}, {}], max: [{}, 0]}}}}\n",
      x_plate, -3 * dp, x_plate + 0.012, x_plate - dp, -4 * dp, x_plate + 0.012 + dp);
  const std::string yaml = fmt::format(R"(name: plate_in_water
description: "plate beside water"
source: "test"
dp: {}
domain: {{min: [-1, -1], max: [1, 1]}}
time: {{end: 1.0, cfl: 0.2}}
gravity: [0, {}]
materials:
  water: {{type: fluid, rho: 1000, nu: 1.0e-6}}
  plate: {{type: solid, rho: 2500, E: 1.0e6, nu: 0.0}}
bodies:
{}walls:
  - {{name: tank, type: box, rectangle: {{min: [0, 0], max: [0.262, 0.3]}}, open_top: true}}
)",
                                       dp, -gravity, bodies);
  return parse_case(yaml, "plate_in_water.yaml");
}

/// Hydrostatic pressure on the particles with PPE rows (fluid, walls, solid surface), as the PPE gives it.
void set_hydrostatic(ParticleSet& p) {
  auto& pressure = p.add_scalar_field("pressure");
  const auto& surface = p.scalar_field("surface");
  for (std::size_t i = 0; i < p.size(); ++i) {
    const bool row = p.kind[i] == ParticleKind::fluid || p.kind[i] == ParticleKind::wall ||
                     (p.kind[i] == ParticleKind::solid && surface[i] != 0);
    pressure[i] = row ? rho * g * std::max<Real>(0, h - p.position[i][1]) : 0.0;
  }
}

/// The sum of the interface forces the interface gives the solid.
Vec total_force(const FsiInterface& fsi) {
  Vec f = Vec::Zero();
  for (const Vec& force : fsi.interface_load().force) f += force;
  return f;
}

/// A scene of plate_case with the plate's solid (which publishes the surface flag, eq. 48), a fluid solver when
/// asked for (coupled: it takes its view of the solid from the interface), and the initialised interface.
struct PlateInWater {
  enum class Fluid { none, coupled, uncoupled };
  CaseSpec spec;
  Scene scene;
  ParticleSet& p;
  Distribution dist{MPI_COMM_SELF, {}};
  std::unique_ptr<FluidSolver> fluid;
  SolidSolver solid;
  FsiInterface fsi;

  explicit PlateInWater(const CaseSpec& case_spec, const Fluid with = Fluid::none, const FsiOptions& options = {})
      : spec(case_spec),
        scene(build_scene(spec)),
        p(scene.particles),
        fluid(with == Fluid::none ? nullptr
                                  : std::make_unique<FluidSolver>(fluid_setup(spec), p, dist,
                                                                  with == Fluid::coupled ? FsiInterface::fluid_options()
                                                                                         : FluidOptions{})),
        solid(solid_setup(spec), p),
        fsi(spec, p, options) {
    fsi.initialize();
  }
  /// Each owned solid particle's position and velocity by global id.
  std::map<GlobalId, std::pair<Vec, Vec>> solid_state() const {
    std::map<GlobalId, std::pair<Vec, Vec>> state;
    for (std::size_t i = 0; i < p.n_owned(); ++i)
      if (p.kind[i] == ParticleKind::solid) state[p.global_id[i]] = {p.position[i], p.velocity[i]};
    return state;
  }
};

}  // namespace

TEST(FsiInterface, HydrostaticForceOnAPlate) {
  for (const bool left : {true, false}) {
    PlateInWater s(plate_case(true, left));
    const ParticleSet& p = s.p;
    FsiInterface& fsi = s.fsi;
    set_hydrostatic(s.p);
    fsi.prepare_fluid_boundary();
    fsi.compute_load();
    const Vec f = total_force(fsi);
    const Real expected = rho * g * h * h / 2;  // 49.05 N per m of width
    std::printf("  water %s: F = (%.3f, %.3f) N/m, expected |Fx| = %.3f N/m\n", left ? "left" : "right", f[0], f[1], expected);
    EXPECT_NEAR(f[0], left ? expected : -expected, 0.03 * expected) << "the water pushes the plate away from it";
    EXPECT_LT(std::abs(f[1]), 0.05 * expected);
    ASSERT_EQ(fsi.bodies().size(), 1U);
    EXPECT_NEAR(fsi.bodies()[0].force[0], f[0], 1e-9 * expected);
    // Every wetted face particle carries about P dp, pushed away from the water; the data are this rank's owned
    // solid particles in local order.
    const SolidLoadData load = fsi.interface_load();
    ASSERT_EQ(load.ids, fsi.solid_ids());
    std::size_t k = 0;
    for (std::size_t i = 0; i < p.n_owned(); ++i) {
      if (p.kind[i] != ParticleKind::solid) continue;
      const Vec& f_i = load.force[k++];
      const Real y = p.position[i][1];
      if (f_i.squaredNorm() > 0 && y < h - 3 * dp && y > 3 * dp) {
        EXPECT_NEAR(f_i[0], (left ? 1 : -1) * rho * g * (h - y) * dp, 0.03 * rho * g * h * dp);
      }
    }
  }
}

TEST(FsiInterface, SeedNormalisationOverestimatesAFlatFace) {
  // Eq. 50 normalised by n~ of eq. 51 (fluid side only) gives n0 / n~ ~ 3 times the pressure force.
  FsiOptions opt;
  opt.normalisation = FsiOptions::Normalisation::seed;
  PlateInWater s(plate_case(true, true), PlateInWater::Fluid::none, opt);
  set_hydrostatic(s.p);
  s.fsi.compute_load();
  const Real ratio = total_force(s.fsi)[0] / (rho * g * h * h / 2);
  std::printf("  seed normalisation: F / (rho g h^2 / 2) = %.3f\n", ratio);
  EXPECT_GT(ratio, 2.5);
}

TEST(FsiInterface, NoFluidNoForce) {
  PlateInWater s(plate_case(false, true));
  auto& pressure = s.p.add_scalar_field("pressure");
  std::fill(pressure.begin(), pressure.end(), 1000.0);  // pressure alone does not load the plate
  s.fsi.compute_load();
  EXPECT_EQ(total_force(s.fsi), Vec::Zero());
  EXPECT_EQ(s.fsi.bodies()[0].n_wetted, 0U);
}

TEST(FsiInterface, WorkOfTheLoadEqualsTheSolidsEnergyGain) {
  PlateInWater s(plate_case(true, true, 0.0));  // no gravity on the solid: only the load works
  SolidSolver& solid = s.solid;
  FsiInterface& fsi = s.fsi;
  set_hydrostatic(s.p);
  fsi.compute_load();
  const Real e0 = solid.diagnostics().total();
  const Real dt_f = 2e-4;
  const SubcycleChoice n = choose_subcycles(0, dt_f, solid.stable_dt());
  for (int step = 0; step < 20; ++step) fsi.advance_solid(solid, step * dt_f, dt_f, n.n);
  const Real gain = solid.diagnostics().total() - e0;
  std::printf("  work %.6e J/m, energy gain %.6e J/m (%d sub-steps per step)\n", fsi.bodies()[0].work_total, gain, n.n);
  EXPECT_GT(fsi.bodies()[0].work_total, 0);
  EXPECT_NEAR(fsi.bodies()[0].work_total, gain, 0.02 * gain);
}

TEST(FsiInterface, Subcycles) {
  EXPECT_EQ(choose_subcycles(0, 1e-4, 3e-5).n, 4);
  EXPECT_FALSE(choose_subcycles(0, 1e-4, 3e-5).raised);
  EXPECT_EQ(choose_subcycles(0, 9e-5, 3e-5).n, 3);  // exactly at the limit
  EXPECT_EQ(choose_subcycles(10, 1e-4, 3e-5).n, 10);
  const SubcycleChoice c = choose_subcycles(2, 1e-4, 3e-5);
  EXPECT_EQ(c.n, 4);
  EXPECT_TRUE(c.raised);
  EXPECT_EQ(choose_subcycles(0, 1e-6, 3e-5).n, 1);
}

TEST(FsiInterface, TheFluidSeesTheSolidThroughTypedInterfaceData) {
  PlateInWater s(plate_case(true, true), PlateInWater::Fluid::coupled);
  const ParticleSet& p = s.p;
  FluidSolver& fluid = *s.fluid;
  FsiInterface& fsi = s.fsi;
  SolidBoundaryData data = fsi.prepare_fluid_boundary();
  // This rank's owned solid particles by global id, the solid's own surface flags, where it is (no step yet, so
  // no predictor) and its reference densities.
  ASSERT_EQ(data.ids, fsi.solid_ids());
  ASSERT_EQ(data.surface.size(), data.ids.size());
  ASSERT_EQ(data.position.size(), data.ids.size());
  ASSERT_EQ(data.velocity.size(), data.ids.size());
  ASSERT_TRUE(data.density_offsets);
  ASSERT_EQ(data.reference_density.size(), data.ids.size());
  const auto& surface = p.scalar_field("surface");
  std::set<GlobalId> on_surface;
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i) {
    if (p.kind[i] != ParticleKind::solid) continue;
    EXPECT_EQ(data.surface[k], surface[i] != 0 ? 1 : 0) << "solid particle " << p.global_id[i];
    EXPECT_EQ(data.position[k], p.position[i]);
    EXPECT_EQ(data.velocity[k], p.velocity[i]);
    EXPECT_GT(data.reference_density[k], 0.0);
    if (surface[i] != 0) on_surface.insert(p.global_id[i]);
    ++k;
  }
  ASSERT_GT(on_surface.size(), 10U);
  ASSERT_LT(on_surface.size(), data.ids.size());
  const auto solid_rows = [&] {
    std::set<GlobalId> rows;
    for (const LocalIndex r : fluid.row_particles())
      if (p.kind[static_cast<std::size_t>(r)] == ParticleKind::solid) rows.insert(p.global_id[static_cast<std::size_t>(r)]);
    return rows;
  };
  // The fluid gives the surface particles pressure rows and none of the others.
  fluid.set_solid_boundary(data);
  fluid.advance(0, 1e-4);
  EXPECT_EQ(solid_rows(), on_surface);
  // The fluid sees the solid where the data puts it, for one step, and leaves the solid's own state as it was: a
  // view moving away from the water at 1 m/s pulls on the water (the wetted face's pressure falls), and the
  // solid's particles are where they were.
  const auto wetted_pressure = [&] {
    const auto& pressure = p.scalar_field("pressure");
    Real sum = 0;
    int n = 0;
    for (std::size_t i = 0; i < p.n_owned(); ++i)
      if (p.kind[i] == ParticleKind::solid && surface[i] != 0 && p.position[i][0] < 0.1 + dp && p.position[i][1] > 0 &&
          p.position[i][1] < h) {
        sum += pressure[i];
        ++n;
      }
    return sum / std::max(n, 1);
  };
  const Real p_at_rest = wetted_pressure();
  const auto before = s.solid_state();
  data = fsi.prepare_fluid_boundary();
  const Vec shift = Vec::UnitX() * 1e-3;
  for (std::size_t q = 0; q < data.ids.size(); ++q) {
    data.position[q] += shift;
    data.velocity[q] = Vec::UnitX();
  }
  fluid.set_solid_boundary(data);
  fluid.advance(1e-4, 1e-4);
  const Real p_pulled = wetted_pressure();
  std::printf("  wetted face: %.1f Pa with the solid at rest, %.1f Pa when the view moves away at 1 m/s\n", p_at_rest,
              p_pulled);
  EXPECT_GT(p_at_rest, 0.2 * rho * g * h);
  EXPECT_LT(p_pulled, 0.5 * p_at_rest);
  EXPECT_EQ(s.solid_state(), before);
  // The view is the data's, not the solid's field: every particle a dummy, no solid rows.
  data = fsi.prepare_fluid_boundary();
  std::fill(data.surface.begin(), data.surface.end(), 0);
  fluid.set_solid_boundary(data);
  fluid.advance(2e-4, 1e-4);
  EXPECT_TRUE(solid_rows().empty());
  // Data that is not this rank's owned solid particles in local order is refused.
  SolidBoundaryData stale = data;
  std::swap(stale.ids.front(), stale.ids.back());
  EXPECT_THROW(fluid.set_solid_boundary(stale), std::logic_error);
  stale = data;
  stale.ids.pop_back();
  stale.surface.pop_back();
  stale.position.pop_back();
  stale.velocity.pop_back();
  stale.reference_density.pop_back();
  EXPECT_THROW(fluid.set_solid_boundary(stale), std::logic_error);
  stale = data;
  stale.reference_density.pop_back();
  EXPECT_THROW(fluid.set_solid_boundary(stale), std::logic_error);
  stale = data;
  stale.density_offsets = false;  // densities given, but no offsets asked for
  EXPECT_THROW(fluid.set_solid_boundary(stale), std::logic_error);
}

TEST(FsiInterface, AFluidBuiltWithoutACoupledSolidRefusesItsView) {
  PlateInWater s(plate_case(true, true), PlateInWater::Fluid::uncoupled);
  EXPECT_THROW(s.fluid->set_solid_boundary(s.fsi.prepare_fluid_boundary()), std::logic_error);
}

TEST(FsiInterface, AFluidStepThatThrowsGivesTheSolidItsOwnStateBack) {
  // A dt so small that the pressure system overflows: the step stops with its diagnosis after the view was placed.
  PlateInWater s(plate_case(true, true), PlateInWater::Fluid::coupled);
  const auto own = s.solid_state();
  SolidBoundaryData data = s.fsi.prepare_fluid_boundary();
  for (Vec& x : data.position) x += Vec::UnitX() * 1e-3;
  s.fluid->set_solid_boundary(data);
  EXPECT_THROW(s.fluid->advance(0, 1e-200), std::runtime_error);
  EXPECT_EQ(s.solid_state(), own);
  // The view stays usable: a new one is taken and the next step runs.
  s.fluid->set_solid_boundary(s.fsi.prepare_fluid_boundary());
  EXPECT_NO_THROW(s.fluid->advance(0, 1e-4));
  EXPECT_EQ(s.solid_state(), own);
}

TEST(FsiInterface, TheSolidTakesTheLoadAsTypedDataOfItsOwnParticles) {
  PlateInWater s(plate_case(true, true));
  const ParticleSet& p = s.p;
  SolidSolver& solid = s.solid;
  FsiInterface& fsi = s.fsi;
  set_hydrostatic(s.p);
  fsi.compute_load();
  SolidLoadData load = fsi.interface_load();
  solid.set_interface_load(load);
  const auto& held = p.vector_field(solid_fields::load);
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.n_owned(); ++i)
    if (p.kind[i] == ParticleKind::solid) {
      EXPECT_EQ(held[i], load.force[k++]);
    }
  SolidLoadData stale = load;
  std::swap(stale.ids.front(), stale.ids.back());
  EXPECT_THROW(solid.set_interface_load(stale), std::logic_error);
  stale = load;
  stale.ids.pop_back();
  stale.force.pop_back();
  EXPECT_THROW(solid.set_interface_load(stale), std::logic_error);
  stale = load;
  stale.force.pop_back();
  EXPECT_THROW(solid.set_interface_load(stale), std::logic_error);
}
