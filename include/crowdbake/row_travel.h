/* row_travel.h - the per-row travel offset (.pal version 5): for a loop baked in place whose
 * feet stride, the body's offset along the heading at each row, the integral of the per-row body
 * speed that keeps the planted feet still. A runtime that moves an instance at the clip's ground
 * speed v adds offset(t) x heading (rotated and scaled as the instance is) to its position, so
 * the body surges and lags within the cycle as the planted feet say, and the feet stay where
 * they land. The offset averages 0 over the cycle and returns to its start at the wrap, so the
 * instance still travels at v.
 *
 * It helps where the planted feet step back together at one speed that varies within the
 * cycle (a gallop: the body is fastest after the hind feet push off); it cannot help where feet
 * planted at the same moment step back at different speeds (a walk whose front and hind feet
 * disagree): no one body speed plants both, and the bake leaves such a clip without it, saying
 * why. Nor does a loop whose name says an action done once (attack, hit...: the loop decision's
 * words) get it: runtimes move an instance only in states that follow the speed. The decision is the bake's, per clip (cb_row_travel.why), and `--row-travel off`
 * overrides it. */
#ifndef CB_ROW_TRAVEL_H
#define CB_ROW_TRAVEL_H

#include "export.h"

#include "core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Shipped where it cuts the planted feet's mean slide (at the ground speed) by at least a third. */
#define CB_ROW_TRAVEL_MIN_CUT (1.0 / 3.0)

/* One clip's per-row travel, as the bake decided it. */
typedef struct cb_row_travel {
    bool applied;          /* the palette carries the clip's offsets (else its rows read as 0) */
    float heading[3];      /* the direction of travel in the model's frame (y 0): the offsets are along it */
    double slide_mean;     /* the planted feet's mean slide at the ground speed, a fraction of it (as cb_stride) */
    double slide_with;     /* the same with the offsets, blended between rows as a runtime blends them */
    char why[256];         /* applied or not, with the numbers */
} cb_row_travel;

/* Measures clip `clip` (cb_clip_analyze on this sampler) baked in `rows` rows (a loop: row i at
 * i / rows of the cycle) and decides whether its offsets help. in_place: its root travel was
 * taken off (a clip that keeps it carries its own travel). offsets: `rows` floats, model units,
 * written when applied (else zeros). */
CROWDBAKE_API void cb_row_travel_measure(cb_sampler *sampler, const cb_clip_info *clip, bool in_place, uint32_t rows,
                                         float *offsets, cb_row_travel *out);

#ifdef __cplusplus
}
#endif

#endif
