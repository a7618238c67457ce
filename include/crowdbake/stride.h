/* stride.h - what a clip's feet do: where the model touches the ground, when each foot is
 * planted, whether the planted feet travel backwards together (a stride, which makes a clip
 * locomotion), the ground speed at which they slide least, and how much they still slide.
 *
 * The frame is the one a game draws in: the clip with its average root travel taken off (as
 * an in-place bake stores it) and the instance moved along its heading at a constant speed v.
 * A contact point then moves in the world at u(t) + v d, where u is its velocity in that frame
 * and d the heading; a foot that is really planted has u = -v d. Playing the clip at a rate
 * proportional to the instance's speed scales u and v together, so the slide, as a fraction of
 * the ground speed, is the same at every speed: what foot-sync promises. */
#ifndef CB_STRIDE_H
#define CB_STRIDE_H

#include "export.h"

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { CB_MAX_FEET = 8, CB_MAX_STANCES = 4 };

/* One planted interval of a foot: when it lands and when it lifts, in seconds into the clip (a
 * stance across a loop's end lifts before it lands). The moments its contact point crosses the
 * top of its stance band (interpolated between the analysis's samples). */
typedef struct cb_stance {
    double land, lift;
} cb_stance;

/* One contact point: the skinned vertices at the bottom of the rest pose that one joint moves. */
typedef struct cb_foot {
    uint32_t joint;     /* index into the skin's joints */
    char name[64];      /* that joint's node name */
    double stance;      /* the fraction of the clip it is planted (in the lowest band of its height) */
    double step_speed;  /* its mean speed backwards while planted, model units/s */
    bool strides;       /* planted for a real part of the cycle, moving backwards steadily */
    double slide_mean, slide_worst; /* while planted, at the clip's ground speed: |u + v d| / v */
    uint32_t stance_count;          /* a loop's planted intervals, in time order (one-shots: none) */
    cb_stance stances[CB_MAX_STANCES];
} cb_foot;

typedef struct cb_stride {
    uint32_t foot_count;          /* contact points found in the rest pose */
    cb_foot feet[CB_MAX_FEET];
    bool stride;                  /* the clip loops and at least two feet stride the same way */
    char why[256];                /* why (not), with the numbers */
    double speed;                 /* the ground speed with the least mean slide over the striding feet; 0 without a stride */
    double heading[3];            /* d: the direction of travel in the model's frame (y 0) */
    double slide_mean, slide_worst; /* over every striding foot's stance, at `speed` */
    /* A measurement, not shipped: the mean slide if the body's travel could also vary within the
     * cycle (a per-row offset along the heading, the best one for each row). */
    double slide_mean_varying;
} cb_stride;

/* Analyses clip `clip` (framed by cb_clip_analyze on this sampler, so a loop without a closing
 * key wraps). Without a skinned mesh the feet are the lowest leaf joints. */
CROWDBAKE_API void cb_stride_measure(cb_sampler *sampler, const cb_clip_info *clip, cb_stride *out);

#ifdef __cplusplus
}
#endif

#endif
