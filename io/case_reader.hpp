// The case file's reading machinery, shared by the readers of its sections (io/case_file.cpp,
// io/case_geometry.cpp) and not part of io's interface: where a value came from (Source, Field) and the message
// that names file, line, key and expected form; the conversions of one value; MapReader over one YAML map; the
// keys that several sections share; the case as a YAML tree (io/case_tree.cpp: loading, --set overrides).
#pragma once

#include "io/case.hpp"

#include "core/tank_motion.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mpsfsi::case_detail {

namespace fs = std::filesystem;

/// Largest number of lattice cells along one side of a rectangle, and of particles in all bodies.
inline constexpr Real max_cells_per_side = 1e6;
inline constexpr Real max_particles = 1e9;
/// Largest case file read (the shipped ones have a few KiB).
inline constexpr std::uintmax_t max_case_bytes = 16u << 20;

// Bounds that keep a case's work and numbers finite. Each is far beyond any case the method can run, so
// a value outside is a typo or a unit mistake, not a choice (docs/case-format.md lists them).
/// Effective radii in units of dp: 10 dp is about pi 10^2 = 314 neighbours per particle (2.1 dp: 13).
inline constexpr Real max_radius_dp = 10;
/// Stencil radii of sources and receivers [dp].
inline constexpr Real max_stencil_dp = 10;
/// Smallest time step [s], and most steps up to time.end with a fixed one.
inline constexpr Real min_time_step = 1e-12;
inline constexpr Real max_steps = 1e9;
/// Smallest output / receiver interval [s], and most frames / rows up to time.end.
inline constexpr Real min_interval = 1e-9;
inline constexpr Real max_frames = 1e6;
/// Most solid sub-steps per fluid step.
inline constexpr long long max_subcycles = 100000;
/// Largest gravity [m/s2] (1000 g), initial speed of a body [m/s] and initial angular velocity [rad/s].
inline constexpr Real max_gravity = 1e4;
inline constexpr Real max_speed = 1e4;
inline constexpr Real max_angular_velocity = 1e4;
/// Shortest sine-roll period [s] (with the largest amplitude, the tank turns at up to 2 pi^2 / period rad/s).
inline constexpr Real min_period = 1e-3;
/// Narrowest lateral-wall gap [m] (the friction rate grows as 1 / gap^2).
inline constexpr Real min_gap = 1e-6;
/// Largest solid-load peak pressure [Pa] and source amplitude [N m/m or N/m].
inline constexpr Real max_load = 1e13;
/// Material ranges: densities [kg/m3], sound and wave speeds [m/s], kinematic viscosity [m2/s], Young's
/// modulus [Pa].
inline constexpr Real min_density = 1e-3, max_density = 1e5;
inline constexpr Real min_speed = 1e-3, max_wave_speed = 1e5;
inline constexpr Real max_viscosity = 1e4;
inline constexpr Real min_modulus = 1e-3, max_modulus = 1e13;
/// Longest name (file-name safe: case names name the output folder).
inline constexpr std::size_t max_name_length = 64;

// ---------------------------------------------------------------------------------------------
// Text, paths and locations (io/case_reader.cpp).

std::string join(const std::vector<std::string>& items, const std::string& separator = ", ");
std::string trim(const std::string& s);
std::vector<std::string> split(const std::string& s, char separator);
bool is_digits(const std::string& s);
/// Names of cases, materials, bodies, walls, probes and output fields: at most max_name_length letters,
/// digits, '_' and '-', starting with a letter or '_' (so that they are file-name safe and never look like
/// a list index or contain the '.' of a --set path).
bool is_name(const std::string& s);
/// What is_name accepts, for the messages.
extern const std::string name_form;
/// `typo` is close enough to `key` for a "did you mean" hint.
bool looks_like(const std::string& typo, const std::string& key);

