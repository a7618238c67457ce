/* step_rows.c - STEP-keyed clips: the rate whose rows fall on every key time. A STEP channel
 * holds each key's value until the next key, so rows blended as a LINEAR clip's are wrong
 * between any two rows across a step at every rate (the shared STEP SimpleSkin: 218 mm/m at
 * 120 fps). Rows at the key times, held rather than blended (clip flag bit 2), are exact. */
#include "crowdbake/palette.h"

#include <math.h>

/* Key times are float32: a key within this fraction of a step of the grid lies on it. */
#define STEP_GRID_TOLERANCE 1e-3
/* Grids finer than the smallest key gap tried, for keys at uneven multiples of a step (a
 * gap of 2 steps beside one of 3: the step is the smallest gap / 2). */
#define STEP_GRID_DIVISIONS 12

/* True when every key time of the animation, less t0, is a whole number of `step`s. */
static bool keys_on_grid(const cb_animation *a, double step)
{
    for (uint32_t c = 0; c < a->channel_count; ++c) {
        const cb_channel *ch = &a->channels[c];
        for (uint32_t k = 0; ch->key_count > 1 && k < ch->key_count; ++k) {
            double at = ((double)ch->times[k] - a->t0) / step;
            if (fabs(at - floor(at + 0.5)) > STEP_GRID_TOLERANCE) return false;
        }
    }
    return true;
}

/* Whether every channel that moves (two keys or more) is STEP, and there is one. */
static bool only_step_channels(const cb_animation *a)
{
    bool any = false;
    for (uint32_t c = 0; c < a->channel_count; ++c) {
        const cb_channel *ch = &a->channels[c];
        if (ch->key_count < 2) continue; /* a constant: any interpolation holds it */
        if (ch->interp != CB_INTERP_STEP) return false;
        any = true;
    }
    return any;
}

bool cb_clip_step_grid(const cb_model *model, int32_t animation, double *fps)
{
    if (animation < 0 || (uint32_t)animation >= model->animation_count) return false;
    const cb_animation *a = &model->animations[animation];
    if (!only_step_channels(a)) return false;
    double gap = cb_animation_key_interval(a);
    if (!(gap > 0)) return false;
    for (int n = 1; n <= STEP_GRID_DIVISIONS; ++n) {
        double step = gap / n;
        if (1 / step > CB_FPS_LIMIT) return false;
        if (keys_on_grid(a, step)) return *fps = 1 / step, true;
    }
    return false;
}
