/* plant_feet.h (internal) - the bake job's side of feet locked at bake time
 * (crowdbake/plant_feet.h): the job's model swapped for a copy whose planted clips have their
 * leg chains turned, and back. */
#ifndef CB_BAKE_PLANT_FEET_H
#define CB_BAKE_PLANT_FEET_H

#include "crowdbake/bake.h"
#include "crowdbake/plant_feet.h"
#include "crowdbake/stride.h"

/* Plants the feet of the job's planned clips: job->model becomes a copy with the planted clips'
 * leg channels rewritten (the caller's model is not touched), and the report is kept. */
cb_status plant_feet_apply(cb_bake_job *job, cb_error *err);
/* Gives the job its own model back and frees the copy and the report. */
void plant_feet_release(cb_bake_job *job);

/* plant_keys.c: one clip's new leg channels (the fade before a landing and after a lift
 * ramp_share of the foot's shortest swing each), appended to or replacing the clip's in `anim` (a
 * copy the caller owns; new arrays are malloc'd and listed in *owned for freeing). */
typedef struct plant_owned {
    void **ptr;
    uint32_t count, cap;
} plant_owned;
bool plant_owned_add(plant_owned *o, void *p);
bool plant_clip(cb_sampler *s, const cb_clip_info *clip, const cb_stride *st, double ramp_share, cb_animation *anim,
                plant_owned *owned, cb_plant_clip *out);

#endif
