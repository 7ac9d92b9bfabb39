// YAML files as every host reader loads them: checked event by event before yaml-cpp builds the node
// tree, so that what yaml-cpp would take silently or could not finish is one error naming the file and
// line instead: a key given twice in one map (yaml-cpp keeps the first and drops the second without a
// word), a key that is not a plain scalar (a list, map, alias or nothing: readers would throw on it), nesting deeper
// than kMaxYamlDepth, and a document larger than kMaxYamlNodes nodes once its aliases are expanded (a "billion laughs"
// file of a kilobyte expands to billions of nodes: every reader that walks it would hang). Syntax errors are
// "FILE:LINE: YAML syntax error: ...".
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <string>

namespace beslam {

constexpr std::size_t kMaxYamlDepth = 64;
constexpr std::size_t kMaxYamlNodes = 1'000'000;

// Throws beslam::Error naming `file` (and the line) when `text` breaks one of the rules above.
void checkYaml(const std::string& text, const std::string& file);
// checkYaml, then the node tree of the first document.
YAML::Node loadYaml(const std::string& text, const std::string& file);
// loadYaml of the file's contents; a file that cannot be read is an error naming it.
YAML::Node loadYamlFile(const std::string& path);

// Where a node stands, for messages: "FILE:LINE", or FILE followed by `no_line` for a node with no place in
// the file (one an override created: the pipeline reader passes " (--set)").
std::string yamlWhere(const std::string& file, const YAML::Node& node, const std::string& no_line = "");
// A node as text for messages: a scalar's value, else its YAML form.
std::string yamlText(const YAML::Node& node);

}  // namespace beslam
