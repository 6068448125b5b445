// The geometry of a case: bodies and walls (rectangles, spheres, cylinders, closed surfaces), the walls' own
// motion and wave makers, and the cross-checks of the whole geometry (inside the domain, overlaps, clamps,
// materials).
#include "io/case_geometry.hpp"

#include "io/surface.hpp"

#include <cmath>
#include <limits>

namespace mpsfsi {

Rect RoundShape::bounds() const {
  if (kind == Kind::sphere) return {centre - Vec::Constant(radius), centre + Vec::Constant(radius)};
  // The end discs' extents along each coordinate axis: radius sqrt(1 - e_a^2).
  const Vec e = axis.normalized();
  Vec reach;
  for (int a = 0; a < dim; ++a) reach[a] = radius * std::sqrt(std::max(Real(0), 1 - e[a] * e[a]));
  return {centre.cwiseMin(centre + axis) - reach, centre.cwiseMax(centre + axis) + reach};
}

Rect free_part(const BodySpec& b) {
  Rect r = b.rect;
  if (!b.clamp) return r;
  const Rect& c = *b.clamp;
  for (int a = 0; a < dim; ++a) {
    // The clamp cuts along axis a when it spans every other axis fully.
    bool spans = true;
    for (int o = 0; o < dim; ++o)
      if (o != a && (c.lo[o] > r.lo[o] || c.hi[o] < r.hi[o])) spans = false;
    if (!spans) continue;
    if (c.lo[a] <= r.lo[a] && c.hi[a] < r.hi[a]) r.lo[a] = std::max(r.lo[a], c.hi[a]);
    else if (c.hi[a] >= r.hi[a] && c.lo[a] > r.lo[a]) r.hi[a] = std::min(r.hi[a], c.lo[a]);
  }
  return r;
}

namespace case_detail {

namespace {

const std::string sphere_form = std::string(dim == 2 ? "a disc" : "a ball") + " {centre: " + components() +
                                ", radius: R} in metres";
const std::string cylinder_form = "a cylinder {base: " + components() + ", axis: " + components() +
                                  ", radius: R} in metres (base: the centre of one end; axis: from there to the other end)";

/// The sphere or cylinder under `key` ("sphere" or "cylinder") of r: a point, a non-zero axis, a positive radius.
RoundShape read_round(MapReader& r, const std::string& key) {
  const bool sphere = key == "sphere";
  const std::string& form = sphere ? sphere_form : cylinder_form;
  MapReader m(r.source(), r.required(key, form), form);
  RoundShape s;
  s.kind = sphere ? RoundShape::Kind::sphere : RoundShape::Kind::cylinder;
  s.centre = m.vec(sphere ? "centre" : "base", point_form);
  if (!sphere) {
    const std::string axis_form = "a non-zero axis " + components() + " in metres, from the base to the other end";
    s.axis = m.vec("axis", axis_form);
    if (!(s.axis.norm() > 0)) r.source().expected(m.at("axis"), axis_form);
  }
  s.radius = m.number("radius", positive, "a positive radius in metres");
  m.finish();
  return s;
}

/// The key of a body or wall given by a closed surface: an STL or OBJ file in 3D, a polygon in 2D.
const std::string surface_key = dim == 2 ? "polygon" : "surface";
const std::string surface_form =
    dim == 2 ? "a polygon {points: [[x, y], ...] or file: a text file of x y lines (relative to the case file), scale: "
               "s or [sx, sy], rotate: degrees, translate: [x, y]} in metres (scaled, rotated about the origin, then "
               "translated)"
             : "a surface {file: an STL or OBJ file (relative to the case file), scale: s or [sx, sy, sz], rotate: "
               "[rx, ry, rz] degrees about x, then y, then z, translate: [x, y, z]} in metres (scaled, rotated about the "
               "origin, then translated)";

/// The closed surface under surface_key of r, read, transformed and checked (io/surface.hpp).
std::shared_ptr<const ClosedSurface> read_surface(MapReader& r, const fs::path& base_dir) {
  const Source& src = r.source();
  const Field field = r.required(surface_key, surface_form);
  MapReader m(src, field, surface_form);
  SurfaceTransform t;
  if (const auto f = m.optional("scale")) {
    const std::string form = "a positive scale factor s or " + components() + " of positive factors";
    if (is_plain_scalar(f->node)) t.scale = Vec::Constant(to_real(src, *f, positive, form));
    else t.scale = to_vec(src, *f, form);
    if (!(t.scale.array() > 0).all()) src.expected(*f, form);
  }
#if MPSFSI_DIM == 2
  t.rotate_deg[0] = m.number("rotate", 0, any_number, "an angle in degrees (counter-clockwise about the origin)");
#else
  t.rotate_deg = m.vec("rotate", Vec::Zero(), "angles [rx, ry, rz] in degrees (about x, then y, then z)");
#endif
  t.translate = m.vec("translate", Vec::Zero(), "a translation " + components() + " in metres");
  const bool has_points = dim == 2 && m.has("points");
  const bool has_file = m.has("file");
  if (!has_points && !has_file) m.finish();  // an unknown key (e.g. a 2D polygon's points in 3D) said first
  if (has_points == has_file)
    src.fail(field, fmt::format("{}: {}; expected {}", field.path,
                                has_file ? "both points and file given" : dim == 2 ? "neither points nor file given" : "no file given",
                                surface_form));
  try {
    std::shared_ptr<const ClosedSurface> surface;
    if (has_points) {
      std::vector<Vec> points;
      for (const Field& item : m.list("points", "a list of points [[x, y], ...] in metres", true))
        points.push_back(to_vec(src, item, "a point [x, y] in metres"));
      m.finish();
      surface = ClosedSurface::from_polygon(std::move(points), t);
    } else {
      const FileKey file = file_key(m, "file", base_dir, "the path of " + std::string(dim == 2 ? "a text file of x y lines" : "an STL or OBJ file") +
                                                             ", relative to the case file");
      m.finish();
      surface = ClosedSurface::from_file(file.path.string(), t);
      file.name_absolute();
    }
    return surface;
  } catch (const SurfaceError& e) {
    src.fail(field, fmt::format("{}: {}", field.path, e.what()));
  }
}

const std::string wall_motion_form =
    "a motion {translation: {type: velocity, velocity: " + components() + "} or {type: sine, amplitude: " + components() +
    ", period} or {type: table, file, direction}, rotation: {type: sine, pivot: " + components() +
    (dim == 3 ? ", axis: [x, y, z]" : "") + ", amplitude_deg, period} or {type: table, file, pivot" +
    (dim == 3 ? ", axis" : "") + "}, start, ramp, stop} or {wave_maker: {type: piston | flap, stroke, period, direction, "
    "hinge, water_level}, start, ramp, stop} (times in s)";

/// A wall's motion table (translation or rotation `type: table`): `file` (relative to the case file) and the
/// velocities' `half_window`; the rows' times from `start`. A translation's table may change by at most
/// max_speed between two rows.
std::pair<TimeTable, Real> read_motion_table(MapReader& r, const fs::path& base_dir, const TimeTableColumn& column,
                                             const bool translation) {
  const Source& src = r.source();
  const FileKey file = file_key(r, "file", base_dir, fmt::format("the path of a CSV file of time [s] (from start), {}, relative to the case file", column.name));
  TimeTable table = read_table(src, file.field, file.path, column);
  const Real h = r.number("half_window", 0.025, positive,
                          "a positive time [s]: the half width of the centred difference that gives the velocity (default 0.025)");
  const Real speed = TableSeries(table.time, table.value, h).largest_rate();
  if (translation && !(speed <= max_speed))
    src.expected(file.field, fmt::format("a table whose displacement changes at most {:g} m/s (it changes at {:.4g} m/s)", max_speed, speed));
  file.name_absolute();
  return {std::move(table), h};
}

const std::string wave_maker_form = "a wave maker {type: piston | flap, stroke, period, direction, hinge, water_level}";

/// A wave maker's paddle motion by its stroke S (peak to peak; a flap's at the still water level) and period T,
/// the waves running along the horizontal `direction`: a piston translates by (S/2) sin(2 pi tau / T) along it; a
/// flap turns about its hinge line (through `hinge`, horizontal and across the direction) by theta = atan(S / (2 d))
/// sin(2 pi tau / T), d the still water level above the hinge, its top moving along the direction first.
void read_wave_maker(MapReader w, WallMotionSpec& m) {
  const Source& src = w.source();
  const bool piston = w.choice("type", {"piston", "flap"}) == "piston";
  const Real stroke = w.number("stroke", positive, "the paddle's stroke S > 0 [m] (peak to peak; a flap's at the still water level)");
  const Real period = w.number("period", positive, "a positive period [s]");
  if (period < min_period) src.expected(w.at("period"), fmt::format("a period of at least {:g} s", min_period));
  const std::string direction_form = "a horizontal direction " + components() + " (the last component 0; default [1, 0" +
                                     (dim == 3 ? ", 0" : "") + "]; normalised): the waves run along it";
  Vec direction = w.vec("direction", Vec::UnitX(), direction_form);
  if (!(direction.norm() > 0 && std::isfinite(direction.norm()) && direction[dim - 1] == 0))
    src.expected(w.at("direction"), direction_form);
  direction.normalize();
  if (piston) {
    m.translation = WallMotionSpec::Translation::sine;
    m.amplitude = 0.5 * stroke * direction;
    m.period = period;
  } else {
    m.rotation = WallMotionSpec::Rotation::sine;
    m.pivot = w.vec("hinge", point_form + " (a point on the flap's hinge line)");
    const Real level = w.number("water_level", any_number, "the still water level [m] (the height at which the stroke is measured)");
    const Real depth = level - m.pivot[dim - 1];
    if (!(depth > 0))
      src.expected(w.at("water_level"), fmt::format("a still water level above the hinge (height {:g} m)", m.pivot[dim - 1]));
    const Real amplitude = std::atan(0.5 * stroke / depth);
#if MPSFSI_DIM == 3
    m.axis = Vec(-direction[1], direction[0], 0);  // e_z x direction: a positive angle moves the top along the direction
    m.angle_amplitude = amplitude;
#else
    m.angle_amplitude = -direction[0] * amplitude;  // about e_z: clockwise moves the top along +x
#endif
    m.angle_period = period;
  }
  w.finish();
}

/// A wall's own motion (core/wall_motion.hpp): a translation, a rotation or both, from `start`, ramped up over
/// `ramp`, frozen at `stop`.
WallMotionSpec read_wall_motion(MapReader r, const fs::path& base_dir) {
  const Source& src = r.source();
  WallMotionSpec m;
  if (r.has("wave_maker")) {
    for (const char* key : {"translation", "rotation"})
      if (r.has(key))
        src.fail(r.at(key), fmt::format("{}: a wall's motion is a wave_maker or a translation and rotation; expected one of them",
                                        r.path_of(key)));
    read_wave_maker(MapReader(src, r.at("wave_maker"), wave_maker_form), m);
  }
  MapReader t = r.optional_map("translation", "a translation {type: velocity, velocity} or {type: sine, amplitude, period} "
                                              "or {type: table, file, direction}");
  if (!t.empty()) {
    const std::string type = t.choice("type", {"velocity", "sine", "table"});
    if (type == "table") {
      m.translation = WallMotionSpec::Translation::table;
      const std::string direction_form = "a non-zero direction " + components() + " (normalised): the wall moves along it by the table's displacement";
      m.direction = t.vec("direction", direction_form);
      if (!(m.direction.norm() > 0 && std::isfinite(m.direction.norm()))) src.expected(t.at("direction"), direction_form);
      m.direction.normalize();
      auto [table, h] = read_motion_table(t, base_dir, {"displacement [m]", 1e3, "a displacement in (-1000, 1000) m"}, true);
      m.table_time = std::move(table.time);
      m.table_value = std::move(table.value);
      m.table_half_window = h;
    } else if (type == "velocity") {
      m.translation = WallMotionSpec::Translation::velocity;
      m.velocity = t.vec("velocity", "the velocity " + components("v") + " in m/s after the ramp");
      if (!(m.velocity.norm() <= max_speed))
        src.expected(t.at("velocity"), fmt::format("a velocity {} in m/s of magnitude at most {:g} m/s", components("v"), max_speed));
    } else {
      m.translation = WallMotionSpec::Translation::sine;
      m.amplitude = t.vec("amplitude", "the displacement's amplitude " + components() + " in metres");
      m.period = t.number("period", positive, "a positive period [s]");
      if (m.period < min_period) src.expected(t.at("period"), fmt::format("a period of at least {:g} s", min_period));
    }
    t.finish();
  }
  MapReader q = r.optional_map("rotation", "a rotation {type: sine, pivot, amplitude_deg, period} or {type: table, file, pivot}");
  if (!q.empty()) {
    const bool table = q.choice("type", {"sine", "table"}) == "table";
    m.rotation = table ? WallMotionSpec::Rotation::table : WallMotionSpec::Rotation::sine;
    m.pivot = q.vec("pivot", point_form + " (the centre of the rotation at rest)");
#if MPSFSI_DIM == 3
    const std::string axis_form = "a non-zero rotation axis [x, y, z] through the pivot (default [0, 0, 1]; normalised)";
    m.axis = q.vec("axis", Vec::UnitZ(), axis_form);
    if (!(m.axis.norm() > 0)) src.expected(q.at("axis"), axis_form);
    m.axis.normalize();
#endif
    if (table) {
      auto [rows, h] = read_motion_table(q, base_dir, angle_table_column(), false);
      for (auto& a : rows.value) a *= pi / 180;
      m.angle_time = std::move(rows.time);
      m.angle_value = std::move(rows.value);
      m.angle_half_window = h;
    } else {
      m.angle_amplitude = q.number("amplitude_deg", in_open(-90, 90), "a number of degrees in (-90, 90) (the amplitude)") * pi / 180;
      m.angle_period = q.number("period", positive, "a positive period [s]");
      if (m.angle_period < min_period) src.expected(q.at("period"), fmt::format("a period of at least {:g} s", min_period));
    }
    q.finish();
  }
  m.start = r.number("start", 0, non_negative, "a time >= 0 [s] (the motion starts)");
  m.ramp = r.number("ramp", 0, non_negative, "a time >= 0 [s] (the velocity or amplitude rises smoothly over it)");
  if (const auto f = r.optional("stop")) {
    m.stop = to_real(src, *f, positive, "a time > start [s] (the motion stops, the wall stays)");
    if (!(m.stop > m.start)) src.expected(*f, "a time > start [s] (the motion stops, the wall stays)");
  }
  r.finish();
  if (!m.moving()) src.fail(r.field(), fmt::format("{}: no translation and no rotation; expected {}", r.field().path, wall_motion_form));
  return m;
}

const std::string body_shapes = "rectangle | sphere | cylinder | " + surface_key;

/// inner lies in outer, to `tolerance` (a rotated surface's bounds carry round-off: cos 90 degrees is 6e-17).
bool inside(const Rect& inner, const Rect& outer, const Real tolerance = 0) {
  return (inner.lo.array() >= outer.lo.array() - tolerance).all() && (inner.hi.array() <= outer.hi.array() + tolerance).all();
}

/// Inside a box: within its inner rectangle; an open box does not bound the top.
bool inside_box(const Rect& r, const WallSpec& box, const Real tolerance) {
  Rect bound = box.rect;
  if (box.open_top) bound.hi[dim - 1] = std::numeric_limits<Real>::infinity();
  return inside(r, bound, tolerance);
}

/// The interiors of a and b intersect by more than `tolerance` along every axis.
bool overlap_beyond(const Rect& a, const Rect& b, const Real tolerance) {
  return (a.lo.array() < b.hi.array() - tolerance).all() && (b.lo.array() < a.hi.array() - tolerance).all();
}

}  // namespace

void read_bodies(MapReader& top, CaseSpec& spec, std::map<std::string, std::string>& names, GeometryFields& g,
                 const fs::path& base_dir) {
  const Source& src = top.source();
  const std::string form = "a list of bodies, each {name, kind: fluid | solid, material, " + body_shapes + ", ...}";
  for (const Field& item : top.list("bodies", form, true)) {
    MapReader r(src, item, "a body {name, kind: fluid | solid, material, " + body_shapes + ", subtract, ...}");
    BodySpec b;
    b.name = unique_name(r, names, "bodies and walls");
    b.kind = r.choice("kind", {"fluid", "solid"}) == "solid" ? BodyKind::solid : BodyKind::fluid;
    b.material = r.name("material", "the name of a material of the body's kind");
    // The shape: a rectangle, a sphere, a cylinder or a closed surface, exactly one.
    std::string shape;
    for (const std::string& key : {std::string("rectangle"), std::string("sphere"), std::string("cylinder"), surface_key}) {
      if (!r.has(key)) continue;
      if (!shape.empty())
        src.fail(r.at(key), fmt::format("{}: '{}' and '{}' given; expected one shape: rectangle, sphere, cylinder or {}",
                                        item.path.empty() ? "body" : item.path, shape, key, surface_key));
      shape = key;
    }
    if (shape.empty() || shape == "rectangle") {
      b.rect = r.rect("rectangle", rect_form + " filled with particles (or a sphere, cylinder or " + surface_key + " instead)");
    } else if (shape == surface_key) {
      b.surface = read_surface(r, base_dir);
      b.rect = b.surface->bounds();
    } else {
      b.round = read_round(r, shape);
      b.rect = b.round->bounds();
    }
    for (const Field& name : r.list("subtract", "a list of names of walls (blocks, spheres, cylinders, or surfaces with "
                                                "the fluid outside) cut out of the body",
                                    false))
      b.subtract.push_back(to_name(src, name, "the name of a wall"));
    g.body_subtract.push_back(r.at("subtract"));
    b.clamp = r.optional_rect("clamp", rect_form + " (solid bodies: particles inside are clamped)");
    b.velocity = r.vec("velocity", Vec::Zero(), "an initial velocity " + components("v") + " in m/s");
    if (!(b.velocity.norm() <= max_speed))
      src.expected(r.at("velocity"), fmt::format("an initial velocity {} in m/s of magnitude at most {:g} m/s", components("v"), max_speed));
#if MPSFSI_DIM == 2
    b.angular_velocity = r.number("angular_velocity", 0, magnitude_at_most(max_angular_velocity),
                                  fmt::format("a number in [-{0:g}, {0:g}] (initial angular velocity) [rad/s]",
                                              max_angular_velocity));
#else
    b.angular_velocity = r.vec("angular_velocity", Vec::Zero(), "an initial angular velocity " + components("w") + " in rad/s");
    if (!(b.angular_velocity.norm() <= max_angular_velocity))
      src.expected(r.at("angular_velocity"), fmt::format("an initial angular velocity {} in rad/s of magnitude at most "
                                                         "{:g} rad/s", components("w"), max_angular_velocity));
#endif
    r.finish();
    g.body_rect.push_back(r.at(shape.empty() ? "rectangle" : shape));
    g.body_material.push_back(r.at("material"));
    g.body_clamp.push_back(r.at("clamp"));
    if (b.clamp && b.kind == BodyKind::fluid)
      src.fail(r.at("clamp"), fmt::format("{}: a fluid body cannot be clamped; expected clamp only on solid bodies",
                                          r.path_of("clamp")));
    spec.bodies.push_back(b);
  }
}

void read_walls(MapReader& top, CaseSpec& spec, std::map<std::string, std::string>& names, GeometryFields& g,
                const fs::path& base_dir) {
  const Source& src = top.source();
  const std::string types = "box | block | sphere | cylinder | " + surface_key;
  for (const Field& item : top.list("walls", "a list of walls, each {name, type: " + types + ", ...}", false)) {
    MapReader r(src, item, "a wall {name, type: " + types + ", rectangle | sphere | cylinder | " + surface_key +
                               ", fluid, open_top, motion}");
    WallSpec w;
    w.name = unique_name(r, names, "bodies and walls");
    const std::string type = r.choice("type", {"box", "block", "sphere", "cylinder", surface_key});
    w.type = type == "box" ? WallType::box : type == "block" ? WallType::block
           : type == "sphere" ? WallType::sphere : type == "cylinder" ? WallType::cylinder : WallType::surface;
    const bool round = w.type == WallType::sphere || w.type == WallType::cylinder;
    if (round) {
      w.round = read_round(r, type);
      w.rect = w.round->bounds();
    } else if (w.type == WallType::surface) {
      w.surface = read_surface(r, base_dir);
      w.rect = w.surface->bounds();
      w.fluid_inside = r.choice("fluid", "outside", {"outside", "inside"}) == "inside";
    } else {
      w.rect = r.rect("rectangle", rect_form + (w.type == WallType::box ? " (inner, wetted side of the box)" : " (the block)"));
    }
    if (r.has("motion")) w.motion = read_wall_motion(MapReader(src, r.at("motion"), wall_motion_form), base_dir);
    if (w.type == WallType::box) w.open_top = r.boolean("open_top", true, "true or false (box without a lid)");
    if (w.type == WallType::surface && w.fluid_inside)
      w.open_top = r.boolean("open_top", false, "true or false (no wall layers above the surface's top: a tank without a lid)");
    else if (w.type == WallType::surface)
      w.open_top = false;
    r.finish();
    g.wall_rect.push_back(r.at(round || w.type == WallType::surface ? type : "rectangle"));
    spec.walls.push_back(w);
  }
}

void assign_clamp_walls(const Source& src, CaseSpec& spec, const GeometryFields& g) {
  for (std::size_t i = 0; i < spec.bodies.size(); ++i) {
    BodySpec& b = spec.bodies[i];
    if (!b.clamp || b.kind != BodyKind::solid) continue;
    for (const WallSpec& w : spec.walls) {
      if (!w.motion.moving()) continue;
      const Vec layers = Vec::Constant(3 * spec.dp);
      if (!overlaps(*b.clamp, Rect{w.rect.lo - layers, w.rect.hi + layers})) continue;
      if (!b.clamp_wall.empty())
        src.fail(g.body_clamp[i], fmt::format("{} = {} reaches into two walls that move, '{}' and '{}'; expected a clamp "
                                              "in one moving wall at most",
                                              g.body_clamp[i].path, show_rect(*b.clamp), b.clamp_wall, w.name));
      b.clamp_wall = w.name;
    }
  }
}

void check_geometry(const Source& src, const CaseSpec& spec, const GeometryFields& g, const Field& dp_field) {
  const Real tolerance = 1e-9 * spec.dp;
  const auto check_size = [&](const Rect& r, const Field& f) {
    const Vec size = r.size();
    if (size.minCoeff() < 0.5 * spec.dp)
      src.fail(f, fmt::format("{} = {}: expected a rectangle at least dp/2 = {:g} m wide{} high (one particle)",
                              f.path, show_rect(r), 0.5 * spec.dp, dim == 2 ? " and" : ", deep and"));
    if (size.maxCoeff() > max_cells_per_side * spec.dp)
      src.fail(f, fmt::format("{} = {}: expected at most {:g} particles along a side (dp = {:g} m)", f.path, show_rect(r),
                              max_cells_per_side, spec.dp));
    if (!inside(r, spec.domain, tolerance))
      src.fail(f, fmt::format("{} = {} lies outside the domain {}: expected a rectangle inside the domain", f.path,
                              show_rect(r), show_rect(spec.domain)));
  };
  Real n_particles = 0;
  for (std::size_t i = 0; i < spec.bodies.size(); ++i) {
    check_size(spec.bodies[i].rect, g.body_rect[i]);
    n_particles += spec.bodies[i].rect.size().prod() / std::pow(spec.dp, dim);
  }
  for (std::size_t i = 0; i < spec.walls.size(); ++i) check_size(spec.walls[i].rect, g.wall_rect[i]);
  if (n_particles > max_particles)
    src.fail(dp_field, fmt::format("dp = {:g}: the bodies would have about {:.3g} particles; expected at most {:g} "
                                   "(dp is in metres)", spec.dp, n_particles, max_particles));

  for (std::size_t i = 0; i < spec.bodies.size(); ++i) {
    const BodySpec& b = spec.bodies[i];
    const Field& f = g.body_rect[i];
    for (std::size_t j = 0; j < i; ++j)
      if (overlap_beyond(b.rect, spec.bodies[j].rect, tolerance))
        src.fail(f, fmt::format("{} overlaps {} ('{}'): bodies must not overlap", f.path, g.body_rect[j].path,
                                spec.bodies[j].name));
    const WallSpec* first_box = nullptr;
    bool in_a_box = false;
    for (const std::string& name : b.subtract) {
      const auto it = std::find_if(spec.walls.begin(), spec.walls.end(), [&](const WallSpec& w) { return w.name == name; });
      const Field& sf = g.body_subtract[i];
      if (it == spec.walls.end())
        src.fail(sf, fmt::format("{}: '{}' is not a wall of the case; expected names of walls", sf.path, name));
      if (it->is_container())
        src.fail(sf, fmt::format("{}: '{}' is a tank (the fluid is inside it); expected obstacles: blocks, spheres, "
                                 "cylinders or {}s with the fluid outside",
                                 sf.path, name, surface_key));
    }
    for (std::size_t k = 0; k < spec.walls.size(); ++k) {
      const WallSpec& w = spec.walls[k];
      const bool cut_out = std::find(b.subtract.begin(), b.subtract.end(), w.name) != b.subtract.end();
      if (!w.is_container() && !cut_out && overlap_beyond(free_part(b), w.rect, tolerance))  // a sphere, cylinder or surface by its bounds
        src.fail(f, fmt::format("{} overlaps {} ('{}'): bodies must not overlap walls (or list the wall in the body's "
                                "subtract)",
                                f.path, g.wall_rect[k].path, w.name));
      if (w.is_container()) {
        if (!first_box) first_box = &w;
        in_a_box = in_a_box || inside_box(free_part(b), w, tolerance);
      }
    }
    if (first_box && !in_a_box) {
      const auto k = static_cast<std::size_t>(first_box - spec.walls.data());
      src.fail(f, fmt::format("{} = {} lies outside {} ('{}'), the inner rectangle of the tank{}: expected bodies inside "
                              "the tank",
                              f.path, show_rect(b.rect), g.wall_rect[k].path, first_box->name,
                              first_box->open_top ? " (open top)" : ""));
    }
    if (b.clamp && !overlaps(*b.clamp, b.rect))
      src.fail(g.body_clamp[i], fmt::format("{} = {} does not overlap {}: expected a clamp region that covers part of "
                                            "the body",
                                            g.body_clamp[i].path, show_rect(*b.clamp), f.path));
  }
}

void check_body_materials(const Source& src, const CaseSpec& spec, const GeometryFields& g) {
  const auto names = [](const auto& materials) {
    std::vector<std::string> out;
    for (const auto& m : materials) out.push_back(m.name);
    return out.empty() ? std::string("none defined") : join(out);
  };
  for (std::size_t i = 0; i < spec.bodies.size(); ++i) {
    const BodySpec& b = spec.bodies[i];
    const bool solid = b.kind == BodyKind::solid;
    const std::string kind = solid ? "solid" : "fluid";
    const std::string wanted = fmt::format("a {} material (one of: {})", kind,
                                           solid ? names(spec.solid_materials) : names(spec.fluid_materials));
    const bool is_fluid_material = spec.fluid_material_index(b.material) >= 0;
    const bool is_solid_material = spec.solid_material_index(b.material) >= 0;
    const Field& f = g.body_material[i];
    if (!is_fluid_material && !is_solid_material)
      src.fail(f, fmt::format("{} = {}: unknown material; expected {}", f.path, b.material, wanted));
    if (solid != is_solid_material)
      src.fail(f, fmt::format("{} = {}: '{}' is a {} material but the body is {}; expected {}", f.path, b.material,
                              b.material, solid ? "fluid" : "solid", kind, wanted));
  }
}

}  // namespace case_detail
}  // namespace mpsfsi
