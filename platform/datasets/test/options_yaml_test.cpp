#include "beslam/datasets/options_yaml.hpp"

#include <gtest/gtest.h>

#include "test_util.hpp"

namespace beslam::datasets {
namespace {

TEST(OptionsYaml, ReadsAllKeysAndRoundTrips) {
  const YAML::Node node = YAML::Load(
      "{type: tum, root: /data/rgbd_dataset_freiburg1_xyz, sequence: '', camera: auto, load_color: true,"
      " load_lidar: false, first: 2, last: 40, step: 3, undistort: false, gt_max_dt: 0.01,"
      " camera_override: {fx: 500, fy: 501, cx: 320, cy: 240}}");
  const DatasetOptions o = datasetOptionsFromYaml(node, "run.yaml");
  EXPECT_EQ(o.type, "tum");
  EXPECT_TRUE(o.load_color);
  EXPECT_EQ(o.first, 2);
  EXPECT_EQ(o.last, 40);
  EXPECT_EQ(o.step, 3);
  EXPECT_FALSE(o.undistort);
  EXPECT_DOUBLE_EQ(o.gt_max_dt, 0.01);
  ASSERT_TRUE(o.camera_override);
  EXPECT_DOUBLE_EQ(o.camera_override->fy, 501);
  EXPECT_EQ(o.camera_override->width, 0);
  const DatasetOptions back = datasetOptionsFromYaml(datasetOptionsToYaml(o), "x");
  EXPECT_EQ(back.root, o.root);
  EXPECT_EQ(back.step, 3);
  EXPECT_DOUBLE_EQ(back.camera_override->cx, 320);
  // Sequence numbers written unquoted stay strings as written.
  EXPECT_EQ(datasetOptionsFromYaml(YAML::Load("{type: kitti_odometry, root: r, sequence: 06}"), "x").sequence, "06");
}

TEST(OptionsYaml, Errors) {
  EXPECT_BESLAM_ERROR(datasetOptionsFromYaml(YAML::Load("{type: tum, root: r, sequnce: 06}"), "run.yaml"), "run.yaml",
                      "unknown key dataset.sequnce");
  EXPECT_BESLAM_ERROR(datasetOptionsFromYaml(YAML::Load("{type: tum, root: r, step: two}"), "run.yaml"),
                      "dataset.step must be an integer");
  EXPECT_BESLAM_ERROR(datasetOptionsFromYaml(YAML::Load("{type: tum, root: r, load_color: [1]}"), "run.yaml"),
                      "dataset.load_color must be true or false");
  EXPECT_BESLAM_ERROR(datasetOptionsFromYaml(YAML::Load("{root: r}"), "run.yaml"), "dataset.type is missing");
  EXPECT_BESLAM_ERROR(datasetOptionsFromYaml(YAML::Load("[1, 2]"), "run.yaml"), "must be a map");
  EXPECT_BESLAM_ERROR(
      datasetOptionsFromYaml(YAML::Load("{type: tum, root: r, camera_override: {fx: 1, fy: 1, cx: 1}}"), "y"),
      "camera_override needs cy");
}

}  // namespace
}  // namespace beslam::datasets
