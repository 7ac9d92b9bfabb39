#include "beslam/common/yaml_set.hpp"

#include <gtest/gtest.h>

#include "beslam/common/error.hpp"

TEST(YamlSet, SetsNestedValuesAndCreatesMaps) {
  YAML::Node root = YAML::Load("dataset: {root: a}\n");
  beslam::applySetOverride(root, "dataset.root=/data/kitti");
  beslam::applySetOverride(root, "backend.options.features=3000");
  beslam::applySetOverride(root, "list=[1, 2, 3]");
  EXPECT_EQ(root["dataset"]["root"].as<std::string>(), "/data/kitti");
  EXPECT_EQ(root["backend"]["options"]["features"].as<int>(), 3000);
  EXPECT_EQ(root["list"].size(), 3u);
}

TEST(YamlSet, RejectsMalformedAssignments) {
  YAML::Node root = YAML::Load("a: 1\n");
  EXPECT_THROW(beslam::applySetOverride(root, "novalue"), beslam::Error);
  EXPECT_THROW(beslam::applySetOverride(root, "=3"), beslam::Error);
  EXPECT_THROW(beslam::applySetOverride(root, "a..b=3"), beslam::Error);
  EXPECT_THROW(beslam::applySetOverride(root, "a.b=3"), beslam::Error);  // a is a scalar
}
