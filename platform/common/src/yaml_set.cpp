#include "beslam/common/yaml_set.hpp"

#include <vector>

#include "beslam/common/error.hpp"
#include "beslam/common/yaml_load.hpp"

namespace beslam {

namespace {

// A copy of a parsed value without source marks, so errors about it say "--set", not "line 1".
YAML::Node withoutMarks(const YAML::Node& node) {
  if (node.IsScalar()) return YAML::Node(node.Scalar());
  if (node.IsSequence()) {
    YAML::Node out(YAML::NodeType::Sequence);
    for (const auto& item : node) out.push_back(withoutMarks(item));
    return out;
  }
  if (node.IsMap()) {
    YAML::Node out(YAML::NodeType::Map);
    for (const auto& kv : node) out[kv.first.Scalar()] = withoutMarks(kv.second);
    return out;
  }
  return YAML::Node();
}

}  // namespace

void applySetOverride(YAML::Node& root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw Error("--set " + assignment + ": expected key=value (e.g. backend.plugin=backend_orb)");
  const std::string key = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);

  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const auto dot = key.find('.', start);
    parts.push_back(key.substr(start, dot - start));
    if (parts.back().empty()) throw Error("--set " + assignment + ": empty key segment in '" + key + "'");
    if (dot == std::string::npos) break;
    start = dot + 1;
  }

  YAML::Node value;
  try {
    checkYaml(text, "value");
    value = YAML::Load(text);
  } catch (const Error& e) {
    throw Error("--set " + assignment + ": " + e.what());
  } catch (const YAML::Exception& e) {
    throw Error("--set " + assignment + ": value is not valid YAML: " + e.msg);
  }
  if (!value.IsDefined() || value.IsNull()) value = YAML::Node(text);
  value = withoutMarks(value);

  // yaml-cpp nodes are handles: walk by reassigning a handle to each child map.
  YAML::Node node = root;
  if (!node.IsDefined() || node.IsNull()) node = YAML::Node(YAML::NodeType::Map);
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    YAML::Node child = node[parts[i]];
    if (child.IsDefined() && !child.IsNull() && !child.IsMap())
      throw Error("--set " + assignment + ": '" + parts[i] + "' is not a map");
    if (!child.IsDefined() || child.IsNull()) node[parts[i]] = YAML::Node(YAML::NodeType::Map);
    node.reset(node[parts[i]]);
  }
  node[parts.back()] = value;
}

}  // namespace beslam