/// Dotted path for messages: "" is the top level.
std::string show_path(const std::string& path);
std::string child_path(const std::string& parent, const std::string& key);
std::string item_path(const std::string& parent, std::size_t index);
/// True when `path` is `root` or lies below it ("bodies[0].velocity" lies below "bodies[0]").
bool lies_within(const std::string& path, const std::string& root);
/// A value as it appears in messages: scalars as written (quoted ones in quotes), lists and maps
/// in flow style, long values shortened.
std::string show(const YAML::Node& node);

/// A --set override after it was applied: its text and the path of the subtree it wrote (the
/// topmost node it created, or the node it replaced).
struct AppliedOverride {
  std::string text;
  std::string root;
};

/// One value of the case tree: the node, its dotted path and, for map values, the key node (whose
/// line is the one reported: the value of `rectangle:` may start on the next line).
struct Field {
  YAML::Node node;
  std::string path;
  YAML::Node key = YAML::Node();
};

/// Where the case text came from; turns a field into "file:line" (or "file (--set ...)") and throws.
class Source {
 public:
  explicit Source(std::string file) : file_(std::move(file)) {}

  const std::string& file() const { return file_; }

  std::string location(const Field& f) const {
    for (auto it = overrides_.rbegin(); it != overrides_.rend(); ++it)
      if (!f.path.empty() && lies_within(f.path, it->root)) return fmt::format("{} (--set {})", file_, it->text);
    const YAML::Mark key_mark = f.key.IsDefined() ? f.key.Mark() : YAML::Mark::null_mark();
    const YAML::Mark mark = key_mark.is_null() && f.node.IsDefined() ? f.node.Mark() : key_mark;
    std::string where = mark.is_null() ? file_ : fmt::format("{}:{}", file_, mark.line + 1);
    for (auto it = overrides_.rbegin(); it != overrides_.rend(); ++it) {
      if (!f.path.empty() && lies_within(it->root, f.path)) {
        where += fmt::format(" (after --set {})", it->text);
        break;
      }
    }
    return where;
  }

  /// Throws "location: message".
  [[noreturn]] void fail(const Field& f, const std::string& message) const {
    throw CaseError(fmt::format("{}: {}", location(f), message));
  }

  /// Throws "location: path = value: expected <form>".
  [[noreturn]] void expected(const Field& f, const std::string& form) const {
    fail(f, fmt::format("{} = {}: expected {}", show_path(f.path), show(f.node), form));
  }

  void add_override(AppliedOverride o) {
    // A later override of the same subtree replaces what the earlier one wrote.
    overrides_.erase(std::remove_if(overrides_.begin(), overrides_.end(),
                                    [&](const AppliedOverride& old) { return lies_within(old.root, o.root); }),
                     overrides_.end());
    overrides_.push_back(std::move(o));
  }

 private:
  std::string file_;
  std::vector<AppliedOverride> overrides_;
};

// ---------------------------------------------------------------------------------------------
// Conversions of one field. `form` is the expected form, used in the message.

using Check = std::function<bool(Real)>;

extern const Check any_number, positive, non_negative;
/// lo < x <= hi
Check in_half_open(Real lo, Real hi);
/// lo < x < hi
Check in_open(Real lo, Real hi);
/// lo <= x <= hi
Check in_closed(Real lo, Real hi);
/// |x| <= bound
Check magnitude_at_most(Real bound);

/// A scalar written without quotes or tag (a quoted "1" is text, not a number).
bool is_plain_scalar(const YAML::Node& node);
Real to_real(const Source& src, const Field& f, const Check& check, const std::string& form);
int to_int(const Source& src, const Field& f, const std::function<bool(long long)>& check, const std::string& form);
bool to_bool(const Source& src, const Field& f, const std::string& form);
std::string to_text(const Source& src, const Field& f, const std::string& form);
std::string to_name(const Source& src, const Field& f, const std::string& form);
std::string to_choice(const Source& src, const Field& f, const std::vector<std::string>& options);
Vec to_vec(const Source& src, const Field& f, const std::string& form);

