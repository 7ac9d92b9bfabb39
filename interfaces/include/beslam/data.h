/* BE-SLAM plugin ABI: the data that crosses it — images, LiDAR scans, cameras, poses, 3D boxes, label
 * masks, frames, keyframes and object landmarks. All views borrow memory they do not own.
 *
 * Frames and units: metres, seconds, radians. Camera frame x right, y down, z forward (KITTI).
 * beslam_pose m[] holds the top 3x4 of a 4x4 rigid transform, row-major; a field named T_a_b maps
 * points from frame b to frame a (p_a = T_a_b * p_b). "world" is the backend's map frame.
 *
 * The world unit. A monocular backend's map has no metric scale until it recovers one (camera height
 * over the road, metric boxes, LiDAR): until then its world is "metres times an unknown factor". Since
 * ABI 1.1 a backend says which it is (beslam_track_result.world_scale, BESLAM_WORLD_SCALE_*); the host
 * hands world-frame poses to the motion checker and the reconstructor only once the world is metric.
 * A backend built against ABI 1.0 never says so and counts as BESLAM_WORLD_SCALE_UNKNOWN.
 *
 * Two object frames, on purpose:
 *  - a 3D box (beslam_box3d) is a detection in the CAMERA frame: geometric centre, size = length
 *    (along the heading), width, height, and yaw about the camera y axis (KITTI rotation_y: 0 = heading
 *    along camera +x). It is what detectors and datasets give.
 *  - an object landmark (beslam_object_landmark) lives in the WORLD frame with a right-handed body frame
 *    x forward (heading), y left, z up, origin at the box's geometric centre, so shape models and meshes
 *    are written in the usual vehicle convention. For a level camera (world y down):
 *    T_cam_object = [R_y(yaw) * M | centre_cam] with M mapping body (x fwd, y left, z up) to camera-style
 *    axes (x right, y down, z forward) at yaw 0: body x -> cam +x, body y -> cam +z, body z -> cam -y.
 *    The SDK's sdk::objectPose(box) (views.hpp) gives T_cam_object of a box.
 */
#ifndef BESLAM_DATA_H
#define BESLAM_DATA_H

#include "beslam/abi.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Images ---- */
#define BESLAM_PIXEL_GRAY8 1   /* 1 x uint8 */
#define BESLAM_PIXEL_BGR8 2    /* 3 x uint8, OpenCV order */
#define BESLAM_PIXEL_RGB8 3    /* 3 x uint8 */
#define BESLAM_PIXEL_LABEL16 4 /* 1 x uint16, a label mask (see BESLAM_LABEL_*) */

typedef struct beslam_image_view {
  const uint8_t* data; /* NULL: no image */
  int32_t width;
  int32_t height;
  int32_t stride_bytes; /* bytes from one row to the next, >= width * pixel size */
  int32_t format;       /* BESLAM_PIXEL_* */
} beslam_image_view;

/* A label mask the host owns and a mask generator fills (BESLAM_PIXEL_LABEL16). */
typedef struct beslam_mask_buffer {
  uint16_t* data;
  int32_t width;
  int32_t height;
  int32_t stride_bytes;
  int32_t reserved;
} beslam_mask_buffer;

/* Label values: 0 background, 1 dynamic object, BESLAM_LABEL_STATIC_BASE + track id a static object. */
#define BESLAM_LABEL_BACKGROUND 0
#define BESLAM_LABEL_DYNAMIC 1
#define BESLAM_LABEL_STATIC_BASE 1000

/* ---- LiDAR ---- */
typedef struct beslam_point_cloud_view {
  const float* data; /* x y z intensity, in the LiDAR frame; NULL: no scan */
  uint64_t count;
  uint32_t stride_bytes; /* bytes from one point to the next, >= 16 */
  uint32_t reserved;
} beslam_point_cloud_view;

/* ---- Geometry ---- */
typedef struct beslam_pose {
  double m[12]; /* [R | t] row-major */
} beslam_pose;

typedef struct beslam_camera {
  uint32_t struct_size;
  int32_t width;
  int32_t height;
  int32_t reserved;
  double fx, fy, cx, cy; /* rectified pinhole: images arrive undistorted */
} beslam_camera;

/* ---- 3D boxes ---- */
#define BESLAM_CLASS_UNKNOWN 0
#define BESLAM_CLASS_CAR 1
#define BESLAM_CLASS_PEDESTRIAN 2
#define BESLAM_CLASS_CYCLIST 3
#define BESLAM_CLASS_TRUCK 4
#define BESLAM_CLASS_VAN 5

