/* Motion checker kind: decides, per box, whether the object is static (parked) or dynamic, by keeping
 * tracks of objects in the world frame over time. It writes track_id and motion_state in place and must
 * not reorder, add or remove boxes. */
#ifndef BESLAM_KINDS_MOTION_CHECKER_H
#define BESLAM_KINDS_MOTION_CHECKER_H

#include "beslam/data.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct beslam_motion_checker_v1 {
  uint32_t struct_size;
  uint32_t reserved;
  /* T_world_cam: the backend's prediction for this frame, in metres; NULL when it has none or when the
   * backend's world is not metric yet (a monocular map before its scale is known): a checker then
   * answers BESLAM_MOTION_UNKNOWN, or decides only by a test that needs no scale. */
  beslam_status (*classify)(void* instance, const beslam_frame* frame, const beslam_pose* T_world_cam,
                            beslam_box_array* boxes);
  /* ABI 1.7, optional (NULL, or absent from an older table: the host skips it). The backend moved its
   * world (beslam_track_result.world_moved) while the world was metric: a point the checker placed in the
   * world is now at scale * R * p + t, [R | t] = S_new_old, and the next classify's pose is in the moved
   * world. Called after the track() that moved it, before the next classify. */
  beslam_status (*world_moved)(void* instance, const beslam_pose* S_new_old, double scale);
} beslam_motion_checker_v1;

#ifdef __cplusplus
}
#endif

#endif
