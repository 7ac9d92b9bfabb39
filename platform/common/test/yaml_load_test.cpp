#include "beslam/common/yaml_load.hpp"

#include <gtest/gtest.h>

#include <string>

#include "beslam/common/error.hpp"
#include "beslam/common/yaml_set.hpp"

namespace {

std::string errorOf(const std::string& text) {
  try {
    beslam::loadYaml(text, "p.yaml");
  } catch (const beslam::Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted: " << text.substr(0, 200);
  return {};
}

// The classic "billion laughs": ten lines, 1.2 KB, 9^9 = 387,420,489 leaves once expanded.
std::string aliasBomb() {
  std::string text = "a: &a [\"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\", \"lol\"]\n";
  const std::string names = "abcdefghi";
  for (size_t i = 1; i < names.size(); ++i) {
    text += std::string(1, names[i]) + ": &" + names[i] + " [";
    for (int k = 0; k < 9; ++k) text += std::string(k ? ", " : "") + "*" + names[i - 1] + ", *" + names[i - 1];
    text += "]\n";
  }
  return text;
}

}  // namespace

TEST(YamlLoad, LoadsOrdinaryYamlWithAnchorsAndAliases) {
  const YAML::Node n = beslam::loadYaml("a: &x {b: 1, c: [1, 2]}\nd: *x\ne: \"it's [ not a list\"\n", "p.yaml");
  EXPECT_EQ(n["d"]["c"].size(), 2u);
  EXPECT_EQ(n["e"].as<std::string>(), "it's [ not a list");
  EXPECT_TRUE(beslam::loadYaml("", "p.yaml").IsNull());
}

// Probe: yaml-cpp keeps the first of two equal keys and drops the second without a word.
TEST(YamlLoad, ADuplicateKeyNamesBothLines) {
  EXPECT_EQ(errorOf("backend:\n  plugin: backend_orb\n  features: 20000\n  features: 100\n"),
            "p.yaml:4: duplicate key 'features' (first at line 3; give each key once)");
  EXPECT_EQ(errorOf("a: {x: 1, \"x\": 2}\n"), "p.yaml:1: duplicate key 'x' (first at line 1; give each key once)");
  // The same key in two different maps, and equal values, are fine.
  EXPECT_NO_THROW(beslam::loadYaml("a: {x: 1}\nb: {x: 1}\nc: [x, x]\n", "p.yaml"));
}

// Found by the bench_matrix fuzz target: a map written as a key ("{label: a}: ...") made yaml-cpp's
// as<std::string>() throw a bad-conversion exception past every reader's checks.
TEST(YamlLoad, AKeyThatIsNotAPlainNameIsRefused) {
  const std::string expected = "a key must be a plain name (not a list, a map, an alias or empty)";
  EXPECT_EQ(errorOf("sequences:\n  - {label: a}:\n  - {label: b}\n"), "p.yaml:2: " + expected);
  EXPECT_EQ(errorOf("[1, 2]: x\n"), "p.yaml:1: " + expected);
  EXPECT_EQ(errorOf("a: &k x\n*k : y\n"), "p.yaml:2: " + expected);
  EXPECT_EQ(errorOf("? \n: y\n"), "p.yaml:2: " + expected);
  EXPECT_NO_THROW(beslam::loadYaml("\"quoted key\": 1\n'1': 2\n3: [a, b]\n", "p.yaml"));
}

// Probe: a 1.2 KB alias bomb used to hang every reader that walked it; now one error, at once.
TEST(YamlLoad, AnAliasBombIsRefused) {
  const std::string bomb = aliasBomb();
  EXPECT_LT(bomb.size(), 1300u);
  const std::string message = errorOf(bomb);
  EXPECT_NE(message.find("p.yaml:"), std::string::npos) << message;
  EXPECT_NE(message.find("more than 1000000 nodes once its aliases (*name) are expanded"), std::string::npos)
      << message;
}

// Probe: 100,000-deep nesting said only "bad file"; flow and block nesting past the limit are one error.
TEST(YamlLoad, DeepNestingIsRefused) {
  const std::string deep = "a: " + std::string(100000, '[') + std::string(100000, ']') + "\n";
  EXPECT_EQ(errorOf(deep), "p.yaml:1: nested deeper than 64 levels; refused");
  std::string dashes;
  for (int i = 0; i < 100000; ++i) dashes += "- ";
  EXPECT_EQ(errorOf(dashes + "x\n"), "p.yaml:1: nested deeper than 64 levels; refused");
  std::string blocks;
  for (int i = 0; i < 70; ++i) blocks += std::string(2 * i, ' ') + "k" + std::to_string(i) + ":\n";
  EXPECT_EQ(errorOf(blocks), "p.yaml:65: nested deeper than 64 levels; refused");
  // 64 levels are fine; brackets inside quotes do not count.
  EXPECT_NO_THROW(beslam::loadYaml("a: " + std::string(63, '[') + std::string(63, ']') + "\n", "p.yaml"));
  EXPECT_NO_THROW(beslam::loadYaml("a: \"" + std::string(100, '[') + "\"\n", "p.yaml"));
}

TEST(YamlLoad, SyntaxErrorsNameFileAndLine) {
  const std::string message = errorOf("a: 1\nb: [1, 2\n");
  EXPECT_EQ(message.rfind("p.yaml:", 0), 0u) << message;
  EXPECT_NE(message.find("YAML syntax error"), std::string::npos) << message;
}

TEST(YamlLoad, SetOverridesAreCheckedToo) {
  YAML::Node root = YAML::Load("a: 1\n");
  try {
    beslam::applySetOverride(root, "b={x: 1, x: 2}");
    ADD_FAILURE() << "accepted";
  } catch (const beslam::Error& e) {
    EXPECT_NE(std::string(e.what()).find("duplicate key 'x'"), std::string::npos) << e.what();
  }
}
