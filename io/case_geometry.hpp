// The geometry of a case (io/case_geometry.cpp; io-internal): bodies and walls with their shapes and motions,
// and the cross-checks that need the whole geometry.
#pragma once

#include "io/case_reader.hpp"

namespace mpsfsi::case_detail {

/// Fields of the bodies and walls kept for the cross-checks.
struct GeometryFields {
  std::vector<Field> body_rect, body_material, body_clamp, body_subtract, wall_rect;
};

/// The `bodies` list of the case: each body's name (unique among `names`), kind, material, shape, velocity, clamp.
void read_bodies(MapReader& top, CaseSpec& spec, std::map<std::string, std::string>& names, GeometryFields& g,
                 const fs::path& base_dir);
/// The `walls` list: boxes, blocks, spheres, cylinders and closed surfaces, each with its own motion if any.
void read_walls(MapReader& top, CaseSpec& spec, std::map<std::string, std::string>& names, GeometryFields& g,
                const fs::path& base_dir);
/// A solid body's clamp that reaches into a wall with a motion of its own (the wall's bounds and its 3 layers)
/// moves with that wall (BodySpec::clamp_wall): a plate clamped into a paddle. A clamp in two such walls is refused.
void assign_clamp_walls(const Source& src, CaseSpec& spec, const GeometryFields& g);
/// Every rectangle is inside the domain and at least one particle (dp/2) thick; bodies do not overlap
/// each other or a block and lie in a box when there is one (a clamped end may reach into a wall);
/// clamps touch their body.
void check_geometry(const Source& src, const CaseSpec& spec, const GeometryFields& g, const Field& dp_field);
/// Every body names a material of its kind.
void check_body_materials(const Source& src, const CaseSpec& spec, const GeometryFields& g);

}  // namespace mpsfsi::case_detail
