// The case-file parser: reads a case (cases/*.yaml; schema in docs/case-format.md) with yaml-cpp,
// applies the command-line overrides (--set dotted.key=value) to the YAML tree, checks every value
// and fills a CaseSpec in SI units. Every problem is a CaseError whose message names the file, the
// line (or the --set override that caused it), the dotted key and the expected form, e.g.
//   cases/dam_break.yaml:7: dp = -0.004: expected a positive number (particle spacing in metres)
//
// The reading is built on MapReader, which wraps one YAML map with its dotted path: each schema key
// is one call (required/optional number, vector, rectangle, name, choice, ...), and finish()
// reports every key that was not asked for as unknown. Cross-checks (materials, names, overlaps)
// follow the reading.
#include "io/case.hpp"
#include "io/surface.hpp"

#include "core/tank_motion.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <utility>

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

namespace {

namespace fs = std::filesystem;

/// Largest number of lattice cells along one side of a rectangle, and of particles in all bodies.
constexpr Real max_cells_per_side = 1e6;
constexpr Real max_particles = 1e9;
/// Largest case file read (the shipped ones have a few KiB).
constexpr std::uintmax_t max_case_bytes = 16u << 20;

// Bounds that keep a case's work and numbers finite. Each is far beyond any case the method can run, so
// a value outside is a typo or a unit mistake, not a choice (docs/case-format.md lists them).
/// Effective radii in units of dp: 10 dp is about pi 10^2 = 314 neighbours per particle (2.1 dp: 13).
constexpr Real max_radius_dp = 10;
/// Stencil radii of sources and receivers [dp].
constexpr Real max_stencil_dp = 10;
/// Smallest time step [s], and most steps up to time.end with a fixed one.
constexpr Real min_time_step = 1e-12;
constexpr Real max_steps = 1e9;
/// Smallest output / receiver interval [s], and most frames / rows up to time.end.
constexpr Real min_interval = 1e-9;
constexpr Real max_frames = 1e6;
/// Most solid sub-steps per fluid step.
constexpr long long max_subcycles = 100000;
/// Largest gravity [m/s2] (1000 g), initial speed of a body [m/s] and initial angular velocity [rad/s].
constexpr Real max_gravity = 1e4;
constexpr Real max_speed = 1e4;
constexpr Real max_angular_velocity = 1e4;
/// Shortest sine-roll period [s] (with the largest amplitude, the tank turns at up to 2 pi^2 / period rad/s).
constexpr Real min_period = 1e-3;
/// Narrowest lateral-wall gap [m] (the friction rate grows as 1 / gap^2).
constexpr Real min_gap = 1e-6;
/// Largest solid-load peak pressure [Pa] and source amplitude [N m/m or N/m].
constexpr Real max_load = 1e13;
/// Material ranges: densities [kg/m3], sound and wave speeds [m/s], kinematic viscosity [m2/s], Young's
/// modulus [Pa].
constexpr Real min_density = 1e-3, max_density = 1e5;
constexpr Real min_speed = 1e-3, max_wave_speed = 1e5;
constexpr Real max_viscosity = 1e4;
constexpr Real min_modulus = 1e-3, max_modulus = 1e13;
/// Longest name (file-name safe: case names name the output folder).
constexpr std::size_t max_name_length = 64;

// ---------------------------------------------------------------------------------------------
// Small string helpers.

std::string join(const std::vector<std::string>& items, const std::string& separator = ", ") {
  std::string out;
  for (const auto& s : items) {
    if (!out.empty()) out += separator;
    out += s;
  }
  return out;
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

std::vector<std::string> split(const std::string& s, const char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const auto end = s.find(separator, start);
    parts.push_back(s.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) return parts;
    start = end + 1;
  }
}

bool is_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](const unsigned char c) { return std::isdigit(c); });
}

