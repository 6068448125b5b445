// The case file's reading machinery (io/case_reader.hpp): text helpers, locations, the conversions of one
// value, and the keys that several sections share.
#include "io/case_reader.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

namespace mpsfsi::case_detail {

// ---------------------------------------------------------------------------------------------
// Small string helpers.

std::string join(const std::vector<std::string>& items, const std::string& separator) {
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

const std::string name_form = "a name of at most 64 letters, digits, '_' and '-' that starts with a letter or '_'";

namespace {

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

}  // namespace

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
std::string components(const std::string& prefix) {
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
// Keys that several sections share.

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

/// A name that must be unique within `names` (name -> path of its first use).
std::string unique_name(MapReader& r, std::map<std::string, std::string>& names, const std::string& among) {
  const std::string name = r.name("name", name_form + ", unique among " + among);
  const auto [it, inserted] = names.emplace(name, r.path_of("name"));
  if (!inserted)
    r.source().fail(r.at("name"), fmt::format("{} = {}: duplicate name (also {}); expected a name unique among {}",
                                              r.path_of("name"), name, it->second, among));
  return name;
}

namespace {

/// A file named in the case: an absolute path, or relative to the case file's directory.
fs::path resolve(const fs::path& base_dir, const std::string& file) {
  return fs::path(file).is_absolute() ? fs::path(file) : base_dir / file;
}

}  // namespace

FileKey file_key(MapReader& r, const std::string& key, const fs::path& base_dir, const std::string& form) {
  const fs::path path = resolve(base_dir, r.text(key, form));
  return {path, r.at(key)};
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

}  // namespace mpsfsi::case_detail
