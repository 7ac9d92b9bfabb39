/* Mask generator kind (the paper's Algorithm 1): boxes (with motion states) to a per-pixel label mask.
 * The host hands a zero-filled mask of the image's size; the generator writes BESLAM_LABEL_DYNAMIC on
 * dynamic (and, by policy, unknown) objects and BESLAM_LABEL_STATIC_BASE + track_id on static ones. */
#ifndef BESLAM_KINDS_MASK_GENERATOR_H
#define BESLAM_KINDS_MASK_GENERATOR_H

#include "beslam/data.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct beslam_mask_generator_v1 {
  uint32_t struct_size;
  uint32_t reserved;
  beslam_status (*generate)(void* instance, const beslam_frame* frame, const beslam_box_list* boxes,
                            beslam_mask_buffer* mask);
} beslam_mask_generator_v1;

#ifdef __cplusplus
}
#endif

#endif
