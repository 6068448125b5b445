// The case-file parser: reads a case (cases/*.yaml; schema in docs/case-format.md) with yaml-cpp,
// applies the command-line overrides (--set dotted.key=value) to the YAML tree, checks every value
// and fills a CaseSpec in SI units. Every problem is a CaseError whose message names the file, the
// line (or the --set override that caused it), the dotted key and the expected form, e.g.
//   cases/dam_break.yaml:7: dp = -0.004: expected a positive number (particle spacing in metres)
//
// The reading is built on MapReader (io/case_reader.hpp), which wraps one YAML map with its dotted path:
// each schema key is one call (required/optional number, vector, rectangle, name, choice, ...), and
// finish() reports every key that was not asked for as unknown. This file reads the sections of a case
// and holds the entry points; the bodies and walls and the geometry's cross-checks are read in
// io/case_geometry.cpp, the YAML tree and its --set overrides handled in io/case_tree.cpp.
#include "io/case.hpp"
#include "io/case_geometry.hpp"
#include "io/case_reader.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace mpsfsi {

namespace {

/// Index of the material called `name` in `materials`, or -1.
template <typename Material>
int index_by_name(const std::vector<Material>& materials, const std::string& name) {
  for (std::size_t i = 0; i < materials.size(); ++i)
    if (materials[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace

int CaseSpec::fluid_material_index(const std::string& name) const {
  return index_by_name(fluid_materials, name);
}

int CaseSpec::solid_material_index(const std::string& name) const {
  return index_by_name(solid_materials, name);
}

namespace case_detail {
namespace {

void read_time(MapReader r, TimeSpec& time) {
  time.end = r.number("end", positive, "a positive number [s]");
  time.dt = r.optional_number("dt", positive, "a positive number (fixed time step) [s]");
  time.cfl = r.optional_number("cfl", in_half_open(0, 1), "a Courant number C with 0 < C <= 1");
  const auto dt_max = r.optional_number("dt_max", positive, "a positive number (largest adaptive time step) [s]");
  r.finish();
  const Source& src = r.source();
  if (time.dt) check_time_step(r, "dt", *time.dt, time.end);
  if (dt_max && *dt_max < min_time_step)
    src.expected(r.at("dt_max"), fmt::format("a time step of at least {:g} s (largest adaptive time step) [s]", min_time_step));
  if (time.dt && time.cfl)
    src.fail(r.at("cfl"), "time: both dt and cfl are given; expected exactly one of time.dt (fixed step [s]) or "
                          "time.cfl (adaptive step)");
  if (time.dt && *time.dt > time.end)
    src.expected(r.at("dt"), fmt::format("a time step no larger than time.end = {:g} s", time.end));
  if (dt_max && time.dt)
    src.fail(r.at("dt_max"), "time.dt_max: expected only with time.cfl (it bounds the adaptive step); remove it or use cfl");
  if (dt_max) time.dt_max = *dt_max;
}

void read_materials(MapReader r, CaseSpec& spec) {
  const Source& src = r.source();
  const std::string density_form = fmt::format("a number in [{:g}, {:g}] (density) [kg/m3]", min_density, max_density);
  if (r.empty()) src.expected(r.field(), "a map of materials, e.g. water: {type: fluid, rho: 1000, nu: 1.0e-6}");
  for (const auto& [name, field] : r.items()) {
    if (!is_name(name)) src.fail(Field{field.key, field.path, field.key}, fmt::format("material name '{}': expected {}", name, name_form));
    MapReader m(src, field, "a material {type: fluid | solid, rho: ..., ...}");
    if (m.choice("type", {"fluid", "solid"}) == "fluid") {
      FluidMaterial f;
      f.name = name;
      f.rho = m.number("rho", in_closed(min_density, max_density), density_form);
      f.nu = m.number("nu", in_closed(0, max_viscosity),
                      fmt::format("a number in [0, {:g}] (kinematic viscosity) [m2/s]", max_viscosity));
      f.c = m.number("c", f.c, in_closed(min_speed, max_wave_speed),
                     fmt::format("a number in [{:g}, {:g}] (sound speed of the compressibility term) [m/s]", min_speed,
                                 max_wave_speed));
      f.kappa = m.number("kappa", f.kappa, in_half_open(0, 1), "a number in (0, 1] (relaxation of the PPE source)");
      spec.fluid_materials.push_back(f);
    } else {
      SolidMaterial s;
      s.name = name;
      s.rho = m.number("rho", in_closed(min_density, max_density), density_form);
      // Elastic constants: either E and nu, or the wave speeds vp and vs (then E and nu are the equivalents).
      if (m.has("vp") || m.has("vs")) {
        s.vp = m.number("vp", in_closed(min_speed, max_wave_speed),
                        fmt::format("a number in [{:g}, {:g}] (P-wave speed, given with vs) [m/s]", min_speed, max_wave_speed));
        s.vs = m.number("vs", in_closed(min_speed, max_wave_speed),
                        fmt::format("a number in [{:g}, {:g}] (S-wave speed, given with vp) [m/s]", min_speed, max_wave_speed));
        if (!(*s.vp > std::sqrt(4.0 / 3.0) * *s.vs))
          src.expected(m.at("vp"), fmt::format("vp > sqrt(4/3) vs = {:g} m/s (positive bulk modulus)", std::sqrt(4.0 / 3.0) * *s.vs));
        if (m.has("E") || m.has("nu"))
          src.fail(m.at(m.has("E") ? "E" : "nu"), fmt::format("{}: expected either E and nu or vp and vs, not both",
                                                               m.field().path));
        const Real mu = s.rho * *s.vs * *s.vs;
        const Real lambda = s.rho * (*s.vp * *s.vp - 2 * *s.vs * *s.vs);
        s.E = mu * (3 * lambda + 2 * mu) / (lambda + mu);
        s.nu = lambda / (2 * (lambda + mu));
      } else {
        s.E = m.number("E", in_closed(min_modulus, max_modulus),
                       fmt::format("a number in [{:g}, {:g}] (Young's modulus) [Pa]", min_modulus, max_modulus));
        s.nu = m.number("nu", in_open(-1, 0.5), "a number in (-1, 0.5) (Poisson's ratio)");
      }
      s.fracture_strain = m.optional_number("fracture_strain", positive, "a positive number (strain at which bonds break)");
      spec.solid_materials.push_back(s);
    }
    m.finish();
  }
}

#if MPSFSI_DIM == 3
/// 3D: the roll axis through the pivot (tank_motion.axis), default e_z, normalised.
void read_roll_axis(MapReader& r, TankMotionSpec& m) {
  const std::string form = "a non-zero roll axis [x, y, z] through the pivot (default [0, 0, 1]; normalised)";
  m.axis = r.vec("axis", Vec::UnitZ(), form);
  const Real length = m.axis.norm();
  if (!(length > 0 && std::isfinite(length))) r.source().expected(r.at("axis"), form);
  m.axis /= length;
}
#endif

void read_tank_motion(MapReader r, const fs::path& base_dir, CaseSpec& spec) {
  const Source& src = r.source();
  TankMotionSpec& m = spec.tank_motion;
  const std::string type = r.choice("type", "none", {"none", "sine_roll", "table"});
  if (type == "sine_roll") {
    m.type = TankMotionType::sine_roll;
    m.pivot = r.vec("pivot", point_form + " (centre of the roll)");
#if MPSFSI_DIM == 3
    read_roll_axis(r, m);
#endif
    m.amplitude = r.number("amplitude_deg", in_open(0, 90), "a number of degrees in (0, 90) (roll amplitude)") * pi / 180;
    m.period = r.number("period", positive, "a positive number (roll period) [s]");
    if (m.period < min_period) src.expected(r.at("period"), fmt::format("a roll period of at least {:g} s", min_period));
  } else if (type == "table") {
    m.type = TankMotionType::table;
    m.pivot = r.vec("pivot", point_form + " (centre of the roll)");
#if MPSFSI_DIM == 3
    read_roll_axis(r, m);
#endif
    const FileKey file = file_key(r, "file", base_dir, "the path of a CSV file of time [s], angle [deg], relative to the case file");
    m.file = file.path.string();
    TimeTable table = read_table(src, file.field, file.path, angle_table_column());
    file.name_absolute();
    m.time = std::move(table.time);
    m.angle = std::move(table.value);
    for (auto& a : m.angle) a *= pi / 180;
  }
  r.finish();
  if (m.type != TankMotionType::none && spec.walls.empty())
    src.fail(r.at("type"), fmt::format("tank_motion.type = {}: expected walls (a tank) to move", type));
  for (const auto& w : spec.walls)
    if (m.type != TankMotionType::none && w.motion.moving())
      src.fail(r.at("type"), fmt::format("tank_motion.type = {} and wall '{}' has a motion of its own: expected the tank "
                                         "to move or its walls on their own, not both",
                                         type, w.name));
}

void read_coupling(MapReader r, CouplingParameters& c) {
  const std::string form =
      fmt::format("a positive integer up to {} or auto (solid sub-steps per fluid step)", max_subcycles);
  if (const auto f = r.optional("subcycles")) {
    c.subcycles = (is_plain_scalar(f->node) && f->node.Scalar() == "auto")
                      ? 0
                      : to_int(r.source(), *f, [](const long long n) { return n >= 1 && n <= max_subcycles; }, form);
  }
  c.solid_damping = r.number("solid_damping", c.solid_damping, [](Real x) { return x >= 0; },
                             "a number >= 0 (solid bond damping time in units of dp / c_p)");
  c.load_relaxation = r.number("load_relaxation", c.load_relaxation, [](Real x) { return x > 0 && x <= 1; },
                               "a number in (0, 1] (under-relaxation of the interface load in time)");
  c.scheme = r.option("scheme", c.scheme, coupling_scheme_names());
  MapReader im = r.optional_map(
      "implicit", "a map {acceleration, relaxation, tolerance, max_iterations, reuse, max_columns, filter, on_max_iterations}");
  ImplicitCouplingParameters& ic = c.implicit;
  AccelerationParameters& a = ic.acceleration;
  a.kind = im.option("acceleration", a.kind, acceleration_kind_names());
  a.relaxation = im.number("relaxation", a.relaxation, [](Real x) { return x > 0 && x <= 1; },
                           "a number in (0, 1] (the relaxation factor of the first iteration)");
  ic.tolerance = im.number("tolerance", ic.tolerance, [](Real x) { return x > 0 && x < 1; },
                           "a number in (0, 1) (relative change of the solid's displacement between iterations)");
  ic.max_iterations = im.integer("max_iterations", ic.max_iterations, [](long long n) { return n >= 1 && n <= 1000; },
                                 "an integer from 1 to 1000 (coupled steps per time step at most)");
  a.reuse = im.integer("reuse", a.reuse, [](long long n) { return n >= 0 && n <= 1000; },
                       "an integer from 0 to 1000 (past time steps whose IQN-ILS columns are kept)");
  a.max_columns = im.integer("max_columns", a.max_columns, [](long long n) { return n >= 1 && n <= 10000; },
                             "an integer from 1 to 10000 (IQN-ILS columns at most)");
  a.filter = im.number("filter", a.filter, [](Real x) { return x >= 0 && x < 1; },
                       "a number in [0, 1) (IQN-ILS: a column nearly dependent on the newer ones by this share is left out)");
  ic.on_max_iterations = im.option("on_max_iterations", ic.on_max_iterations, non_convergence_names());
  im.finish();
  r.finish();
}

void read_parallel(MapReader r, ParallelSpec& par) {
  par.partition = r.option("partition", par.partition, partition_method_names());
  par.imbalance = r.number("imbalance", par.imbalance, [](Real x) { return x > 0 && x <= 10; },
                           "a number in (0, 10] (re-partition when the largest rank's owned particles exceed the mean "
                           "by this fraction)");
  par.skin = r.number("skin", par.skin, [](Real x) { return x >= 0 && x <= 10; },
                      "a number in [0, 10] (halo skin in units of dp: owners and ghosts are renewed when a particle "
                      "has moved half of it)");
  r.finish();
}

void read_lateral_walls(MapReader r, const TankMotionSpec& motion, LateralWallFriction& w) {
  if (!r.field().node.IsDefined() || r.field().node.IsNull()) return;
  w.gap = r.number("gap", positive, "a positive number (distance between the front and back walls) [m]");
  if (w.gap < min_gap) r.source().expected(r.at("gap"), fmt::format("a gap of at least {:g} m (distance between the front and back walls) [m]", min_gap));
  if (dim == 3)
    r.source().fail(r.at("gap"), fmt::format("{} = {}: a 3D tank has its real front and back walls (give them as walls, "
                                             "at their real distance); the lateral-wall friction is a quasi-2D model of "
                                             "them; expected no {} in a 3D case",
                                             r.path_of("gap"), show(r.at("gap").node), show_path(r.field().path)));
  w.model = r.option("model", w.model, lateral_wall_model_names());
  if (w.model == LateralWallModel::stokes) {
    const auto f = r.optional_number("frequency", positive, "a positive number (oscillation frequency) [Hz]");
    if (f)
      w.frequency = *f;
    else if (motion.type == TankMotionType::sine_roll)
      w.frequency = 1.0 / motion.period;
    else
      r.source().fail(r.field(), fmt::format("missing key 'frequency' in {}; expected: {}, a positive number [Hz] "
                                             "(model stokes needs the oscillation frequency unless tank_motion is a "
                                             "sine_roll)", show_path(r.field().path), r.path_of("frequency")));
  }
  r.finish();
}

/// Particles within a radius of `r` lattice spacings: about pi r^2 in 2D, 4/3 pi r^3 in 3D; and that
/// formula as text for messages.
Real particles_within(const Real r) { return dim == 2 ? pi * r * r : 4.0 / 3.0 * pi * r * r * r; }
const char* const particles_within_text = dim == 2 ? "pi re^2" : "4/3 pi re^3";

/// An effective radius in units of dp, in (1, max_radius_dp]: beyond, the neighbour search and the
/// operators would do about pi re^2 (3D: 4/3 pi re^3) work per particle (re = 1e6: 3e12), which the message
/// says.
Real radius_in_dp(MapReader& r, const std::string& key, const Real fallback, const std::string& what) {
  const std::string form = fmt::format("a number in (1, {:g}] ({}, in units of dp)", max_radius_dp, what);
  const auto f = r.optional(key);
  if (!f) return fallback;
  const Real re = to_real(r.source(), *f, [](Real x) { return x > 1; }, form);
  if (re > max_radius_dp)
    r.source().fail(*f, fmt::format("{} = {}: about {} = {:.2g} neighbours per particle; expected {} (at most about "
                                    "{:.0f} neighbours)",
                                    f->path, show(f->node), particles_within_text, particles_within(re), form,
                                    particles_within(max_radius_dp)));
  return re;
}

/// A stencil radius [m] (sources, receivers) of key `key`, at most max_stencil_dp dp; default 2 dp.
Real stencil_radius(MapReader& r, const std::string& key, const Real dp) {
  const std::string form = "a positive number (radius of the particle stencil; default 2 dp) [m]";
  const Real radius = r.number(key, 2 * dp, positive, form);
  if (radius > max_stencil_dp * dp)
    r.source().fail(r.at(key), fmt::format("{} = {}: {:.3g} dp, about {:.2g} particles in the stencil; expected a radius "
                                           "of at most {:g} dp = {:g} m (dp = {:g} m)",
                                           r.path_of(key), show(r.at(key).node), radius / dp,
                                           particles_within(radius / dp), max_stencil_dp, max_stencil_dp * dp, dp));
  return radius;
}

void read_fluid_numerics(MapReader r, const TankMotionSpec& motion, FluidParameters& n) {
  n.re_gradient = radius_in_dp(r, "re_gradient", n.re_gradient, "effective radius of density and gradient");
  n.re_laplacian = radius_in_dp(r, "re_laplacian", n.re_laplacian, "effective radius of the Laplacian");
  n.beta1 = r.number("beta1", n.beta1, in_half_open(0, 1), "a number in (0, 1] (free surface: n_i < beta1 n0)");
  n.beta2 = r.number("beta2", n.beta2, in_half_open(0, 1), "a number in (0, 1] (free surface: N_i < beta2 N0)");
  n.gradient = r.option("gradient", n.gradient, pressure_gradient_names());
  n.scheme = r.option("scheme", n.scheme, fluid_scheme_names());
  n.max_active_set_solves = r.integer("max_active_set_solves", n.max_active_set_solves,
                                      [](const long long k) { return k >= 1 && k <= 100; },
                                      "an integer in [1, 100] (scheme projection: the most pressure solves of one step)");
  n.projection_kernel = r.option("projection_kernel", n.projection_kernel, density_kernel_names());
  n.projection_radius = radius_in_dp(r, "projection_radius", n.projection_radius, "radius of the projection's density kernel");
  n.projection_stabilisation =
      r.number("projection_stabilisation", n.projection_stabilisation, [](Real x) { return x >= 0 && x <= 1; },
               "a number in [0, 1] (scheme projection: the share of the Laplacian in the pressure matrix)");
  if (n.scheme == FluidScheme::projection && n.gradient == PressureGradient::corrected)
    r.source().fail(r.at("gradient"), "fluid.gradient = corrected: expected min_pressure (the default) with fluid.scheme = "
                                      "projection (the default), which has its own pressure force; the corrected "
                                      "gradient needs fluid.scheme = standard");
  n.solver = r.option("solver", n.solver, krylov_solver_names());
  n.preconditioner = r.option("preconditioner", n.preconditioner, preconditioner_names());
  n.tolerance = r.number("tolerance", n.tolerance, in_open(0, 1), "a number in (0, 1) (relative residual of the pressure solve)");
  n.density_tolerance = r.number("density_tolerance", n.density_tolerance, [](Real x) { return x >= 0 && x < 1; },
                                 "a number in [0, 1) (RMS density error r dt^2 / rho at which the pressure solve "
                                 "may stop; 0: off)");
  n.max_iterations = r.integer("max_iterations", n.max_iterations, [](const long long k) { return k >= 1; },
                               "a positive integer (iterations of the pressure solve)");
  if (r.has("muelu_rebuild_every"))
    r.source().fail(r.at("muelu_rebuild_every"),
                    fmt::format("{}: this key was replaced by {} (full preconditioner setup every N steps, for every "
                                "preconditioner); rename it",
                                r.path_of("muelu_rebuild_every"), r.path_of("preconditioner_rebuild_every")));
  n.preconditioner_rebuild_every =
      r.integer("preconditioner_rebuild_every", n.preconditioner_rebuild_every, [](const long long k) { return k >= 1; },
                "a positive integer (full preconditioner setup every N steps)");
  n.coarse_size = r.number("coarse_size", n.coarse_size, [&](const Real x) { return x == 0 || x >= n.re_laplacian; },
                           fmt::format("0 or a number >= re_laplacian = {} (side of the coarse groups of the sgs / ssor "
                                       "pressure solve, in units of dp; 0: one level)",
                                       n.re_laplacian));
  n.max_loss = r.number("max_loss", n.max_loss, in_closed(0, 1),
                        "a number in [0, 1] (largest share of a fluid body's particles that may leave the domain before "
                        "the run stops)");
  read_lateral_walls(r.optional_map("lateral_walls", "a map {gap, model: stokes | poiseuille, frequency}"), motion,
                     n.lateral_walls);
  r.finish();
}

void read_solid_numerics(MapReader r, const std::vector<SolidMaterial>& materials, const Real end, SolidParameters& n) {
  n.re = radius_in_dp(r, "re", n.re, "effective radius of the bonds");
  n.dt = r.optional_number("dt", positive, "a positive number (solid time step) [s]");
  if (n.dt) check_time_step(r, "dt", *n.dt, end);
  n.plane_stress = r.boolean("plane_stress", n.plane_stress, "true (plane stress) or false (plane strain)");
  if (dim == 3 && n.plane_stress)
    r.source().fail(r.at("plane_stress"), fmt::format("{} = true: a 3D body has its real thickness; plane stress is a 2D "
                                                      "model (a section of a body free in the third direction); expected "
                                                      "false, or leave the key out",
                                                      r.path_of("plane_stress")));
  n.wide_plate = r.boolean("wide_plate", n.wide_plate,
                           "true (plane stress with the wide-plate bending modulus E / (1 - nu^2)) or false");
  if (dim == 3 && n.wide_plate)
    r.source().fail(r.at("wide_plate"), fmt::format("{} = true: a 3D plate has its real width and bends as a plate by "
                                                    "itself; the wide-plate modulus E / (1 - nu^2) is a 2D model of it; "
                                                    "expected false, or leave the key out",
                                                    r.path_of("wide_plate")));
  if (n.wide_plate && !n.plane_stress)
    r.source().fail(r.at("wide_plate"), fmt::format("{} = true: expected {}: true as well (wide_plate is the "
                                                    "plane-stress model with the bending modulus E / (1 - nu^2))",
                                                    r.path_of("wide_plate"), r.path_of("plane_stress")));
  if (n.wide_plate)
    for (const auto& m : materials)
      if (m.vp)
        r.source().fail(r.at("wide_plate"), fmt::format("{} = true: material '{}' is given by its wave speeds; expected "
                                                        "solid materials given by E and nu (wide_plate scales E)",
                                                        r.path_of("wide_plate"), m.name));
  n.dt_factor = r.number("dt_factor", n.dt_factor, in_half_open(0, 1), "a number in (0, 1] (stable dt = dt_factor dp / c_p)");
  n.contact_stiffness = r.number("contact_stiffness", n.contact_stiffness, non_negative,
                                 "a non-negative number (contact spring / nearest-neighbour bond stiffness)");
  n.normalisation = r.option("normalisation", n.normalisation, solid_normalisation_names());
  n.volumetric_strain = r.option("volumetric_strain", n.volumetric_strain, volumetric_strain_names());
  r.finish();
}

/// The solid body named by `key` of `r` (checked: it exists and is solid).
const BodySpec& solid_body(MapReader& r, const CaseSpec& spec, const std::string& key, const std::string& name) {
  const auto b = std::find_if(spec.bodies.begin(), spec.bodies.end(), [&](const BodySpec& s) { return s.name == name; });
  if (b == spec.bodies.end() || b->kind != BodyKind::solid) {
    std::vector<std::string> solids;
    for (const auto& s : spec.bodies)
      if (s.kind == BodyKind::solid) solids.push_back(s.name);
    r.source().fail(r.at(key), fmt::format("{} = {}: {}; expected a solid body (one of: {})", r.path_of(key), name,
                                           b == spec.bodies.end() ? "unknown body" : "'" + name + "' is a fluid body",
                                           solids.empty() ? std::string("none defined") : join(solids)));
  }
  return *b;
}

void read_solid_loads(MapReader& top, CaseSpec& spec) {
  const Source& src = top.source();
  std::map<std::string, std::string> names;
  for (const Field& item : top.list("solid_loads", "a list of pressure pulses, each {name, body, region, ...}", false)) {
    MapReader r(src, item, "a solid load {name, body, region, direction, peak, time, width}");
    SolidLoadSpec l;
    l.name = unique_name(r, names, "solid loads");
    l.body = r.name("body", "the name of a solid body");
    l.region = r.rect("region", rect_form + " (particles of the body inside are loaded)");
    l.direction = r.vec("direction", direction_form);
    l.peak = r.number("peak", magnitude_at_most(max_load), fmt::format("a number in [-{0:g}, {0:g}] (peak pressure) [Pa]", max_load));
    l.time = r.number("time", non_negative, "a non-negative number (time of the peak) [s]");
    l.width = r.number("width", positive, "a positive number (1/e half-width of the pulse) [s]");
    r.finish();
    if (!(l.direction.norm() > 0)) src.expected(r.at("direction"), direction_form);
    const BodySpec& b = solid_body(r, spec, "body", l.body);
    if (!overlaps(l.region, b.rect))
      src.fail(r.at("region"), fmt::format("{} = {} does not overlap body '{}' {}: expected a region that covers part of "
                                           "the body",
                                           r.path_of("region"), show_rect(l.region), b.name, show_rect(b.rect)));
    spec.solid_loads.push_back(l);
  }
}

void read_wavelet(MapReader r, const fs::path& base_dir, WaveletSpec& w) {
  const std::string type = r.choice("type", {"gaussian_derivative", "ricker", "gaussian", "table"});
  if (type == "table") {
    w.type = WaveletType::table;
    const FileKey file = file_key(r, "file", base_dir, "the path of a CSV file of time [s], value, relative to the case file");
    w.file = file.path.string();
    TimeTable table = read_table(r.source(), file.field, file.path, TimeTableColumn{});
    file.name_absolute();
    w.time = std::move(table.time);
    w.value = std::move(table.value);
  } else {
    w.type = type == "gaussian_derivative" ? WaveletType::gaussian_derivative
             : type == "ricker"            ? WaveletType::ricker
                                           : WaveletType::gaussian;
    w.frequency = r.number("frequency", positive, "a positive number (central frequency f0) [Hz]");
    w.delay = r.number("delay", 1.5 / w.frequency, non_negative,
                       "a non-negative number (delay t0 of the wavelet's centre; default 1.5 / frequency) [s]");
  }
  r.finish();
}

void read_sources(MapReader& top, const fs::path& base_dir, CaseSpec& spec) {
  const Source& src = top.source();
  std::map<std::string, std::string> names;
  for (const Field& item : top.list("sources", "a list of sources, each {name, body, type, position, ...}", false)) {
    MapReader r(src, item, "a source {name, body, type: explosion | force, position, amplitude, direction, radius, wavelet}");
    SourceSpec s;
    s.name = unique_name(r, names, "sources");
    s.body = r.name("body", "the name of a solid body");
    s.type = r.choice("type", {"explosion", "force"}) == "explosion" ? SourceType::explosion : SourceType::force;
    s.position = r.vec("position", point_form + " on the body");
    s.amplitude = r.number("amplitude", magnitude_at_most(max_load),
                           fmt::format("a number in [-{0:g}, {0:g}] {1}", max_load,
                                       s.type == SourceType::explosion ? (dim == 2 ? "(line moment M0) [N m/m]" : "(moment M0) [N m]")
                                                                       : (dim == 2 ? "(line force F0) [N/m]" : "(force F0) [N]")));
    if (s.type == SourceType::force) {
      s.direction = r.vec("direction", direction_form);
      if (!(s.direction.norm() > 0)) src.expected(r.at("direction"), direction_form);
      s.direction.normalize();
    } else if (r.has("direction")) {
      src.fail(r.at("direction"), fmt::format("{}: expected only with type: force (an explosion pushes in every "
                                              "direction); remove it",
                                              r.path_of("direction")));
    }
    s.radius = stencil_radius(r, "radius", spec.dp);
    read_wavelet(r.map("wavelet", "a map {type: gaussian_derivative | ricker | gaussian | table, frequency, delay, file}"),
                 base_dir, s.wavelet);
    r.finish();
    const BodySpec& b = solid_body(r, spec, "body", s.body);
    if (!b.rect.contains(s.position))
      src.fail(r.at("position"), fmt::format("{} = {}: expected a point on body '{}' {}", r.path_of("position"),
                                             show_vec(s.position), b.name, show_rect(b.rect)));
    spec.sources.push_back(s);
  }
}

void read_probes(MapReader& top, CaseSpec& spec) {
  const Source& src = top.source();
  std::map<std::string, std::string> names;
  for (const Field& item : top.list("probes", "a list of probes, each {name, type, position, body}", false)) {
    MapReader r(src, item, "a probe {name, type: pressure | surge_front | column_height | wave_gauge | displacement, position, body, frame}");
    ProbeSpec p;
    p.name = unique_name(r, names, "probes");
    const std::string type = r.choice("type", {"pressure", "surge_front", "column_height", "wave_gauge", "displacement"});
    p.type = type == "pressure"        ? ProbeType::pressure
             : type == "surge_front"   ? ProbeType::surge_front
             : type == "column_height" ? ProbeType::column_height
             : type == "wave_gauge"    ? ProbeType::wave_gauge
                                       : ProbeType::displacement;
    const std::string position_form = point_form + (p.type == ProbeType::displacement ? " on the body" : "");
    const bool has_position = p.type != ProbeType::surge_front || r.has("position");
    if (has_position) p.position = r.vec("position", position_form);
    if (p.type == ProbeType::displacement) {
      p.body = r.name("body", "the name of a solid body (whose displacement is measured)");
      p.frame = r.choice("frame", "global", {"global", "tank"}) == "tank" ? ProbeFrame::tank : ProbeFrame::global;
    } else if (r.has("body"))
      p.body = r.name("body", "the name of a body");
    r.finish();

    if (has_position && !spec.domain.contains(p.position))
      src.fail(r.at("position"), fmt::format("{} = {}: expected a point inside the domain {}", r.path_of("position"),
                                             show_vec(p.position), show_rect(spec.domain)));
    if (!p.body.empty()) {
      const auto b = std::find_if(spec.bodies.begin(), spec.bodies.end(), [&](const BodySpec& s) { return s.name == p.body; });
      std::vector<std::string> candidates;
      for (const auto& s : spec.bodies)
        if (p.type != ProbeType::displacement || s.kind == BodyKind::solid) candidates.push_back(s.name);
      const std::string wanted = fmt::format("the name of a{} body (one of: {})",
                                             p.type == ProbeType::displacement ? " solid" : "",
                                             candidates.empty() ? std::string("none defined") : join(candidates));
      if (b == spec.bodies.end())
        src.fail(r.at("body"), fmt::format("{} = {}: unknown body; expected {}", r.path_of("body"), p.body, wanted));
      if (p.type == ProbeType::displacement && b->kind != BodyKind::solid)
        src.fail(r.at("body"), fmt::format("{} = {}: '{}' is a fluid body; expected {}", r.path_of("body"), p.body, p.body,
                                           wanted));
      if (p.type == ProbeType::displacement && !b->rect.contains(p.position))
        src.fail(r.at("position"), fmt::format("{} = {}: expected a point on body '{}' {}", r.path_of("position"),
                                               show_vec(p.position), b->name, show_rect(b->rect)));
    }
    spec.probes.push_back(p);
  }
}

void read_receivers(MapReader r, CaseSpec& spec) {
  const Source& src = r.source();
  ReceiversSpec& rs = spec.receivers;
  rs.interval = r.optional_number("interval", positive,
                                  "a positive number (simulated time between rows of receivers.csv; default every step) [s]");
  if (rs.interval) check_interval(r, "interval", *rs.interval, true, spec.time.end, "rows");
  rs.radius = stencil_radius(r, "radius", spec.dp);
  std::map<std::string, std::string> names;
  const bool any = !r.empty();
  for (const Field& item : r.list("points", "a list of receivers, each {name, body, position}", any)) {
    MapReader p(src, item, "a receiver {name, body, position}");
    ReceiverSpec rec;
    rec.name = unique_name(p, names, "receivers");
    rec.body = p.name("body", "the name of a solid body");
    rec.position = p.vec("position", point_form + " on the body");
    p.finish();
    const BodySpec& b = solid_body(p, spec, "body", rec.body);
    if (!b.rect.contains(rec.position))
      src.fail(p.at("position"), fmt::format("{} = {}: expected a point on body '{}' {}", p.path_of("position"),
                                             show_vec(rec.position), b.name, show_rect(b.rect)));
    rs.points.push_back(rec);
  }
  r.finish();
}

void read_output(MapReader r, const Real end, OutputSpec& out) {
  out.interval = r.number("interval", out.interval, positive, "a positive number (simulated time between frames) [s]");
  check_interval(r, "interval", out.interval, r.has("interval"), end, "frames");
  out.probe_interval = r.optional_number("probe_interval", positive, "a positive number (simulated time between rows of probes.csv) [s]");
  if (out.probe_interval) check_interval(r, "probe_interval", *out.probe_interval, true, end, "probe rows");
  std::set<std::string> seen;
  for (const Field& f : r.list("fields", "a list of field names, e.g. [pressure, velocity]", false)) {
    const std::string name = to_name(r.source(), f, "a field name (" + name_form + ")");
    if (!seen.insert(name).second)
      r.source().fail(f, fmt::format("{} = {}: duplicate field; expected each field once", f.path, name));
    out.fields.push_back(name);
  }
  r.finish();
}

/// The case's `dimension` (2 or 3, default 2) must be the build's. Checked before any other key, so that
/// a case of the other dimension is refused for that and not for its first vector.
void check_dimension(const Source& src, const MapReader& top) {
  const std::optional<Field> f = top.peek("dimension");
  const int d = f ? to_int(src, *f, [](const long long k) { return k == 2 || k == 3; },
                           "2 or 3 (the spatial dimension of the case; default 2)")
                  : 2;
  if (d == dim) return;
  const std::string what_to_do =
      dim == 2 ? "expected a 2D case (dimension: 2, the default); 3D cases run in the 3D program, which mpsfsi starts when it "
                 "was built beside it (<build>/3d/mpsfsi, CMake option MPSFSI_WITH_3D)"
               : "expected a 3D case (dimension: 3); 2D cases run in the 2D program (<build>/mpsfsi, which starts this one for "
                 "3D cases)";
  src.fail(f ? *f : top.field(), fmt::format("dimension = {}{}: this mpsfsi is built for {}D (MPSFSI_DIM={}); {}", d,
                                             f ? "" : " (the default)", dim, dim, what_to_do));
}

CaseSpec read_case(const Source& src, const YAML::Node& root, const fs::path& base_dir) {
  CaseSpec spec;
  MapReader top(src, Field{root, ""}, "a map of case keys (name, description, source, dp, domain, time, ...)");
  check_dimension(src, top);
  spec.name = top.name("name", "the case name: " + name_form);
  // Optional: a user's own case has no paper (the shipped cases give both; test shipped_cases_name_their_source).
  spec.description = top.text("description", "", "a one-line description of the case");
  spec.source = top.text("source", "", "where the geometry and data come from (paper, experiment)");
  spec.dp = top.number("dp", positive, "a positive number (particle spacing in metres)");
  spec.domain = top.rect("domain", rect_form + " (particles leaving it are removed)");
  read_time(top.map("time", "a map {end, dt or cfl, dt_max} in seconds"), spec.time);
  spec.gravity = top.vec("gravity", Vec::Zero(), "a vector " + components("g") + " in m/s2");
  if (!(spec.gravity.norm() <= max_gravity))
    src.expected(top.at("gravity"), fmt::format("a vector {} in m/s2 of magnitude at most {:g} m/s2 (1000 g)", components("g"), max_gravity));
  spec.gravity_ramp = top.number("gravity_ramp", 0.0, non_negative,
                                 "a non-negative time [s] over which gravity rises from 0 (0: at once)");
  read_materials(top.map("materials", "a map of materials, e.g. water: {type: fluid, rho: 1000, nu: 1.0e-6}"), spec);

  std::map<std::string, std::string> body_and_wall_names;
  GeometryFields geometry;
  read_bodies(top, spec, body_and_wall_names, geometry, base_dir);
  read_walls(top, spec, body_and_wall_names, geometry, base_dir);
  // The fluid needs a time step rule; a solid-only case may use the solid's own (solid.dt or stable dt).
  const bool has_fluid = std::any_of(spec.bodies.begin(), spec.bodies.end(),
                                     [](const BodySpec& b) { return b.kind == BodyKind::fluid; });
  if (has_fluid && !spec.time.dt && !spec.time.cfl)
    src.fail(top.at("time"), "missing key 'dt' or 'cfl' in time; expected exactly one of: time.dt, a positive number [s]; "
                             "or time.cfl, a Courant number C with 0 < C <= 1 (needed with fluid bodies)");
  check_body_materials(src, spec, geometry);
  check_geometry(src, spec, geometry, top.at("dp"));
  assign_clamp_walls(src, spec, geometry);

  read_tank_motion(top.optional_map("tank_motion", "a map {type: none | sine_roll | table, ...}"), base_dir, spec);
  read_coupling(top.optional_map("coupling", "a map {scheme, implicit, subcycles, solid_damping, load_relaxation}"), spec.coupling);
  read_parallel(top.optional_map("parallel", "a map {partition, imbalance, skin}"), spec.parallel);
  read_fluid_numerics(top.optional_map("fluid", "a map of fluid numerics {re_gradient, re_laplacian, ...}"), spec.tank_motion,
                      spec.fluid);
  read_solid_numerics(top.optional_map("solid", "a map of solid numerics {re, dt, plane_stress, ...}"), spec.solid_materials,
                      spec.time.end, spec.solid);
  read_solid_loads(top, spec);
  read_sources(top, base_dir, spec);
  read_probes(top, spec);
  read_receivers(top.optional_map("receivers", "a map {interval, radius, points: [{name, body, position}, ...]}"), spec);
  read_output(top.optional_map("output", "a map {interval, probe_interval, fields}"), spec.time.end, spec.output);
  top.has("dimension");  // checked first (check_dimension); listed last among the known keys
  top.finish();
  return spec;
}

CaseSpec parse(const std::string& text, const std::string& file, const fs::path& base_dir,
               const std::vector<std::string>& overrides) {
  Source src(file);
  try {
    YAML::Node root = load_yaml(text, file);
    if (!root.IsMap())
      src.expected(Field{root, ""}, "a map of case keys (name, description, source, dp, domain, time, ...)");
    for (const auto& o : overrides) apply_override(root, o, src);
    CaseSpec spec = read_case(src, root, base_dir);
    spec.file = file;
    spec.resolved_yaml = emit(root);
    return spec;
  } catch (const YAML::Exception& e) {
    // Safety net: the reader checks node types before use, so this is not expected.
    const std::string where = e.mark.is_null() ? file : fmt::format("{}:{}", file, e.mark.line + 1);
    throw CaseError(fmt::format("{}: {}", where, e.msg));
  }
}

}  // namespace
}  // namespace case_detail

namespace fs = std::filesystem;
using case_detail::max_case_bytes;
using case_detail::parse;

int peek_case_dimension(const std::string& text_or_path, const bool from_file) {
  std::error_code ec;
  if (from_file && !fs::is_regular_file(text_or_path, ec)) return 0;  // not read here (a FIFO would block)
  try {
    const YAML::Node root = from_file ? YAML::LoadFile(text_or_path) : YAML::Load(text_or_path);
    if (!root.IsMap() || !root["dimension"]) return 2;
    const YAML::Node d = root["dimension"];
    if (!d.IsScalar()) return 0;
    return d.Scalar() == "2" ? 2 : d.Scalar() == "3" ? 3 : 0;
  } catch (const std::exception&) {
    return 0;
  }
}

CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw CaseError(fmt::format("{}: cannot read the case file: {}", path, fs::exists(path, ec) ? "not a regular file" : "no such file"));
  const auto size = fs::file_size(path, ec);
  if (!ec && size > max_case_bytes)
    throw CaseError(fmt::format("{}: cannot read the case file: it has {} bytes; expected a case file of at most {} MiB",
                                path, size, max_case_bytes >> 20));
  std::ifstream in(path, std::ios::binary);
  if (!in.is_open()) throw CaseError(fmt::format("{}: cannot read the case file: cannot open it", path));
  std::ostringstream text;
  text << in.rdbuf();
  const fs::path dir = fs::path(path).parent_path();
  return parse(text.str(), path, dir.empty() ? fs::path(".") : dir, overrides);
}

CaseSpec parse_case(const std::string& yaml_text, const std::string& name, const std::vector<std::string>& overrides,
                    const std::string& base_dir) {
  return parse(yaml_text, name, fs::path(base_dir.empty() ? std::string(".") : base_dir), overrides);
}

}  // namespace mpsfsi
