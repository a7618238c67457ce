/* bake_transients.c - see bake_transients.h: fast transients (a punch, a death) searched past
 * the default max_fps for the default goal alone (issue 43, item 0). The default max_error is
 * a goal the bake reaches for: where the default cap is what stops it, that clip (and only it)
 * may go on to higher rates; a stated max_error or max_fps keeps its meaning. */
#include "bake_transients.h"

#include <stdlib.h>
#include <string.h>

#include "../core/palette_bake.h" /* palette_choose_rates */

/* Clip i was searched by error, missed crowdbake's default goal at crowdbake's default cap, and
 * the user stated neither. */
static bool reaches_on(const cb_bake_job *job, uint32_t i)
{
    const cb_clip_settings *c = &job->clip_settings[i];
    return c->fps_auto && !job->plan[i].step && c->max_error_mm > 0 && !job->rates[i].met &&
           c->from.max_error == CB_FROM_DEFAULT && c->from.max_fps == CB_FROM_DEFAULT && c->max_fps < CB_TRANSIENT_MAX_FPS;
}

cb_status bake_reach_for_transients(cb_bake_job *job, cb_sampler *s, const cb_bake_options *o, cb_error *err)
{
    uint32_t n = job->plan_count;
    cb_rate_goal *goals = calloc(n ? n : 1, sizeof *goals);
    cb_rate_choice *fresh = calloc(n ? n : 1, sizeof *fresh);
    cb_clip_plan *before = malloc((n ? n : 1) * sizeof *before);
    bool any = false;
    for (uint32_t i = 0; goals && fresh && before && i < n; ++i)
        if (reaches_on(job, i))
            goals[i] = (cb_rate_goal){job->clip_settings[i].max_error_mm, CB_TRANSIENT_MAX_FPS, CB_ROWS_BEST}, any = true;
    if (any) {
        memcpy(before, job->plan, n * sizeof *before);
        palette_choose_rates(s, o, job->plan, n, goals, fresh, job->search_poses, err);
        for (uint32_t i = 0; i < n; ++i) {
            if (!(goals[i].max_error_mm > 0)) continue;
            if (err->status || !fresh[i].met) { /* still over the goal: its first answer, fewer rows */
                job->plan[i] = before[i];
                continue;
            }
            job->rates[i] = fresh[i];
            job->clip_settings[i].max_fps = CB_TRANSIENT_MAX_FPS;
            job->clip_settings[i].from.max_fps = CB_FROM_TRANSIENT;
        }
    } else if (!goals || !fresh || !before) {
        cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    free(goals), free(fresh), free(before);
    return err->status;
}
