/* plant_feet.h - feet locked at bake time (opt-in: cb_bake_settings.plant_feet, `--plant-feet`,
 * a catalog's `plant_feet = true`).
 *
 * A locomotion loop whose planted feet step back at speeds no single body speed reconciles
 * (Husky's Walk: its front paws at ~1.0 units/s, its hind ones at ~2.5) slides at any playback
 * rate. Planting turns each leg's two bones above the foot (two-bone IK, analytic: the bones
 * keep their lengths, the knee bends in its own plane) so that while a foot is planted its sole
 * stays where it landed in a world the body crosses at the clip's ground speed; the change
 * fades in before the landing and out after the lift (a tenth, a quarter or two fifths of the
 * swing each, whichever leaves the least slide), so nothing pops; where the knees then bend no
 * faster than without it, the foot is also held a 30 fps row interval before it lands and after it
 * lifts, so the row that holds the landing does not blend swing into stance. Only the leg chains (hip and
 * knee bones, the foot bone's rotation that keeps the foot's world orientation, and rig bones
 * that carry the sole, e.g. an IK control the paw is weighted to) change; every other joint
 * keeps its keys. The bake samples a copy of the model with the new keys; the caller's model is
 * not touched. */
#ifndef CB_PLANT_FEET_H
#define CB_PLANT_FEET_H

#include "export.h"

#include "core.h"
#include "herd_slide.h" /* CB_PLANT_SLIDE_GOAL: which clips are planted */

#ifdef __cplusplus
extern "C" {
#endif

/* What planting did to one clip. Slides are fractions of the ground speed (stride.h). */
typedef struct cb_plant_clip {
    int32_t animation;
    bool planted;              /* its legs were turned */
    char why[200];             /* what was done, or why not, with the numbers */
    double speed;              /* the ground speed its feet were planted at (the stride's), units/s */
    uint32_t feet;             /* feet planted */
    double slide_before, slide_worst_before; /* mean and worst, over the striding feet's stances */
    double slide_after, slide_worst_after;   /* the same, measured again on the planted clip */
    double max_rotation_deg;   /* the largest change of one joint's local rotation at one key */
    double max_shortfall;      /* the farthest an ankle stopped short of its planted place (a leg out of reach),
                                * model units; 0 when every target was reached */
} cb_plant_clip;

typedef struct cb_plant_report {
    uint32_t clip_count;       /* the job's planned clips, in plan order */
    cb_plant_clip *clips;
} cb_plant_report;

struct cb_bake_job;
/* The planting a job did (cb_bake_job_plan does it when settings.plant_feet), or NULL. */
CROWDBAKE_API const cb_plant_report *cb_bake_job_plant_report(const struct cb_bake_job *job);

#ifdef __cplusplus
}
#endif

#endif