/// The components of a vector of the build's dimension for expected forms, each the axis name after
/// `prefix`: "[x, y]" in 2D and "[x, y, z]" in 3D; with prefix "g": "[gx, gy]" and "[gx, gy, gz]".
std::string components(const std::string& prefix = "");
/// A vector as "[1, 2]" (2D) or "[1, 2, 3]" (3D).
std::string show_vec(const Vec& v);
std::string show_rect(const Rect& r);

// ---------------------------------------------------------------------------------------------
// MapReader: one YAML map and its dotted path.

class MapReader {
 public:
  /// `form` describes the map, for the message when the node is not a map. A null node (a key
  /// with nothing after the colon) reads as an empty map.
  MapReader(const Source& src, Field field, const std::string& form) : src_(src), field_(std::move(field)) {
    if (field_.node.IsNull() || !field_.node.IsDefined()) return;
    if (!field_.node.IsMap()) src_.expected(field_, form);
    for (const auto& kv : field_.node) {
      const Field key_field{kv.first, field_.path, kv.first};
      if (!kv.first.IsScalar() || kv.first.Scalar().empty())
        src_.fail(key_field, fmt::format("key {} in {}: expected a plain name as key", show(kv.first), show_path(field_.path)));
      const std::string key = kv.first.Scalar();
      for (const auto& e : entries_) {
        if (e.key == key) {
          const auto first_line = e.key_node.Mark().line + 1;
          src_.fail(Field{kv.first, child_path(field_.path, key), kv.first},
                    fmt::format("duplicate key '{}' in {} (first given at line {}): expected each key once", key,
                                show_path(field_.path), first_line));
        }
      }
      entries_.push_back({key, kv.first, kv.second});
    }
  }

  const Field& field() const { return field_; }
  const Source& source() const { return src_; }
  std::string path_of(const std::string& key) const { return child_path(field_.path, key); }

  /// The key's value, or nothing when the key is absent or null (`key: ~` is the same as leaving it out).
  std::optional<Field> optional(const std::string& key) {
    known(key);
    const Entry* e = find(key);
    if (e == nullptr || e->value.IsNull()) return std::nullopt;
    return Field{e->value, path_of(key), e->key_node};
  }

  /// The key's value; throws "missing key" when absent and "expected <form>" when null.
  Field required(const std::string& key, const std::string& form) {
    known(key);
    if (const Entry* e = find(key)) {
      const Field f{e->value, path_of(key), e->key_node};
      if (e->value.IsNull()) src_.expected(f, form);
      return f;
    }
    // A key that was not asked for and looks like the missing one is most likely a typo of it.
    for (const auto& e : entries_) {
      if (std::find(known_.begin(), known_.end(), e.key) == known_.end() && looks_like(e.key, key))
        src_.fail(Field{e.value, path_of(e.key), e.key_node},
                  fmt::format("unknown key '{}' in {}; did you mean '{}'? expected: {}, {}", e.key, show_path(field_.path),
                              key, path_of(key), form));
    }
    src_.fail(field_, fmt::format("missing key '{}' in {}; expected: {}, {}", key, show_path(field_.path), path_of(key), form));
  }

  /// The key's value like optional(), without marking the key as known: a key read ahead of the others
  /// (`dimension`) and asked for again later keeps its place in the list of an unknown key's message.
  std::optional<Field> peek(const std::string& key) const {
    const Entry* e = find(key);
    if (e == nullptr || e->value.IsNull()) return std::nullopt;
    return Field{e->value, path_of(key), e->key_node};
  }

  /// The field of a key read before (for messages of cross-checks).
  Field at(const std::string& key) const {
    const Entry* e = find(key);
    return e ? Field{e->value, path_of(key), e->key_node} : field_;
  }

  bool has(const std::string& key) {
    known(key);
    const Entry* e = find(key);
    return e != nullptr && !e->value.IsNull();
  }

