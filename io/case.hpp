// The in-memory form of a case file (cases/*.yaml), checked and in SI units. The parser
// (io/case_file.cpp) fills it; scene building and the coupling read it, the fluid and the solid get
// their part through io/setup.hpp. The schema is documented in docs/case-format.md. The parameters live
// with their physics: fluid/fluid_parameters.hpp, solid/solid_parameters.hpp, coupling/coupling_parameters.hpp,
// and the shared Rect, TimeSpec and TankMotionSpec in core/ (geometry.hpp, time_spec.hpp, tank_motion.hpp).
#pragma once

#include "core/geometry.hpp"
#include "core/tank_motion.hpp"
#include "core/time_spec.hpp"
#include "core/wall_motion.hpp"
#include "core/types.hpp"
#include "core/distribution.hpp"
#include "coupling/coupling_parameters.hpp"
#include "fluid/fluid_parameters.hpp"
#include "solid/solid_parameters.hpp"

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpsfsi {

/// An error in user input (case file or command line). Exit code 2.
class CaseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class BodyKind { fluid, solid };

class ClosedSurface;  // io/surface.hpp

/// A body or wall that is not a rectangle: a ball (`sphere`: centre and radius; a disc in 2D) or a cylinder
/// (`cylinder`: the centre of its base, the axis from there to the other end, and the radius; in 2D its section
/// through the axis, a strip), filled on the lattice (core/geometry.hpp fill_sphere, fill_cylinder).
struct RoundShape {
  enum class Kind { sphere, cylinder };
  Kind kind = Kind::sphere;
  Vec centre = Vec::Zero();  ///< sphere: its centre; cylinder: the centre of its base
  Vec axis = Vec::Zero();    ///< cylinder: from the base's centre to the other end's
  Real radius = 0;
  /// The smallest rectangle (box) that holds the shape.
  Rect bounds() const;
};

struct BodySpec {
  std::string name;
  BodyKind kind = BodyKind::fluid;
  std::string material;             ///< name of a fluid material (fluid) or solid material (solid)
  Rect rect;                        ///< region filled with particles; with `round` the shape's bounds
  std::optional<RoundShape> round;  ///< a sphere or cylinder filled with particles instead of the rectangle
  /// A closed surface (an STL or OBJ file in 3D, a polygon in 2D) filled instead of the rectangle; rect: its bounds.
  std::shared_ptr<const ClosedSurface> surface;
  /// Walls whose shapes are cut out of the body (`subtract`): its lattice points inside them or closer than dp/2 to
  /// their surface are left out, so that water can surround an obstacle.
  std::vector<std::string> subtract;
  std::optional<Rect> clamp;        ///< solid only: particles inside are clamped
  std::string clamp_wall;           ///< solid only: the wall with a motion of its own the clamp reaches into (it moves with it)
  Vec velocity = Vec::Zero();       ///< initial velocity [m/s]
  Angular angular_velocity = angular_zero();       ///< initial angular velocity about the body's centroid [rad/s] (a vector in 3D)
};

/// The part of a body that is not clamped: a clamp that spans the body's whole width (height) cuts its
/// height (width); otherwise the whole body counts. Only this part must stay clear of the walls, so a
/// clamped end may be embedded in a wall (the wall particles there give way, see io/scene.cpp).
Rect free_part(const BodySpec& b);

/// A box (a tank: the wall outside its inner rectangle) or a solid obstacle of wall particles: a block, a
/// sphere or a cylinder (the wall layer and the dummy layers inside its surface); or a closed surface (`surface`
/// in 3D, `polygon` in 2D) with the fluid outside it (an obstacle) or inside it (a container).
enum class WallType { box, block, sphere, cylinder, surface };

struct WallSpec {
  std::string name;
  WallType type = WallType::box;
  Rect rect;              ///< box: the inner (wetted) rectangle; block: the solid block itself; sphere, cylinder: the bounds
  bool open_top = true;   ///< box (default true), surface with the fluid inside (default false): no lid
  std::optional<RoundShape> round;  ///< sphere, cylinder: the shape
  std::shared_ptr<const ClosedSurface> surface;  ///< surface: the shape
  bool fluid_inside = false;  ///< surface: a container (the layers outside the surface) instead of an obstacle
  WallMotionSpec motion;      ///< a motion of its own (`motion`: a gate, a wave maker), relative to the domain
  /// A tank: the fluid is inside it (a box, or a surface with the fluid inside).
  bool is_container() const { return type == WallType::box || (type == WallType::surface && fluid_inside); }
  /// Given by its surface (a polygon, STL or OBJ surface, sphere or cylinder) rather than by a rectangle.
  bool is_shaped() const { return surface != nullptr || round.has_value(); }
};

enum class ProbeType { pressure, surge_front, column_height, wave_gauge, displacement };

/// Frame of a displacement probe: global, or the tank's rotating frame (R(-theta)(x - pivot) - (x0 - pivot)).
enum class ProbeFrame { global, tank };

struct ProbeSpec {
  std::string name;
  ProbeType type = ProbeType::pressure;
  Vec position = Vec::Zero();   ///< pressure: probe point; displacement: initial point on the body
  std::string body;             ///< displacement: which body (optional for others)
  ProbeFrame frame = ProbeFrame::global;  ///< displacement only
};

/// A receiver: the displacement of the material point of a solid body that starts at `position`,
/// interpolated from the body's particles within ReceiversSpec::radius (interpolation_stencil).
struct ReceiverSpec {
  std::string name;
  std::string body;
  Vec position = Vec::Zero();
};

/// How a run spreads its particles over the MPI ranks (core/distribution.hpp): the geometric partitioner,
/// the imbalance of owned particles that triggers a new partition, and the skin of the halo [in dp].
struct ParallelSpec {
  PartitionMethod partition = PartitionMethod::rcb;
  Real imbalance = 0.1;
  Real skin = 2.0;
};

struct ReceiversSpec {
  std::optional<Real> interval;   ///< simulated time between rows of receivers.csv [s]; none: every step
  Real radius = 0;                ///< stencil radius [m]; the parser's default is 2 dp
  std::vector<ReceiverSpec> points;
};

struct OutputSpec {
  Real interval = 0.01;         ///< simulated time between frames [s]
  std::optional<Real> probe_interval;  ///< simulated time between rows of probes.csv [s]; none: with each frame
  std::vector<std::string> fields;  ///< empty: every field
};

struct CaseSpec {
  std::string file;             ///< path of the case file as given
  std::string name;
  std::string description;
  std::string source;           ///< where the geometry and data come from
  Rect domain;                  ///< particles leaving it are removed and counted
  Real dp = 0;                  ///< particle spacing l0 [m]
  TimeSpec time;
  Vec gravity = Vec::Zero();
  Real gravity_ramp = 0;  ///< [s]; gravity rises from 0 over this time (core/ramp.hpp); 0: at once
  std::vector<FluidMaterial> fluid_materials;
  std::vector<SolidMaterial> solid_materials;
  std::vector<BodySpec> bodies;
  std::vector<WallSpec> walls;
  TankMotionSpec tank_motion;
  CouplingParameters coupling;
  ParallelSpec parallel;
  FluidParameters fluid;
  SolidParameters solid;
  std::vector<SolidLoadSpec> solid_loads;
  std::vector<SourceSpec> sources;
  std::vector<ProbeSpec> probes;
  ReceiversSpec receivers;
  OutputSpec output;
  std::string resolved_yaml;    ///< the case after every override, as YAML (saved with the results)

  /// Index of a fluid/solid material by name, or -1.
  int fluid_material_index(const std::string& name) const;
  int solid_material_index(const std::string& name) const;
};

/// What the fluid solver is set up from (fluid/fluid_parameters.hpp): the case's dp, gravity, domain, time,
/// fluid materials, fluid parameters and tank motion.
FluidSetup fluid_setup(const CaseSpec& spec);
/// What the solid solver is set up from (solid/solid_parameters.hpp): the case's dp, gravity, solid
/// materials, solid parameters, tank motion, bodies' angular velocities, solid loads and sources.
SolidSetup solid_setup(const CaseSpec& spec);

/// The spatial dimension a case asks for, from its `dimension:` key alone (YAML text, or a regular file with
/// `from_file`): 2 when it has none, 0 when the text cannot be read, the file is not a regular file or the value
/// is not 2 or 3 (load_case then says what is wrong).
int peek_case_dimension(const std::string& text_or_path, bool from_file);

/// Parse and check a case file; `overrides` are "dotted.key=value" strings (--set), applied before
/// checking. Throws CaseError with file, line, key and the expected form on any bad input.
CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides = {});
/// Same, from YAML text (`name` stands for the file in messages; relative paths in the case, e.g. a
/// tank-motion table, are relative to base_dir).
CaseSpec parse_case(const std::string& yaml_text, const std::string& name,
                    const std::vector<std::string>& overrides = {}, const std::string& base_dir = ".");