/// Names of cases, materials, bodies, walls, probes and output fields: at most max_name_length letters,
/// digits, '_' and '-', starting with a letter or '_' (so that they are file-name safe and never look like
/// a list index or contain the '.' of a --set path).
bool is_name(const std::string& s) {
  if (s.empty() || s.size() > max_name_length || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_'))
    return false;
  return std::all_of(s.begin(), s.end(), [](const unsigned char c) { return std::isalnum(c) || c == '_' || c == '-'; });
}

/// The position of the first byte of `s` that is not valid UTF-8 (a stray continuation byte, an overlong
/// form, a surrogate or a code point above U+10FFFF, a truncated sequence), or npos: text that goes into
/// case.resolved.yaml must stay readable by YAML readers.
std::size_t utf8_error(const std::string& s) {
  std::size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t n = 0;
    std::uint32_t cp = 0;
    if (c < 0x80) {
      ++i;
      continue;
    } else if (c >= 0xc2 && c <= 0xdf) {
      n = 1, cp = c & 0x1fu;
    } else if (c >= 0xe0 && c <= 0xef) {
      n = 2, cp = c & 0x0fu;
    } else if (c >= 0xf0 && c <= 0xf4) {
      n = 3, cp = c & 0x07u;
    } else {
      return i;
    }
    for (std::size_t k = 1; k <= n; ++k) {
      if (i + k >= s.size()) return i;
      const auto d = static_cast<unsigned char>(s[i + k]);
      if ((d & 0xc0u) != 0x80u) return i;
      cp = (cp << 6) | (d & 0x3fu);
    }
    if ((n == 2 && cp < 0x800) || (n == 3 && (cp < 0x10000 || cp > 0x10ffff)) || (cp >= 0xd800 && cp <= 0xdfff))
      return i;
    i += n + 1;
  }
  return std::string::npos;
}

const std::string name_form = "a name of at most 64 letters, digits, '_' and '-' that starts with a letter or '_'";

