/* herd_slide.c - the slide a herd shows, and whether it is worth a warning or planting
 * (crowdbake/herd_slide.h). */
#include "crowdbake/herd_slide.h"

#include <string.h>

void cb_herd_slide_decide(const cb_stride *stride, const cb_row_travel *travel, cb_herd_slide *out)
{
    memset(out, 0, sizeof *out);
    if (!stride->stride) return;
    out->measured = true;
    out->without = out->mean = stride->slide_mean, out->worst = stride->slide_worst;
    /* What remains is what a herd shows: with the per-row travel, the slide it leaves. */
    if (travel && travel->applied) out->with_travel = true, out->mean = travel->slide_with;
    out->warn = out->mean > CB_SLIDE_WARN;
    out->plant = out->mean > CB_PLANT_SLIDE_GOAL;
}
