/* Detector kind: a frame in, 3D boxes in the camera frame out (class, score, centre, size, yaw, and
 * velocity where known). track_id -1 and motion_state UNKNOWN unless the detector knows better. */
#ifndef BESLAM_KINDS_DETECTOR_H
#define BESLAM_KINDS_DETECTOR_H

#include "beslam/data.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct beslam_detector_v1 {
  uint32_t struct_size;
  uint32_t reserved;
  /* Fill *out with this frame's boxes; the memory stays the instance's until its next call. */
  beslam_status (*detect)(void* instance, const beslam_frame* frame, beslam_box_list* out);
} beslam_detector_v1;

#ifdef __cplusplus
}
#endif

#endif