#define BESLAM_MOTION_UNKNOWN 0
#define BESLAM_MOTION_STATIC 1
#define BESLAM_MOTION_DYNAMIC 2

#define BESLAM_BOX_HAS_VELOCITY 0x1u       /* velocity_cam is set */
#define BESLAM_BOX_HAS_BBOX2D 0x2u         /* bbox2d is set */
#define BESLAM_BOX_UNCERTAIN 0x4u          /* the detector doubts this box (too far, too small) */
#define BESLAM_BOX_HAS_POSITION_SIGMA 0x8u /* position_sigma is set (ABI 1.5) */

/* The unit of a backend's world frame (ABI 1.1). */
#define BESLAM_WORLD_SCALE_UNKNOWN 0 /* monocular map: metres times an unknown (drifting) factor */
#define BESLAM_WORLD_SCALE_METRIC 1  /* metres */

/* Arrays of boxes carry their element size: index with (const char*)boxes + i * element_size. */
typedef struct beslam_box3d {
  int32_t class_id;       /* BESLAM_CLASS_* */
  int32_t track_id;       /* -1 until a tracker assigns one */
  int32_t motion_state;   /* BESLAM_MOTION_* */
  uint32_t flags;         /* BESLAM_BOX_* */
  double center_cam[3];   /* geometric centre of the box in the camera frame (not KITTI's bottom centre) */
  double size[3];         /* length (along heading), width, height */
  double yaw;             /* rotation about the camera y axis, KITTI's rotation_y convention */
  double velocity_cam[3]; /* m/s in the camera frame, if BESLAM_BOX_HAS_VELOCITY */
  double bbox2d[4];       /* x1 y1 x2 y2 in pixels, if BESLAM_BOX_HAS_BBOX2D */
  float score;            /* detector confidence, 0..1 */
  float truncation;       /* 0..1, KITTI */
  int32_t occlusion;      /* 0..3, KITTI */
  int32_t reserved;
  /* ABI 1.5, if BESLAM_BOX_HAS_POSITION_SIGMA: how well the detector knows center_cam in the bird's-eye
   * view. position_sigma: standard deviation (m) of one frame's error, [0] along the line of sight from the
   * camera (range), [1] across it. range_drift: the part of the range error that is not new each frame but
   * changes with the range itself, as the standard deviation of d(error)/d(range) (m per m); while the
   * camera closes in, a parked car then seems to move along the line of sight at range_drift times the
   * closing speed. A box lifted onto a flat road from a monocular image: range error (range^2 / camera
   * height) * (road pitch error), so range_drift = 2 * range * pitch error / camera height. */
  double position_sigma[2];
  double range_drift;
} beslam_box3d;

/* A host-owned array a plugin may modify in place (motion checker) or fill (detector output copy). */
typedef struct beslam_box_array {
  beslam_box3d* boxes;
  uint32_t count;
  uint32_t element_size;
} beslam_box_array;

/* Boxes a detector returns: plugin-owned until its next call or destroy. */
typedef struct beslam_box_list {
  const beslam_box3d* boxes;
  uint32_t count;
  uint32_t element_size;
} beslam_box_list;

/* ---- A frame of the input stream ---- */
typedef struct beslam_frame {
  uint32_t struct_size;
  uint32_t reserved;
  int64_t index;                 /* position in the sequence, 0-based */
  double timestamp;              /* seconds */
  beslam_image_view gray;        /* GRAY8; data NULL only for an image-less dataset (detections + poses) */
  beslam_image_view color;       /* BGR8, data NULL when the dataset has none */
  beslam_point_cloud_view lidar; /* data NULL when no scan */
  const char* image_path;        /* where the image came from (for messages); may be NULL */
} beslam_frame;

/* ---- Creating an instance ---- */
typedef struct beslam_create_info {
  uint32_t struct_size;
  uint32_t has_lidar_extrinsics; /* 1 when T_cam_lidar is valid */
  const beslam_host* host;
  const beslam_config_value* config; /* every schema key, defaults filled, validated */
  uint32_t config_count;
  uint32_t reserved;
  beslam_camera camera;
  beslam_pose T_cam_lidar; /* LiDAR frame -> camera frame */
  const char* output_dir;  /* the run's output folder (a plugin may write its own files there) */
  /* ABI 1.1: the rig. A property of the dataset (KITTI: 1.65 m; synthetic: its manifest), which a
   * pipeline may override with dataset.camera_height; handed to every plugin. */
  double camera_height; /* metres from the camera centre down to the road; 0: unknown */
} beslam_create_info;

