/* key_grid.c - see key_grid.h: the coarsest grid that holds every key of a clip. */
#include "key_grid.h"

#include <math.h>

/* Whether t lies on the grid of `step` (within 1e-3 of a step, as a STEP clip's keys are judged). */
static bool on_grid(double t, double step)
{
    double steps = t / step;
    return fabs(steps - round(steps)) < 1e-3;
}

/* Whether every key of the clip lies on t0 + i step, and its end t0 + duration (where a loop's
 * last row blends into its first; duration <= 0: not asked). Channels that share their times are
 * read once. */
static bool keys_on_grid(const cb_animation *a, double t0, double duration, double step)
{
    if (duration > 0 && !on_grid(duration, step)) return false;
    for (uint32_t c = 0; c < a->channel_count; ++c) {
        const cb_channel *ch = &a->channels[c];
        if (c > 0 && ch->times == a->channels[c - 1].times) continue;
        for (uint32_t k = 0; k < ch->key_count; ++k)
            if (!on_grid(ch->times[k] - t0, step)) return false;
    }
    return true;
}

static double grid_rate(double m, double shortest) { return round(m / shortest * 1000) / 1000; }

uint32_t cb_key_grid_divisions(const cb_animation *a, double t0, double duration, double max_fps)
{
    double shortest = cb_animation_key_interval(a);
    for (uint32_t m = 1; shortest > 0; ++m) {
        double rate = grid_rate(m, shortest);
        if (rate > max_fps) break;
        if (keys_on_grid(a, t0, duration, 1 / rate)) return m;
    }
    return 0;
}

double cb_key_grid_fps(const cb_animation *a, double t0, double duration, double max_fps)
{
    uint32_t m = cb_key_grid_divisions(a, t0, duration, max_fps);
    return m ? grid_rate(m, cb_animation_key_interval(a)) : 0;
}
