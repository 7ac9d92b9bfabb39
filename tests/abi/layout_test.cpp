// The ABI's struct layout must be the same from C and from C++ (and must not drift: the numbers in
// layout.c are the ABI 1.0 layout on LP64).
#include <gtest/gtest.h>

#include <cstddef>

#include "beslam/plugin.h"

extern "C" size_t beslam_c_layout(int i);

static_assert(sizeof(beslam_box3d) == 168, "beslam_box3d");
static_assert(offsetof(beslam_plugin_descriptor, functions) == 80, "descriptor.functions");
static_assert(sizeof(beslam_frame) == 104, "beslam_frame");

TEST(AbiLayout, CAndCppAgree) {
  const size_t cpp[] = {
      sizeof(beslam_pose),
      sizeof(beslam_image_view),
      sizeof(beslam_point_cloud_view),
      sizeof(beslam_box3d),
      offsetof(beslam_box3d, velocity_cam),
      offsetof(beslam_box3d, occlusion),
      sizeof(beslam_camera),
      sizeof(beslam_frame),
      offsetof(beslam_frame, lidar),
      sizeof(beslam_create_info),
      offsetof(beslam_create_info, camera),
      sizeof(beslam_plugin_descriptor),
      offsetof(beslam_plugin_descriptor, create),
      sizeof(beslam_config_field),
      sizeof(beslam_config_value),
      sizeof(beslam_host),
      sizeof(beslam_keyframe),
      sizeof(beslam_object_landmark),
      offsetof(beslam_object_landmark, surface_points),
      sizeof(beslam_track_result),
      offsetof(beslam_track_result, T_world_cam),
      sizeof(beslam_detector_v1),
      sizeof(beslam_motion_checker_v1),
      sizeof(beslam_mask_generator_v1),
      sizeof(beslam_reconstructor_v1),
      sizeof(beslam_backend_v1),
      sizeof(beslam_map_point),
      sizeof(beslam_trajectory_entry),
      sizeof(beslam_mask_buffer),
      sizeof(beslam_keyframe_point),
      offsetof(beslam_keyframe, points),
  };
  for (int i = 0; i < static_cast<int>(sizeof(cpp) / sizeof(cpp[0])); ++i)
    EXPECT_EQ(beslam_c_layout(i), cpp[i]) << "layout entry " << i;
  EXPECT_EQ(beslam_c_layout(1000), static_cast<size_t>(-1));
}

TEST(AbiLayout, EveryGrowableStructStartsWithItsSize) {
  EXPECT_EQ(offsetof(beslam_host, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_camera, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_frame, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_create_info, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_plugin_descriptor, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_track_result, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_keyframe, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_object_landmark, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_detector_v1, struct_size), 0u);
  EXPECT_EQ(offsetof(beslam_backend_v1, struct_size), 0u);
}

TEST(AbiLayout, VersionEncoding) {
  EXPECT_EQ(BESLAM_ABI_VERSION >> 16, static_cast<uint32_t>(BESLAM_ABI_VERSION_MAJOR));
  EXPECT_EQ(BESLAM_ABI_VERSION & 0xffffu, static_cast<uint32_t>(BESLAM_ABI_VERSION_MINOR));
}