/* ---- What the backend and reconstructor exchange ---- */

/* ABI 1.3: a map point a new keyframe observes, as the backend hands it on for the reconstructor: its
 * stable id, world position, the pixel it was matched at in the keyframe and the mask label there. */
typedef struct beslam_keyframe_point {
  int64_t id; /* the backend's map point id, stable for the point's life */
  double p_world[3];
  float x, y;     /* pixel in the keyframe (full resolution) */
  uint16_t label; /* mask label under the pixel (BESLAM_LABEL_*; 0 without a mask) */
  uint16_t reserved;
  int32_t observations; /* keyframes that observe the point */
} beslam_keyframe_point;

/* One pose of a trajectory: a backend's trajectories, and the keyframe poses a reconstructor is given. */
typedef struct beslam_trajectory_entry {
  int64_t frame_index;
  double timestamp;
  beslam_pose T_world_cam;
} beslam_trajectory_entry;

typedef struct beslam_keyframe {
  uint32_t struct_size;
  uint32_t reserved;
  int64_t id;
  int64_t frame_index;
  double timestamp;
  beslam_pose T_world_cam;
  int32_t world_scale; /* ABI 1.1: BESLAM_WORLD_SCALE_* of T_world_cam */
  int32_t reserved1;
  /* ABI 1.3: the map points this keyframe observes (NULL from older backends); host memory for the call.
   * point_size is sizeof(beslam_keyframe_point) as the host was built. */
  const beslam_keyframe_point* points;
  uint32_t point_count;
  uint32_t point_size;
  /* ABI 1.6: every keyframe of the backend as it is now (after local and global optimisation, loop
   * corrections and rescaling), this one included, by frame index (NULL from an older host). Whatever the
   * reconstructor keeps relative to a keyframe it places with these, so its objects follow the map. A 1.6
   * host gives T_world_cam above as the same keyframe's pose among these.
   * keyframe_pose_size is sizeof(beslam_trajectory_entry) as the host was built. */
  const beslam_trajectory_entry* keyframe_poses;
  uint32_t keyframe_pose_count;
  uint32_t keyframe_pose_size;
} beslam_keyframe;

typedef struct beslam_keyframe_list {
  const beslam_keyframe* keyframes;
  uint32_t count;
  uint32_t element_size;
} beslam_keyframe_list;

/* Landmark flags (ABI 1.3). */
#define BESLAM_LANDMARK_REMOVED 0x1u /* the object is no landmark any more (it started to move): drop it */

/* A reconstructed static object (parked car) used as a landmark by the backend. */
typedef struct beslam_object_landmark {
  uint32_t struct_size;
  int32_t track_id;
  int32_t class_id;
  float confidence;
  beslam_pose T_world_object; /* object frame: x forward (heading), y left, z up, origin at the centre */
  double scale[3];            /* length, width, height */
  const float* shape_code;    /* latent shape vector, may be NULL */
  uint32_t shape_code_size;
  uint32_t reserved;
  const float* surface_points; /* x y z in the object frame, 3 floats each; may be NULL */
  uint64_t surface_point_count;
  /* ABI 1.3 (an ABI 1.2 plugin's struct_size ends above; the host reads zeros). */
  uint32_t flags;             /* BESLAM_LANDMARK_* */
  int32_t keyframes;          /* keyframes whose observations the estimate uses */
  double cost;                /* final cost of the fit (the reconstructor's energy; lower is better) */
  const float* mesh_vertices; /* x y z in the object frame, metres, 3 floats each; may be NULL */
  uint32_t mesh_vertex_count;
  uint32_t mesh_face_count;
  const uint32_t* mesh_faces; /* vertex index triples, counter-clockwise seen from outside; may be NULL */
} beslam_object_landmark;

typedef struct beslam_landmark_list {
  const beslam_object_landmark* landmarks;
  uint32_t count;
  uint32_t element_size;
} beslam_landmark_list;

/* Named wall times a plugin reports for one call (plugin-owned until its next call). */
typedef struct beslam_stage_time {
  const char* name;
  double milliseconds;
} beslam_stage_time;

/* A named number a plugin reports for one call, e.g. "features_static" (plugin-owned until its next call). */
typedef struct beslam_named_value {
  const char* name;
  double value;
} beslam_named_value;

#ifdef __cplusplus
}
#endif

#endif /* BESLAM_DATA_H */
