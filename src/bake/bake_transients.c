/* bake_transients.c - see bake_transients.h: fast transients (a punch, a death) searched past
 * the default max_fps for the default goal alone (issue 43, item 0). The default max_error is
 * a goal the bake reaches for: where the default cap is what stops it, that clip (and only it)
 * may go on to higher rates; a stated max_error or max_fps keeps its meaning. */
#include "bake_transients.h"

#include <stdlib.h>
#include <string.h>

#include "../core/palette_bake.h" /* palette_choose_rates */

/* Clip i is searched by error for crowdbake's default goal at crowdbake's default cap, and the
 * user stated neither: where it misses the goal there, it is searched on. */
static bool may_reach_on(const cb_bake_job *job, uint32_t i)
{
    const cb_clip_settings *c = &job->clip_settings[i];
    return c->fps_auto && !job->plan[i].step && c->max_error_mm > 0 && c->from.max_error == CB_FROM_DEFAULT &&
           c->from.max_fps == CB_FROM_DEFAULT && c->max_fps < CB_TRANSIENT_MAX_FPS;
}

/* ... and it missed the goal there. */
static bool reaches_on(const cb_bake_job *job, uint32_t i) { return may_reach_on(job, i) && !job->rates[i].met; }

bool *bake_transient_candidates(const cb_bake_job *job)
{
    bool *later = calloc(job->plan_count ? job->plan_count : 1, sizeof *later);
    for (uint32_t i = 0; later && i < job->plan_count; ++i) later[i] = may_reach_on(job, i);
    return later;
}

/* A copy of a plan entry's timed rows' cells (NULL: out of memory). */
static uint32_t *plan_cells_copy(const cb_clip_plan *plan)
{
    uint32_t *cells = malloc((plan->timed_rows ? plan->timed_rows : 1) * sizeof *cells);
    if (cells) memcpy(cells, plan->row_cells, plan->timed_rows * sizeof *cells);
    return cells;
}

/* The second search's answers taken where they meet the goal. A clip still over it keeps its
 * first answer (fewer rows) with the rate the second search found would meet it, from past
 * CB_TRANSIENT_MAX_FPS: the first search left that rate to it (bake_transient_candidates). */
static void take_answers(cb_bake_job *job, const cb_rate_goal *goals, const cb_rate_choice *fresh,
                         cb_clip_plan *before)
{
    for (uint32_t i = 0; i < job->plan_count; ++i) {
        if (!(goals[i].max_error_mm > 0)) continue;
        if (!fresh[i].met) {
            cb_clip_plan_release(&job->plan[i]); /* the second search's timed rows, if any */
            job->plan[i] = before[i];
            before[i].row_cells = NULL;           /* now the plan's */
            job->rates[i].fps_needed = fresh[i].fps_needed;
            continue;
        }
        job->rates[i] = fresh[i];
        job->clip_settings[i].max_fps = CB_TRANSIENT_MAX_FPS;
        job->clip_settings[i].from.max_fps = CB_FROM_TRANSIENT;
    }
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
        for (uint32_t i = 0; i < n; ++i) /* the second search releases the plan's timed rows: its own copy */
            if (before[i].row_cells && !(before[i].row_cells = plan_cells_copy(&job->plan[i])))
                before[i].timed_rows = 0, cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        if (!err->status && !palette_choose_rates(s, o, job->plan, n, goals, fresh, job->search_kept, NULL, err))
            take_answers(job, goals, fresh, before);
        for (uint32_t i = 0; i < n; ++i) cb_clip_plan_release(&before[i]); /* the copies not taken back */
    } else if (!goals || !fresh || !before) {
        cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    free(goals), free(fresh), free(before);
    return err->status;
}