/// A decimal number: [+-]digits[.digits][e[+-]digits]. No hex, inf or nan; finite after conversion.
std::optional<Real> parse_real(const std::string& s) {
  std::size_t i = 0;
  const std::size_t n = s.size();
  const auto digits = [&] {
    std::size_t count = 0;
    while (i < n && std::isdigit(static_cast<unsigned char>(s[i]))) ++i, ++count;
    return count;
  };
  if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
  std::size_t mantissa = digits();
  if (i < n && s[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return std::nullopt;
  if (i < n && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
    if (digits() == 0) return std::nullopt;
  }
  if (i != n) return std::nullopt;
  const Real value = std::strtod(s.c_str(), nullptr);
  if (!std::isfinite(value)) return std::nullopt;
  return value;
}

/// A decimal integer: [+-]digits, within the range of int.
std::optional<long long> parse_integer(const std::string& s) {
  const std::size_t start = (!s.empty() && (s[0] == '+' || s[0] == '-')) ? 1 : 0;
  if (!is_digits(s.substr(start)) || s.size() - start > 10) return std::nullopt;
  const long long value = std::strtoll(s.c_str(), nullptr, 10);
  if (value > 2147483647LL || value < -2147483647LL) return std::nullopt;
  return value;
}

/// Optimal-string-alignment distance, for "did you mean" hints.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

bool looks_like(const std::string& typo, const std::string& key) {
  const std::size_t allowed = key.size() <= 4 ? 1 : 2;
  const std::size_t length_difference = typo.size() > key.size() ? typo.size() - key.size() : key.size() - typo.size();
  return length_difference <= allowed && edit_distance(typo, key) <= allowed;
}

// ---------------------------------------------------------------------------------------------
// Paths and locations.

/// Dotted path for messages: "" is the top level.
std::string show_path(const std::string& path) { return path.empty() ? "(top level)" : path; }

std::string child_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string item_path(const std::string& parent, const std::size_t index) { return fmt::format("{}[{}]", parent, index); }

/// True when `path` is `root` or lies below it ("bodies[0].velocity" lies below "bodies[0]").
bool lies_within(const std::string& path, const std::string& root) {
  if (root.empty()) return true;
  if (path.size() < root.size() || path.compare(0, root.size(), root) != 0) return false;
  return path.size() == root.size() || path[root.size()] == '.' || path[root.size()] == '[';
}

/// A value as it appears in messages: scalars as written (quoted ones in quotes), lists and maps
/// in flow style, long values shortened.
std::string show(const YAML::Node& node) {
  std::string text;
  if (!node.IsDefined() || node.IsNull()) {
    text = "(empty)";
  } else if (node.IsScalar()) {
    text = node.Tag() == "!" ? "\"" + node.Scalar() + "\"" : node.Scalar();
  } else {
    YAML::Emitter out;
    out.SetMapFormat(YAML::Flow);
    out.SetSeqFormat(YAML::Flow);
    out << node;
    text = out.c_str();
  }
  for (auto& c : text)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  return text.size() > 60 ? text.substr(0, 57) + "..." : text;
}

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

const Check any_number = [](Real) { return true; };
const Check positive = [](const Real x) { return x > 0; };
const Check non_negative = [](const Real x) { return x >= 0; };
/// lo < x <= hi
Check in_half_open(const Real lo, const Real hi) {
  return [=](const Real x) { return x > lo && x <= hi; };
}
/// lo < x < hi
Check in_open(const Real lo, const Real hi) {
  return [=](const Real x) { return x > lo && x < hi; };
}
/// lo <= x <= hi
Check in_closed(const Real lo, const Real hi) {
  return [=](const Real x) { return x >= lo && x <= hi; };
}
/// |x| <= bound
Check magnitude_at_most(const Real bound) {
  return [=](const Real x) { return std::abs(x) <= bound; };
}

bool is_plain_scalar(const YAML::Node& node) { return node.IsScalar() && node.Tag() == "?"; }

Real to_real(const Source& src, const Field& f, const Check& check, const std::string& form) {
  const auto value = is_plain_scalar(f.node) ? parse_real(f.node.Scalar()) : std::nullopt;
  if (!value || !check(*value)) src.expected(f, form);
  return *value;
}

int to_int(const Source& src, const Field& f, const std::function<bool(long long)>& check, const std::string& form) {
  const auto value = is_plain_scalar(f.node) ? parse_integer(f.node.Scalar()) : std::nullopt;
  if (!value || !check(*value)) src.expected(f, form);
  return static_cast<int>(*value);
}

bool to_bool(const Source& src, const Field& f, const std::string& form) {
  if (is_plain_scalar(f.node)) {
    const std::string& s = f.node.Scalar();
    if (s == "true" || s == "True" || s == "TRUE") return true;
    if (s == "false" || s == "False" || s == "FALSE") return false;
  }
  src.expected(f, form);
}

std::string to_text(const Source& src, const Field& f, const std::string& form) {
  if (!f.node.IsScalar() || trim(f.node.Scalar()).empty()) src.expected(f, form);
  const std::string& s = f.node.Scalar();
  if (const std::size_t bad = utf8_error(s); bad != std::string::npos) {
    src.fail(f, fmt::format("{}: the text is not valid UTF-8 (byte 0x{:02x} at position {}); expected {}, as UTF-8 text",
                            show_path(f.path), static_cast<unsigned char>(s[bad]), bad + 1, form));
  }
  return s;
}

std::string to_name(const Source& src, const Field& f, const std::string& form) {
  if (!f.node.IsScalar() || !is_name(f.node.Scalar())) src.expected(f, form);
  return f.node.Scalar();
}

std::string to_choice(const Source& src, const Field& f, const std::vector<std::string>& options) {
  if (!f.node.IsScalar() || std::find(options.begin(), options.end(), f.node.Scalar()) == options.end())
    src.expected(f, "one of: " + join(options));
  return f.node.Scalar();
}

Vec to_vec(const Source& src, const Field& f, const std::string& form) {
  if (!f.node.IsSequence() || f.node.size() != static_cast<std::size_t>(dim)) src.expected(f, form);
  Vec v;
  for (int i = 0; i < dim; ++i) {
    const YAML::Node c = f.node[static_cast<std::size_t>(i)];
    const auto value = is_plain_scalar(c) ? parse_real(c.Scalar()) : std::nullopt;
    if (!value) src.expected(f, form);
    v[i] = *value;
  }
  return v;
}

/// The components of a vector of the build's dimension for expected forms, each the axis name after
/// `prefix`: "[x, y]" in 2D and "[x, y, z]" in 3D; with prefix "g": "[gx, gy]" and "[gx, gy, gz]".
std::string components(const std::string& prefix = "") {
  std::string s = "[";
  for (int a = 0; a < dim; ++a) s += (a ? ", " : "") + prefix + "xyz"[a];
  return s + "]";
}

/// A vector as "[1, 2]" (2D) or "[1, 2, 3]" (3D).
std::string show_vec(const Vec& v) {
  std::string s = "[";
  for (int a = 0; a < dim; ++a) s += (a ? ", " : "") + fmt::format("{:g}", v[a]);
  return s + "]";
}

std::string show_rect(const Rect& r) { return fmt::format("{{min: {}, max: {}}}", show_vec(r.lo), show_vec(r.hi)); }

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
// The sections of a case.

const std::string rect_form = "a rectangle {min: " + components() + ", max: " + components() + "} in metres";
const std::string point_form = "a point " + components() + " in metres";
const std::string direction_form = "a non-zero direction " + components() + " of the force";

/// A time step of key `key` (already read, `dt`) at least min_time_step and at most max_steps up to `end`.
void check_time_step(MapReader& r, const std::string& key, const Real dt, const Real end) {
  const Real lowest = std::max(min_time_step, end / max_steps);
  if (dt < lowest)
    r.source().expected(r.at(key), fmt::format("a time step of at least {:g} s (at least {:g} s, and at most {:g} steps up "
                                               "to time.end = {:g} s) [s]",
                                               lowest, min_time_step, max_steps, end));
}

/// An interval between outputs of key `key` (already read, `interval`; `what` are the outputs, e.g.
/// "frames"): at least min_interval and at most max_frames up to time.end. The default (`given` false) is
/// checked too: a long time.end may need a longer interval than the default.
void check_interval(MapReader& r, const std::string& key, const Real interval, const bool given, const Real end,
                    const std::string& what) {
  const Real lowest = std::max(min_interval, end / max_frames);
  if (interval >= lowest) return;
  const std::string form = fmt::format("an interval of at least {:g} s (at least {:g} s, and at most {:g} {} up to "
                                       "time.end = {:g} s) [s]",
                                       lowest, min_interval, max_frames, what, end);
  if (given) r.source().expected(r.at(key), form);
  r.source().fail(r.field(), fmt::format("{} = {:g} (default): expected {}", r.path_of(key), interval, form));
}

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

/// A name that must be unique within `names` (name -> path of its first use).
std::string unique_name(MapReader& r, std::map<std::string, std::string>& names, const std::string& among) {
  const std::string name = r.name("name", name_form + ", unique among " + among);
  const auto [it, inserted] = names.emplace(name, r.path_of("name"));
  if (!inserted)
    r.source().fail(r.at("name"), fmt::format("{} = {}: duplicate name (also {}); expected a name unique among {}",
                                              r.path_of("name"), name, it->second, among));
  return name;
}

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

/// A file named in the case: an absolute path, or relative to the case file's directory.
fs::path resolve(const fs::path& base_dir, const std::string& file) {
  return fs::path(file).is_absolute() ? fs::path(file) : base_dir / file;
}

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

FileKey file_key(MapReader& r, const std::string& key, const fs::path& base_dir, const std::string& form) {
  const fs::path path = resolve(base_dir, r.text(key, form));
  return {path, r.at(key)};
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

/// Fields of the bodies and walls kept for the cross-checks.
struct GeometryFields {
  std::vector<Field> body_rect, body_material, body_clamp, body_subtract, wall_rect;
};

const std::string wall_motion_form =
    "a motion {translation: {type: velocity, velocity: " + components() + "} or {type: sine, amplitude: " + components() +
    ", period} or {type: table, file, direction}, rotation: {type: sine, pivot: " + components() +
    (dim == 3 ? ", axis: [x, y, z]" : "") + ", amplitude_deg, period} or {type: table, file, pivot" +
    (dim == 3 ? ", axis" : "") + "}, start, ramp, stop} or {wave_maker: {type: piston | flap, stroke, period, direction, "
    "hinge, water_level}, start, ramp, stop} (times in s)";

TimeTable read_table(const Source& src, const Field& f, const fs::path& path, const TimeTableColumn& column);

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

/// Every rectangle is inside the domain and at least one particle (dp/2) thick; bodies do not overlap
/// A solid body's clamp that reaches into a wall with a motion of its own (the wall's bounds and its 3 layers)
/// moves with that wall (BodySpec::clamp_wall): a plate clamped into a paddle. A clamp in two such walls is refused.
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

/// each other or a block and lie in a box when there is one (a clamped end may reach into a wall);
/// clamps touch their body.
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

/// A table file named by `f` (the path as resolved), read by read_time_table (core/tank_motion.hpp), the one
/// reader of the case's tables; its problems become "location: key = value: <file:line: problem>".
TimeTable read_table(const Source& src, const Field& f, const fs::path& path, const TimeTableColumn& column) {
  try {
    return read_time_table(path.string(), column);
  } catch (const TableError& e) {
    src.fail(f, fmt::format("{} = {}: {}", f.path, show(f.node), e.what()));
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

// ---------------------------------------------------------------------------------------------
// Loading and overrides.

YAML::Node load_yaml(const std::string& text, const std::string& file) {
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(text);
  } catch (const YAML::Exception& e) {
    if (e.mark.is_null()) throw CaseError(fmt::format("{}: YAML syntax error: {}; expected valid YAML", file, e.msg));
    // Tabs are the most common cause: YAML indents with spaces only.
    const std::vector<std::string> lines = split(text, '\n');
    const auto line = static_cast<std::size_t>(e.mark.line);
    const bool has_tab = line < lines.size() && lines[line].find('\t') != std::string::npos;
    throw CaseError(fmt::format("{}:{}: YAML syntax error: {}; expected valid YAML{}", file, e.mark.line + 1, e.msg,
                                has_tab ? " (this line has a tab: indent with spaces)" : ""));
  }
  if (documents.size() > 1)
    throw CaseError(fmt::format("{}:{}: a second YAML document; expected one document per case file", file,
                                documents[1].Mark().line + 1));
  YAML::Node root;
  if (!documents.empty() && !documents[0].IsNull()) root.reset(documents[0]);
  else root.reset(YAML::Node(YAML::NodeType::Map));
  return root;
}

bool has_key(const YAML::Node& map, const std::string& key) {
  for (const auto& kv : map)
    if (kv.first.IsScalar() && kv.first.Scalar() == key) return true;
  return false;
}

/// Applies one "dotted.key=value" override to the tree (see docs/case-format.md).
void apply_override(YAML::Node& root, const std::string& text, Source& src) {
  const auto fail = [&](const std::string& message) {
    throw CaseError(fmt::format("{} (--set {}): {}", src.file(), text, message));
  };
  const auto eq = text.find('=');
  if (eq == std::string::npos) fail("expected dotted.key=value, e.g. --set time.end=0.5");
  const std::string key = trim(text.substr(0, eq));
  const std::string value_text = text.substr(eq + 1);
  const std::vector<std::string> segments = split(key, '.');
  if (std::any_of(segments.begin(), segments.end(), [](const std::string& s) { return s.empty(); }))
    fail(fmt::format("'{}' is not a dotted key; expected keys separated by single dots, e.g. bodies.column.velocity", key));
  YAML::Node value;
  try {
    value.reset(YAML::Load(value_text));
  } catch (const YAML::Exception& e) {
    fail(fmt::format("the value '{}' is not valid YAML ({}); expected a YAML value, e.g. 0.5, [0, 0] or auto", value_text,
                     e.msg));
  }

  YAML::Node node(root);
  std::string path;
  std::string created;  // path of the first node the override creates
  for (std::size_t s = 0; s < segments.size(); ++s) {
    const std::string& segment = segments[s];
    const bool last = s + 1 == segments.size();
    YAML::Node next;
    if (node.IsSequence()) {
      std::size_t index = node.size();
      if (is_digits(segment)) {
        index = segment.size() <= 9 ? std::stoul(segment) : node.size();
        if (index >= node.size())
          fail(fmt::format("index {} is out of range: {} has {} element(s)", segment, show_path(path), node.size()));
      } else {
        std::vector<std::string> names;
        for (std::size_t i = 0; i < node.size(); ++i) {
          const YAML::Node item = node[i];
          if (!item.IsMap()) continue;
          for (const auto& kv : item) {
            if (!kv.first.IsScalar() || kv.first.Scalar() != "name" || !kv.second.IsScalar()) continue;
            names.push_back(kv.second.Scalar());
            if (kv.second.Scalar() == segment && index == node.size()) index = i;
          }
        }
        if (index == node.size())
          fail(fmt::format("{} has no element named '{}'; expected an index (0 to {}) or one of the names: {}",
                           show_path(path), segment, node.size() == 0 ? 0 : node.size() - 1,
                           names.empty() ? std::string("(none)") : join(names)));
      }
      path = item_path(path, index);
      if (last) node[index] = value;
      else next.reset(node[index]);
    } else if (node.IsMap() || node.IsNull()) {
      const bool exists = node.IsMap() && has_key(node, segment);
      path = child_path(path, segment);
      if (!exists && created.empty()) created = path;
      if (last) {
        node[segment] = value;
      } else {
        if (!exists) node[segment] = YAML::Node(YAML::NodeType::Map);
        next.reset(node[segment]);
      }
    } else {
      fail(fmt::format("{} is a single value ({}), so it has no key '{}'; expected a path to a key of the case",
                       show_path(path), show(node), segment));
    }
    if (!last) node.reset(next);
  }
  src.add_override({text, created.empty() ? path : created});
}

std::string emit(const YAML::Node& root) {
  YAML::Emitter out;
  out << root;
  return std::string(out.c_str()) + "\n";
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

namespace {

/// Every leaf of a YAML tree as "dotted.key[i]" -> value text.
void flatten(const YAML::Node& node, const std::string& key, std::map<std::string, std::string>& out) {
  if (node.IsMap()) {
    if (node.size() == 0) out[key] = "{}";
    for (const auto& kv : node) flatten(kv.second, key.empty() ? kv.first.Scalar() : key + "." + kv.first.Scalar(), out);
  } else if (node.IsSequence()) {
    if (node.size() == 0) out[key] = "[]";
    for (std::size_t i = 0; i < node.size(); ++i) flatten(node[i], key + "[" + std::to_string(i) + "]", out);
  } else if (node.IsNull() || !node.IsDefined()) {
    out[key] = "~";
  } else {
    out[key] = node.Scalar();
  }
}

bool same_value(const std::string& a, const std::string& b) {
  if (a == b) return true;
  char* end_a = nullptr;
  char* end_b = nullptr;
  const double x = std::strtod(a.c_str(), &end_a), y = std::strtod(b.c_str(), &end_b);
  return !a.empty() && !b.empty() && *end_a == '\0' && *end_b == '\0' && x == y;
}

}  // namespace

const std::vector<std::string>& restart_free_keys() {
  static const std::vector<std::string> keys = {"time.end", "output", "description", "source"};
  return keys;
}

const std::vector<std::string>& restart_tunable_keys() {
  static const std::vector<std::string> keys = {
      "time.cfl",       "time.dt",         "time.dt_max",         "coupling.subcycles",
      "fluid.solver",   "fluid.preconditioner", "fluid.tolerance", "fluid.max_iterations",
      "fluid.preconditioner_rebuild_every", "fluid.coarse_size", "fluid.max_loss", "solid.dt", "solid.dt_factor", "parallel"};
  return keys;
}

bool key_under(const std::string& key, const std::vector<std::string>& roots) {
  for (const auto& k : roots)
    if (key == k || key.rfind(k + ".", 0) == 0 || key.rfind(k + "[", 0) == 0) return true;
  return false;
}

std::vector<CaseDifference> case_differences(const std::string& yaml_a, const std::string& yaml_b) {
  std::map<std::string, std::string> a, b;
  flatten(YAML::Load(yaml_a), "", a);
  flatten(YAML::Load(yaml_b), "", b);
  std::map<std::string, CaseDifference> diffs;  // sorted by key
  for (const auto& [key, value] : a) {
    if (key_under(key, restart_free_keys())) continue;
    const auto it = b.find(key);
    if (it == b.end())
      diffs[key] = {key, value, "(absent)"};
    else if (!same_value(value, it->second))
      diffs[key] = {key, value, it->second};
  }
  for (const auto& [key, value] : b)
    if (!key_under(key, restart_free_keys()) && !a.count(key)) diffs[key] = {key, "(absent)", value};
  std::vector<CaseDifference> out;
  for (auto& kv : diffs) out.push_back(std::move(kv.second));
  return out;
}

}  // namespace mpsfsi
