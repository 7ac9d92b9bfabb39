/* The ABI's layout as a C11 compiler sees it: static asserts here, and the same numbers reported to
 * the C++ test (layout_test.cpp), which asserts them again as a C++ compiler sees them. */
#include <stddef.h>

#include "beslam/plugin.h"

/* Sizes and offsets a plugin built by any C or C++ compiler on LP64 must agree on. Changing one is a
 * breaking change (a new major version). */
_Static_assert(sizeof(beslam_pose) == 96, "beslam_pose");
_Static_assert(sizeof(beslam_image_view) == 24, "beslam_image_view");
_Static_assert(sizeof(beslam_point_cloud_view) == 24, "beslam_point_cloud_view");
_Static_assert(sizeof(beslam_box3d) == 168, "beslam_box3d");
_Static_assert(offsetof(beslam_box3d, center_cam) == 16, "beslam_box3d.center_cam");
_Static_assert(offsetof(beslam_box3d, score) == 128, "beslam_box3d.score");
_Static_assert(offsetof(beslam_box3d, position_sigma) == 144, "ABI 1.5 appends position_sigma to 1.4's 144 bytes");
_Static_assert(offsetof(beslam_plugin_descriptor, struct_size) == 0, "descriptor starts with struct_size");
_Static_assert(offsetof(beslam_plugin_descriptor, functions) == 80, "beslam_plugin_descriptor.functions");
_Static_assert(sizeof(beslam_plugin_descriptor) == 88, "beslam_plugin_descriptor");
_Static_assert(sizeof(beslam_config_field) == 56, "beslam_config_field");
_Static_assert(sizeof(beslam_config_value) == 48, "beslam_config_value");
_Static_assert(sizeof(beslam_frame) == 104, "beslam_frame");
_Static_assert(sizeof(beslam_create_info) == 192, "beslam_create_info");
_Static_assert(offsetof(beslam_create_info, camera_height) == 184, "ABI 1.1 appends camera_height to 1.0's 184 bytes");
_Static_assert(sizeof(beslam_track_result) == 296, "beslam_track_result");
_Static_assert(offsetof(beslam_track_result, world_moved) == 184, "ABI 1.7 appends world_moved to 1.6's 184 bytes");
_Static_assert(offsetof(beslam_track_result, S_new_old) == 200, "beslam_track_result.S_new_old");
_Static_assert(sizeof(beslam_motion_checker_v1) == 24, "beslam_motion_checker_v1");
_Static_assert(offsetof(beslam_motion_checker_v1, world_moved) == 16, "ABI 1.7 appends world_moved to 1.6's 16 bytes");
_Static_assert(offsetof(beslam_track_result, keyframe_points) == 168,
               "ABI 1.3 appends keyframe points to 1.2's 168 bytes");
_Static_assert(offsetof(beslam_track_result, keypoints) == 152, "ABI 1.2 appends keypoints to 1.1's 152 bytes");
_Static_assert(sizeof(beslam_keypoint) == 12, "beslam_keypoint");
_Static_assert(offsetof(beslam_track_result, world_scale) == 136, "ABI 1.1 appends world_scale to 1.0's 136 bytes");
_Static_assert(offsetof(beslam_keyframe, world_scale) == 128, "ABI 1.1 appends world_scale to 1.0's 128 bytes");
_Static_assert(sizeof(beslam_backend_v1) == 64, "beslam_backend_v1");
_Static_assert(offsetof(beslam_backend_v1, prepare) == 56, "ABI 1.4 appends prepare to 1.3's 56 bytes");
_Static_assert(sizeof(beslam_object_landmark) == 208, "beslam_object_landmark");
_Static_assert(offsetof(beslam_object_landmark, flags) == 168, "ABI 1.3 appends flags and mesh to 1.2's 168 bytes");
_Static_assert(offsetof(beslam_keyframe, points) == 136, "ABI 1.3 appends points to 1.2's 136 bytes");
_Static_assert(offsetof(beslam_keyframe, keyframe_poses) == 152, "ABI 1.6 appends keyframe poses to 1.5's 152 bytes");
_Static_assert(sizeof(beslam_keyframe) == 168, "beslam_keyframe");
_Static_assert(sizeof(beslam_keyframe_point) == 48, "beslam_keyframe_point");
_Static_assert(offsetof(beslam_reconstructor_v1, finish) == 16, "ABI 1.3 appends finish to 1.2's 16 bytes");

#define ENTRY(x) (size_t)(x)
size_t beslam_c_layout(int i) {
  static const size_t values[] = {
      ENTRY(sizeof(beslam_pose)),
      ENTRY(sizeof(beslam_image_view)),
      ENTRY(sizeof(beslam_point_cloud_view)),
      ENTRY(sizeof(beslam_box3d)),
      ENTRY(offsetof(beslam_box3d, velocity_cam)),
      ENTRY(offsetof(beslam_box3d, occlusion)),
      ENTRY(sizeof(beslam_camera)),
      ENTRY(sizeof(beslam_frame)),
      ENTRY(offsetof(beslam_frame, lidar)),
      ENTRY(sizeof(beslam_create_info)),
      ENTRY(offsetof(beslam_create_info, camera)),
      ENTRY(sizeof(beslam_plugin_descriptor)),
      ENTRY(offsetof(beslam_plugin_descriptor, create)),
      ENTRY(sizeof(beslam_config_field)),
      ENTRY(sizeof(beslam_config_value)),
      ENTRY(sizeof(beslam_host)),
      ENTRY(sizeof(beslam_keyframe)),
      ENTRY(sizeof(beslam_object_landmark)),
      ENTRY(offsetof(beslam_object_landmark, surface_points)),
      ENTRY(sizeof(beslam_track_result)),
      ENTRY(offsetof(beslam_track_result, T_world_cam)),
      ENTRY(sizeof(beslam_detector_v1)),
      ENTRY(sizeof(beslam_motion_checker_v1)),
      ENTRY(sizeof(beslam_mask_generator_v1)),
      ENTRY(sizeof(beslam_reconstructor_v1)),
      ENTRY(sizeof(beslam_backend_v1)),
      ENTRY(sizeof(beslam_map_point)),
      ENTRY(sizeof(beslam_trajectory_entry)),
      ENTRY(sizeof(beslam_mask_buffer)),
      ENTRY(sizeof(beslam_keyframe_point)),
      ENTRY(offsetof(beslam_keyframe, points)),
  };
  return i >= 0 && i < (int)(sizeof(values) / sizeof(values[0])) ? values[i] : (size_t)-1;
}
