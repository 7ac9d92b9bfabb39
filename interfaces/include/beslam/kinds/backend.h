/* Backend kind: the SLAM (or odometry) that turns frames into camera poses and a map.
 * Per frame the host calls predict_pose (so the motion checker can place boxes in the world frame),
 * then track with the frame's label mask and boxes. track() says in world_scale whether the world is in
 * metres (then and for every later prediction, until a track() says otherwise: a backend that resets its
 * map starts an unknown world again); while it is not, the host gives the motion checker no pose; after a keyframe the
 * reconstructor's landmarks come back through add_landmarks. finish() ends the run (final optimisation); then the host
 * reads the trajectories and map points. Frames a backend did not track are absent from its trajectories. With the
 * pipeline's motion_replay_frames the host also reads trajectory(FINAL) once between two frames, right after the
 * track() that first says metric; a backend that cannot answer then returns an error and the run goes on.
 * Since ABI 1.4 a backend may do a frame's mask-independent work ahead of its track() (prepare). */
#ifndef BESLAM_KINDS_BACKEND_H
#define BESLAM_KINDS_BACKEND_H

#include "beslam/data.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BESLAM_TRACKING_NOT_INITIALIZED 0
#define BESLAM_TRACKING_OK 1
#define BESLAM_TRACKING_LOST 2

/* One feature of a tracked frame (ABI 1.2), for drawing and diagnostics. */
#define BESLAM_KEYPOINT_MATCHED 0x1u /* matched to a map point and an inlier of the frame's pose */

typedef struct beslam_keypoint {
  float x, y;     /* pixels of the full-resolution image */
  uint16_t label; /* the mask label under it (BESLAM_LABEL_*; 0 without a mask) */
  uint8_t flags;  /* BESLAM_KEYPOINT_* */
  uint8_t octave; /* pyramid level it was detected at */
} beslam_keypoint;

typedef struct beslam_track_result {
  uint32_t struct_size;
  int32_t state;          /* BESLAM_TRACKING_* */
  int32_t is_keyframe;    /* 1: this frame became keyframe keyframe_id */
  int32_t tracked_points; /* map points matched (inliers) in this frame */
  int64_t keyframe_id;
  beslam_pose T_world_cam;              /* valid when state == OK */
  const beslam_stage_time* stage_times; /* instance-owned until its next call; may be NULL */
  uint32_t stage_count;
  uint32_t reserved;
  /* ABI 1.1. */
  int32_t world_scale; /* BESLAM_WORLD_SCALE_* of T_world_cam and of every later prediction */
  uint32_t counter_count;
  /* Per-frame counts the host sums into the run summary; names the host knows: "features",
   * "features_static" (keypoints on static-object labels), "tracked_static" (map points on static objects
   * matched in this frame). Instance-owned until its next call; may be NULL. */
  const beslam_named_value* counters;
  /* ABI 1.2. The frame's features (may be NULL); instance-owned until its next call. keypoint_size is
   * sizeof(beslam_keypoint) as the plugin was built, so the struct can grow at its end. */
  const beslam_keypoint* keypoints;
  uint32_t keypoint_count;
  uint32_t keypoint_size;
  /* ABI 1.3. When is_keyframe: the map points the new keyframe observes (NULL otherwise or from older
   * backends), handed to the reconstructor: at least those it matched; a backend may add points it did
   * not match but knows to lie on an object in its view (label: that object's). Instance-owned until its next call;
   * keyframe_point_size is sizeof(beslam_keyframe_point) as the plugin was built. */
  const beslam_keyframe_point* keyframe_points;
  uint32_t keyframe_point_count;
  uint32_t keyframe_point_size;
  /* ABI 1.7. world_moved = 1: this call moved the backend's world (a loop correction, a change of scale),
   * and T_world_cam and every later pose are in the moved world. A point the world held before the call is
   * now at world_change_scale * R * p + t, [R | t] = S_new_old; the change is exact about the last tracked
   * camera (where the objects a motion checker follows are) and approximate farther away. 0: the world
   * stayed as it was (an ABI 1.6 backend leaves 0). */
  int32_t world_moved;
  uint32_t reserved_1_7;
  double world_change_scale;
  beslam_pose S_new_old;
} beslam_track_result;

#define BESLAM_TRAJECTORY_FINAL 0     /* every tracked frame, relative to its keyframe after optimisation */
#define BESLAM_TRAJECTORY_ONLINE 1    /* the pose each frame got when it was tracked */
#define BESLAM_TRAJECTORY_KEYFRAMES 2 /* keyframes only */

/* beslam_trajectory_entry: data.h (since ABI 1.6 keyframes carry them to the reconstructor). */

typedef struct beslam_trajectory_list {
  const beslam_trajectory_entry* entries;
  uint32_t count;
  uint32_t element_size;
} beslam_trajectory_list;

#define BESLAM_MAP_POINT_STATIC_OBJECT 0x1u /* made on a static (parked) object: trusted */

typedef struct beslam_map_point {
  double p_world[3];
  uint8_t color[3]; /* RGB */
  uint8_t flags;    /* BESLAM_MAP_POINT_* (ABI 1.0 plugins leave 0) */
  int32_t observations;
} beslam_map_point;

typedef struct beslam_map_point_list {
  const beslam_map_point* points;
  uint64_t count;
  uint32_t element_size;
  uint32_t reserved;
} beslam_map_point_list;

typedef struct beslam_backend_v1 {
  uint32_t struct_size;
  uint32_t reserved;
  /* *valid = 0 when the backend has no prediction (not initialised). */
  beslam_status (*predict_pose)(void* instance, const beslam_frame* frame, beslam_pose* T_world_cam, int32_t* valid);
  /* mask: LABEL16 view (data NULL when the pipeline has no mask generator). */
  beslam_status (*track)(void* instance, const beslam_frame* frame, const beslam_image_view* mask,
                         const beslam_box_list* boxes, beslam_track_result* result);
  beslam_status (*add_landmarks)(void* instance, const beslam_landmark_list* landmarks);
  beslam_status (*finish)(void* instance);
  /* which: BESLAM_TRAJECTORY_*; the instance's memory until its next call. */
  beslam_status (*trajectory)(void* instance, int32_t which, beslam_trajectory_list* out);
  beslam_status (*map_points)(void* instance, beslam_map_point_list* out);
  /* ABI 1.4, optional (NULL, or absent from an older table: the host skips it). The frame's work that needs
   * neither its mask nor the map (an image pyramid, corners), done ahead: with prefetching the host calls it
   * on its producer thread, in frame order, up to `prefetch` frames before the frame's track(), while the
   * instance's other calls run on the main thread, so it must be safe against them. The frame's buffers are
   * borrowed for this call only. Whether prepare ran must not change what track() returns. */
  beslam_status (*prepare)(void* instance, const beslam_frame* frame);
} beslam_backend_v1;

#ifdef __cplusplus
}
#endif

#endif
