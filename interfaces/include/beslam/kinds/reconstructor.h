/* Reconstructor kind (the paper's Algorithm 2): on each new keyframe, estimates shape code, pose and
 * scale of the static objects it sees and returns them as world-frame landmarks for the backend. The host
 * calls it only once the backend's world is metric (keyframe->world_scale == BESLAM_WORLD_SCALE_METRIC).
 * A landmark returned again (same track_id) replaces the earlier one; BESLAM_LANDMARK_REMOVED drops it.
 * Since ABI 1.3 the keyframe carries the map points it observes, and finish() ends the run; the host
 * keeps each object's latest landmark and writes objects.json and objects/ meshes from them. Since ABI 1.6
 * it also carries every keyframe's pose as the backend has it now, so what a reconstructor keeps relative
 * to earlier keyframes can follow the map's corrections. */
#ifndef BESLAM_KINDS_RECONSTRUCTOR_H
#define BESLAM_KINDS_RECONSTRUCTOR_H

#include "beslam/data.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct beslam_reconstructor_v1 {
  uint32_t struct_size;
  uint32_t reserved;
  /* keyframe: the backend's new keyframe (this frame); mask: the frame's label mask (data may be NULL).
   * *out: landmarks created or updated by this call, the instance's memory until its next call. */
  beslam_status (*reconstruct)(void* instance, const beslam_keyframe* keyframe, const beslam_frame* frame,
                               const beslam_box_list* boxes, const beslam_image_view* mask, beslam_landmark_list* out);
  /* ABI 1.3 (absent from shorter tables): the run is over. *out: last updates (e.g. a final refinement),
   * applied like reconstruct()'s; the instance's memory until destroy. The host then writes the objects. */
  beslam_status (*finish)(void* instance, beslam_landmark_list* out);
} beslam_reconstructor_v1;

#ifdef __cplusplus
}
#endif

#endif
