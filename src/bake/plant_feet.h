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

/* plant_keys.c: one clip's new leg channels, appended to or replacing the clip's in `anim` (a
 * copy the caller owns; new arrays are malloc'd and listed in *owned for freeing). */
typedef struct plant_owned {
    void **ptr;
    uint32_t count, cap;
} plant_owned;
bool plant_owned_add(plant_owned *o, void *p);
/* When a foot is pulled: held fully from `hold` seconds before each landing to as long after each
 * lift (capped at a quarter of its shortest swing), the pull fading in and out over ramp_share of
 * that swing beyond. */
typedef struct plant_timing {
    double ramp_share, hold;
} plant_timing;
/* How fast the legs' knees bend: the largest change of one knee's angle from one key to the next,
 * degrees, in the clip as it was and as planted. */
typedef struct plant_knees {
    double source, planted;
} plant_knees;
bool plant_clip(cb_sampler *s, const cb_clip_info *clip, const cb_stride *st, plant_timing timing, cb_animation *anim,
                plant_owned *owned, cb_plant_clip *out, plant_knees *knees);

#endif
