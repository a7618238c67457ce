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

/* The clips that missed the goal even past the default cap keep their first answer, which the
 * first search left without the rate that would meet it (`deferred`): searched again as the
 * first search searched them, this time to that rate (the same choice, the search being
 * deterministic, and its fps_needed). Only a clip out of reach pays for it. */
static void first_answers_again(cb_bake_job *job, cb_sampler *s, const cb_bake_options *o, const bool *again,
                                cb_error *err)
{
    uint32_t n = job->plan_count;
    cb_rate_goal *goals = calloc(n ? n : 1, sizeof *goals);
    cb_rate_choice *first = calloc(n ? n : 1, sizeof *first);
    if (!goals || !first) {
        cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    } else {
        for (uint32_t i = 0; i < n; ++i)
            if (again[i]) goals[i] = (cb_rate_goal){job->clip_settings[i].max_error_mm, job->clip_settings[i].max_fps, CB_ROWS_BEST};
        palette_choose_rates(s, o, job->plan, n, goals, first, job->search_poses, NULL, err);
        for (uint32_t i = 0; i < n && !err->status; ++i)
            if (again[i]) job->rates[i] = first[i];
    }
    free(goals), free(first);
}

/* The second search's answers taken where they meet the goal; true into again[i] where clip i
 * keeps its first answer and `deferred` left that answer's fps_needed out. */
static bool take_answers(cb_bake_job *job, const cb_rate_goal *goals, const cb_rate_choice *fresh,
                         const cb_clip_plan *before, const bool *deferred, bool *again, const cb_error *err)
{
    bool any = false;
    for (uint32_t i = 0; i < job->plan_count; ++i) {
        if (!(goals[i].max_error_mm > 0)) continue;
        if (err->status || !fresh[i].met) { /* still over the goal: its first answer, fewer rows */
            job->plan[i] = before[i];
            any |= again[i] = deferred && deferred[i];
            continue;
        }
        job->rates[i] = fresh[i];
        job->clip_settings[i].max_fps = CB_TRANSIENT_MAX_FPS;
        job->clip_settings[i].from.max_fps = CB_FROM_TRANSIENT;
    }
    return any;
}

cb_status bake_reach_for_transients(cb_bake_job *job, cb_sampler *s, const cb_bake_options *o, const bool *deferred,
                                    cb_error *err)
{
    uint32_t n = job->plan_count;
    cb_rate_goal *goals = calloc(n ? n : 1, sizeof *goals);
    cb_rate_choice *fresh = calloc(n ? n : 1, sizeof *fresh);
    cb_clip_plan *before = malloc((n ? n : 1) * sizeof *before);
    bool *again = calloc(n ? n : 1, sizeof *again);
    bool any = false;
    for (uint32_t i = 0; goals && fresh && before && again && i < n; ++i)
        if (reaches_on(job, i))
            goals[i] = (cb_rate_goal){job->clip_settings[i].max_error_mm, CB_TRANSIENT_MAX_FPS, CB_ROWS_BEST}, any = true;
    if (any) {
        memcpy(before, job->plan, n * sizeof *before);
        palette_choose_rates(s, o, job->plan, n, goals, fresh, job->search_poses, NULL, err);
        if (take_answers(job, goals, fresh, before, deferred, again, err) && !err->status)
            first_answers_again(job, s, o, again, err);
    } else if (!goals || !fresh || !before || !again) {
        cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    free(goals), free(fresh), free(before), free(again);
    return err->status;
}