/// Keys of a case that a restart may change freely (with --set or --end-time): time.end, output (interval,
/// fields), description and source.
const std::vector<std::string>& restart_free_keys();
/// Numerical controls a restart may change, e.g. to continue with a smaller time step after a run went
/// unstable: time.cfl, time.dt, time.dt_max, coupling.subcycles, fluid.solver, fluid.preconditioner,
/// fluid.tolerance, fluid.max_iterations, fluid.preconditioner_rebuild_every, fluid.max_loss, solid.dt,
/// solid.dt_factor. The continuation then is not the original run's. Every other key must equal the
/// checkpoint's case.
const std::vector<std::string>& restart_tunable_keys();
/// True when `key` (dotted, e.g. "time.cfl" or "bodies[0].name") is one of `roots` or lies below one.
bool key_under(const std::string& key, const std::vector<std::string>& roots);

/// One leaf of a case whose value differs between two cases.
struct CaseDifference {
  std::string key;  ///< dotted path, e.g. "bodies[1].rectangle.max[0]"
  std::string a, b; ///< the values as written; "(absent)" for a missing key
  std::string text() const { return key + ": " + a + " vs " + b; }
};
/// The differences between two resolved cases (CaseSpec::resolved_yaml) outside restart_free_keys(), by
/// key (numbers compare by value). Empty: the same case for a restart.
std::vector<CaseDifference> case_differences(const std::string& yaml_a, const std::string& yaml_b);

}  // namespace mpsfsi