  Real number(const std::string& key, const Check& check, const std::string& form) {
    return to_real(src_, required(key, form), check, form);
  }
  Real number(const std::string& key, const Real fallback, const Check& check, const std::string& form) {
    const auto f = optional(key);
    return f ? to_real(src_, *f, check, form) : fallback;
  }
  std::optional<Real> optional_number(const std::string& key, const Check& check, const std::string& form) {
    const auto f = optional(key);
    return f ? std::optional<Real>(to_real(src_, *f, check, form)) : std::nullopt;
  }
  int integer(const std::string& key, const int fallback, const std::function<bool(long long)>& check,
              const std::string& form) {
    const auto f = optional(key);
    return f ? to_int(src_, *f, check, form) : fallback;
  }
  bool boolean(const std::string& key, const bool fallback, const std::string& form) {
    const auto f = optional(key);
    return f ? to_bool(src_, *f, form) : fallback;
  }
  std::string text(const std::string& key, const std::string& form) { return to_text(src_, required(key, form), form); }
  std::string text(const std::string& key, const std::string& fallback, const std::string& form) {
    const auto f = optional(key);
    return f ? to_text(src_, *f, form) : fallback;
  }
  std::string name(const std::string& key, const std::string& form) { return to_name(src_, required(key, form), form); }
  std::string choice(const std::string& key, const std::vector<std::string>& options) {
    return to_choice(src_, required(key, "one of: " + join(options)), options);
  }
  std::string choice(const std::string& key, const std::string& fallback, const std::vector<std::string>& options) {
    const auto f = optional(key);
    return f ? to_choice(src_, *f, options) : fallback;
  }
  /// An option enum read by the names of its table (e.g. fluid/fluid_parameters.hpp preconditioner_names()).
  template <class E>
  E option(const std::string& key, const E fallback, const NameTable<E>& table) {
    return *value_of(table, choice(key, std::string(name_of(table, fallback)), names_of(table)));
  }
  Vec vec(const std::string& key, const std::string& form) { return to_vec(src_, required(key, form), form); }
  Vec vec(const std::string& key, const Vec& fallback, const std::string& form) {
    const auto f = optional(key);
    return f ? to_vec(src_, *f, form) : fallback;
  }
  Rect rect(const std::string& key, const std::string& form) { return to_rect(required(key, form), form); }
  std::optional<Rect> optional_rect(const std::string& key, const std::string& form) {
    const auto f = optional(key);
    return f ? std::optional<Rect>(to_rect(*f, form)) : std::nullopt;
  }

  /// A nested map (required, or empty when absent).
  MapReader map(const std::string& key, const std::string& form) { return MapReader(src_, required(key, form), form); }
  MapReader optional_map(const std::string& key, const std::string& form) {
    const auto f = optional(key);
    return MapReader(src_, f ? *f : Field{YAML::Node(), path_of(key)}, form);
  }

  /// The items of a list, with paths key[i]; an absent optional list is empty.
  std::vector<Field> list(const std::string& key, const std::string& form, const bool is_required) {
    const auto f = is_required ? std::optional<Field>(required(key, form)) : optional(key);
    std::vector<Field> items;
    if (!f) return items;
    if (!f->node.IsSequence() || (is_required && f->node.size() == 0)) src_.expected(*f, form);
    for (std::size_t i = 0; i < f->node.size(); ++i) items.push_back({f->node[i], item_path(f->path, i)});
    return items;
  }

  /// Every key of a map whose keys are names chosen by the user (materials).
  std::vector<std::pair<std::string, Field>> items() {
    std::vector<std::pair<std::string, Field>> out;
    for (const auto& e : entries_) {
      known(e.key);
      out.emplace_back(e.key, Field{e.value, path_of(e.key), e.key_node});
    }
    return out;
  }
  bool empty() const { return entries_.empty(); }

