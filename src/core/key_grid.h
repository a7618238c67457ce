/* key_grid.h - a clip's key rate: the coarsest time grid that holds every key of the clip, what
 * both rate searches (rate_search.c for global rows, local_rate.c for local rows) start from and
 * the bake's reasons name. Internal. */
#ifndef CB_KEY_GRID_H
#define CB_KEY_GRID_H

#include "crowdbake/core.h"

#include <stdint.h>

/* The grid t0 + i step, step = (shortest key gap) / m, for the smallest m = 1, 2, 3, ... whose
 * rate (rounded to 1e-3 fps, as the rate searches round rates) is within max_fps and on which
 * every key lies, and the clip's end t0 + duration too (duration <= 0: not asked); 0 when none
 * is. Rows off that grid cut LINEAR keys' corners, an error that falls only as 1 / fps: Fox's
 * Run keys every 1/24 s, but after a gap of 0.2 s on times 1/30 s off that grid, so its rows land
 * on every key only at 120 fps (m = 5). */
uint32_t cb_key_grid_divisions(const cb_animation *a, double t0, double duration, double max_fps);
/* The rate of that grid, round(m / shortest gap, 1e-3 fps); 0 when there is none. */
double cb_key_grid_fps(const cb_animation *a, double t0, double duration, double max_fps);

#endif
