// The case as a YAML tree: the one document of a case text, the --set overrides applied to it, the tree as
// text (case.resolved.yaml), and the differences of two resolved cases that a restart checks.
#include "io/case_reader.hpp"

#include <cstdlib>

namespace mpsfsi {
namespace case_detail {

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

}  // namespace case_detail

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
