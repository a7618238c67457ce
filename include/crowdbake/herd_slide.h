/* herd_slide.h - the slide a herd shows: one clip's planted-foot slide as a game drawing a herd
 * sees it (after the clip's per-row travel, where the bake ships it), and what it calls for.
 * The one place the thresholds live and the one rule that reads them: the roster's warning, the
 * report's foot-sync table, `info` and feet planted at bake time (plant_feet.h) all ask here. */
#ifndef CB_HERD_SLIDE_H
#define CB_HERD_SLIDE_H

#include "export.h"

#include "core.h"
#include "row_travel.h"
#include "stride.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A mean slide above a quarter of the ground speed reads as skating from a game's camera: the
 * roster warns about such a locomotion clip, whose feet no playback rate can plant. */
#define CB_SLIDE_WARN 0.25
/* A clip's mean slide above this fraction of its ground speed is planted at bake time (when asked
 * for); below, left as is. */
#define CB_PLANT_SLIDE_GOAL 0.10

typedef struct cb_herd_slide {
    bool measured;    /* the clip strides: its planted feet give a slide (else the rest reads 0 and false) */
    bool with_travel; /* `mean` is with the clip's per-row travel (shipped: cb_row_travel.applied) */
    double mean;      /* the mean slide a herd shows, a fraction of the ground speed */
    double without;   /* the stride's own mean, without per-row travel */
    double worst;     /* the worst moment, measured without per-row travel */
    bool warn;        /* mean > CB_SLIDE_WARN: the asset's feet slide at any rate */
    bool plant;       /* mean > CB_PLANT_SLIDE_GOAL: worth planting at bake time */
} cb_herd_slide;

/* The slide of a clip whose feet are `stride` (cb_stride_measure) and whose per-row travel is
 * `travel` (NULL: none decided yet, as when feet are planted: the bake measures the travel of the
 * planted clip, after). */
CROWDBAKE_API void cb_herd_slide_decide(const cb_stride *stride, const cb_row_travel *travel, cb_herd_slide *out);

#ifdef __cplusplus
}
#endif

#endif