  /// Reports the first key that was never asked for.
  void finish() const {
    for (const auto& e : entries_) {
      if (std::find(known_.begin(), known_.end(), e.key) != known_.end()) continue;
      std::string hint;
      for (const auto& k : known_)
        if (looks_like(e.key, k)) hint = fmt::format(" (did you mean '{}'?)", k);
      src_.fail(Field{e.value, path_of(e.key), e.key_node},
                fmt::format("unknown key '{}' in {}; expected one of: {}{}", e.key, show_path(field_.path), join(known_), hint));
    }
  }

 private:
  struct Entry {
    std::string key;
    YAML::Node key_node;
    YAML::Node value;
  };

  const Entry* find(const std::string& key) const {
    for (const auto& e : entries_)
      if (e.key == key) return &e;
    return nullptr;
  }

  void known(const std::string& key) {
    if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.push_back(key);
  }

  Rect to_rect(const Field& f, const std::string& form) const {
    MapReader r(src_, f, form);
    Rect rect;
    rect.lo = r.vec("min", std::string(dim == 2 ? "the lower-left corner " : "the lowest corner ") + components() + " in metres");
    rect.hi = r.vec("max", std::string(dim == 2 ? "the upper-right corner " : "the highest corner ") + components() + " in metres");
    r.finish();
    if (!(rect.hi.array() > rect.lo.array()).all())
      src_.fail(r.at("max"), fmt::format("{} = {}: expected max > min in {} components", show_path(f.path), show_rect(rect),
                                                 dim == 2 ? "both" : "all three"));
    return rect;
  }

  const Source& src_;
  Field field_;
  std::vector<Entry> entries_;
  std::vector<std::string> known_;
};

// ---------------------------------------------------------------------------------------------
// Keys that several sections share (io/case_reader.cpp).

extern const std::string rect_form, point_form, direction_form;

/// A time step of key `key` (already read, `dt`) at least min_time_step and at most max_steps up to `end`.
void check_time_step(MapReader& r, const std::string& key, Real dt, Real end);
/// An interval between outputs of key `key` (already read, `interval`; `what` are the outputs, e.g.
/// "frames"): at least min_interval and at most max_frames up to time.end. The default (`given` false) is
/// checked too: a long time.end may need a longer interval than the default.
void check_interval(MapReader& r, const std::string& key, Real interval, bool given, Real end, const std::string& what);
/// A name that must be unique within `names` (name -> path of its first use).
std::string unique_name(MapReader& r, std::map<std::string, std::string>& names, const std::string& among);

/// A file named in the case: its path as given (absolute, or relative to the case file's directory: what the
/// messages show) and where the key is.
struct FileKey {
  fs::path path;
  Field field;
  /// Once the file has been read: the case's node names it by its absolute path, so that case.resolved.yaml names
  /// the same file wherever it is read from.
  void name_absolute() const {
    std::error_code ec;
    const fs::path absolute = fs::absolute(path, ec).lexically_normal();
    if (ec) return;
    YAML::Node node = field.node;
    node = absolute.string();
  }
};

FileKey file_key(MapReader& r, const std::string& key, const fs::path& base_dir, const std::string& form);
/// A table file named by `f` (the path as resolved), read by read_time_table (core/tank_motion.hpp), the one
/// reader of the case's tables; its problems become "location: key = value: <file:line: problem>".
TimeTable read_table(const Source& src, const Field& f, const fs::path& path, const TimeTableColumn& column);

// ---------------------------------------------------------------------------------------------
// The case as a YAML tree (io/case_tree.cpp).

/// The one YAML document of a case text (an empty text is an empty map); syntax errors name the line.
YAML::Node load_yaml(const std::string& text, const std::string& file);
/// Applies one "dotted.key=value" override to the tree (see docs/case-format.md) and tells `src` which subtree
/// it wrote, so that messages about it name the override.
void apply_override(YAML::Node& root, const std::string& text, Source& src);
/// The tree as YAML text (case.resolved.yaml).
std::string emit(const YAML::Node& root);

}  // namespace mpsfsi::case_detail
