#include "beslam/common/yaml_load.hpp"

#include <yaml-cpp/eventhandler.h>

#include <map>
#include <sstream>
#include <vector>

#include "beslam/common/error.hpp"
#include "beslam/common/file_io.hpp"

namespace beslam {
namespace {

// Walks the parser's events with a stack of open collections: counts every node as if each alias were a
// copy of its anchor, and remembers each map's keys with their lines.
class Checker : public YAML::EventHandler {
 public:
  explicit Checker(std::string file) : file_(std::move(file)) {}

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override { leaf(mark, anchor, 1, nullptr); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const auto it = sizes_.find(anchor);
    leaf(mark, 0, it == sizes_.end() ? 1 : it->second, nullptr);
  }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor, const std::string& value) override {
    leaf(mark, anchor, 1, &value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    open(mark, anchor, false);
  }
  void OnSequenceEnd() override { close(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    open(mark, anchor, true);
  }
  void OnMapEnd() override { close(); }

 private:
  struct Open {
    bool is_map = false;
    YAML::anchor_t anchor = 0;
    std::size_t nodes_before = 0;  // expanded_ when it opened
    std::size_t items = 0;         // children so far (a map's keys are the even ones)
    std::map<std::string, int> keys;
  };

  static int lineOf(const YAML::Mark& mark) { return mark.line >= 0 ? mark.line + 1 : 0; }

  void count(const YAML::Mark& mark, std::size_t nodes) {
    expanded_ += nodes;
    if (expanded_ > kMaxYamlNodes)
      throwAt(file_,
              "more than " + std::to_string(kMaxYamlNodes) +
                  " nodes once its aliases (*name) are expanded; refused (an alias bomb?)",
              lineOf(mark));
  }

  // A child of the innermost open collection: a map's key must be a scalar (every reader names keys by
  // their text) and is checked against the map's other keys.
  void child(const YAML::Mark& mark, const std::string* scalar) {
    if (stack_.empty()) return;
    Open& parent = stack_.back();
    if (parent.is_map && parent.items % 2 == 0 && !scalar)
      throwAt(file_, "a key must be a plain name (not a list, a map, an alias or empty)", lineOf(mark));
    if (parent.is_map && parent.items % 2 == 0) {
      const auto [it, inserted] = parent.keys.emplace(*scalar, lineOf(mark));
      if (!inserted)
        throwAt(file_,
                "duplicate key '" + (scalar->size() > 80 ? scalar->substr(0, 80) + "..." : *scalar) +
                    "' (first at line " + std::to_string(it->second) + "; give each key once)",
                lineOf(mark));
    }
    ++parent.items;
  }

  void leaf(const YAML::Mark& mark, YAML::anchor_t anchor, std::size_t nodes, const std::string* scalar) {
    child(mark, scalar);
    count(mark, nodes);
    if (anchor) sizes_[anchor] = nodes;
  }

  void open(const YAML::Mark& mark, YAML::anchor_t anchor, bool is_map) {
    child(mark, nullptr);
    if (stack_.size() >= kMaxYamlDepth)
      throwAt(file_, "nested deeper than " + std::to_string(kMaxYamlDepth) + " levels; refused", lineOf(mark));
    const std::size_t before = expanded_;
    count(mark, 1);
    Open o;
    o.is_map = is_map;
    o.anchor = anchor;
    o.nodes_before = before;
    stack_.push_back(std::move(o));
  }

  void close() {
    if (stack_.empty()) return;
    const Open& o = stack_.back();
    if (o.anchor) sizes_[o.anchor] = expanded_ - o.nodes_before;
    stack_.pop_back();
  }

  std::string file_;
  std::vector<Open> stack_;
  std::map<YAML::anchor_t, std::size_t> sizes_;  // expanded node count of each anchored node
  std::size_t expanded_ = 0;
};

}  // namespace

void checkYaml(const std::string& text, const std::string& file) {
  // Flow collections ([ and {) nested past the limit are found in the text itself: yaml-cpp's scanner
  // would otherwise read the whole run before the first event (and fail with "bad file").
  {
    std::size_t depth = 0;
    int line = 1;
    char quote = 0;
    bool comment = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
      const char c = text[i];
      if (c == '\n') {
        ++line, comment = false;
        if (quote == 0) continue;
      }
      if (comment) continue;
      if (quote) {
        if (c == quote) quote = 0;
        if (c == '\\' && quote == '"') ++i;
        continue;
      }
      if (c == '#' && (i == 0 || text[i - 1] == ' ' || text[i - 1] == '\t' || text[i - 1] == '\n'))
        comment = true;
      else if ((c == '"' || c == '\'') && (i == 0 || std::string(" \t\n[{,:-").find(text[i - 1]) != std::string::npos))
        quote = c;  // a quoted scalar starts (an apostrophe inside a plain scalar does not)
      else if (c == '[' || c == '{') {
        if (++depth > kMaxYamlDepth)
          throwAt(file, "nested deeper than " + std::to_string(kMaxYamlDepth) + " levels; refused", line);
      } else if ((c == ']' || c == '}') && depth > 0)
        --depth;
    }
  }
  std::istringstream in(text);
  try {
    YAML::Parser parser(in);
    Checker checker(file);
    parser.HandleNextDocument(checker);
  } catch (const YAML::ParserException& e) {
    throwAt(file, "YAML syntax error: " + e.msg, e.mark.is_null() ? 0 : e.mark.line + 1);
  } catch (const YAML::Exception& e) {
    throwAt(file, "cannot read YAML: " + e.msg);
  }
}

YAML::Node loadYaml(const std::string& text, const std::string& file) {
  checkYaml(text, file);
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throwAt(file, "YAML syntax error: " + e.msg, e.mark.is_null() ? 0 : e.mark.line + 1);
  } catch (const YAML::Exception& e) {
    throwAt(file, "cannot read YAML: " + e.msg);
  }
}

YAML::Node loadYamlFile(const std::string& path) { return loadYaml(readFile(path), path); }

std::string yamlWhere(const std::string& file, const YAML::Node& node, const std::string& no_line) {
  const YAML::Mark mark = node.Mark();
  return mark.line < 0 ? file + no_line : file + ":" + std::to_string(mark.line + 1);
}

std::string yamlText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  std::stringstream ss;
  ss << node;
  return ss.str();
}

}  // namespace beslam
