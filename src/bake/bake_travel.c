/* bake_travel.c - the bake job's per-row travel offsets (bake_travel.h). */
#include "bake_travel.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/plumbing.h"
#include "../core/clip_memo.h"
#include "../core/foot_cache.h"

/* Whether a clip carries its own travel in its rows: root motion kept on a clip whose root
 * travels. A clip animated in place (its root still) is in place whatever the mode says. */
static bool carries_travel(const cb_bake_job *job, const cb_clip_info *info, double model_height)
{
    return !cb_root_motion_in_place(job->settings.root_motion, info) && cb_clip_travels(info, model_height);
}

/* cb_bake_job_row_travel with the bake's foot analyses (feet: NULL measures them here). */
static void job_row_travel(const cb_bake_job *job, foot_cache *feet, cb_sampler *s, const cb_clip_info *info,
                           float *offsets, cb_row_travel *out)
{
    if (job->settings.row_travel_off) {
        memset(out, 0, sizeof *out);
        memset(offsets, 0, (size_t)info->frames * sizeof *offsets);
        snprintf(out->why, sizeof out->why, "not applied: turned off (--row-travel off, or the catalog's row_travel = false)");
        return;
    }
    double model_height = foot_cache_rest_height(feet, s);
    row_travel_measure_cached(feet, s, info, !carries_travel(job, info, model_height), info->frames, offsets, out);
}

void cb_bake_job_row_travel(const cb_bake_job *job, cb_sampler *s, const cb_clip_info *info, float *offsets,
                            cb_row_travel *out)
{
    job_row_travel(job, NULL, s, info, offsets, out);
}

bool bake_clip_travel(const cb_bake_job *job, uint32_t c, struct foot_cache *feet, struct clip_memo *memo, cb_sampler *s,
                      measured_travel *out)
{
    cb_clip_info info;
    cb_error ignored = {0};
    *out = (measured_travel){.fps = cb_bake_job_clip_fps(job, c)};
    if (clip_memo_analyze(memo, s, job->plan[c].animation, out->fps, job->plan[c].loop, &job->limits, &info, &ignored)) {
        snprintf(out->travel.why, sizeof out->travel.why, "not applied: %.200s", ignored.message);
        return true;
    }
    out->offsets = calloc(info.frames ? info.frames : 1, sizeof *out->offsets);
    if (!out->offsets) return false;
    out->cells = info.frames, out->made = true;
    job_row_travel(job, feet, s, &info, out->offsets, &out->travel);
    return true;
}

cb_status bake_row_travel(const cb_bake_job *job, struct foot_cache *feet, struct clip_memo *memo, cb_sampler *s,
                          const measured_travel *ahead, cb_palette *p, cb_error *err)
{
    float *offsets = calloc(p->rows ? p->rows : 1, sizeof *offsets);
    if (!offsets) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    bool any = false;
    for (uint32_t c = 0; c < p->clip_count && c < job->plan_count; ++c) {
        cb_palette_clip *clip = &p->clips[c];
        const cb_clip_plan *plan = &job->plan[c];
        measured_travel own = {0};
        const measured_travel *m = ahead && ahead[c].made && ahead[c].fps == cb_bake_job_clip_fps(job, c) ? &ahead[c] : &own;
        if (m == &own && !bake_clip_travel(job, c, feet, memo, s, &own))
            return free(offsets), cb_fail(err, CB_ERR_INTERNAL, "out of memory");
        clip->travel = m->travel;
        bool timed = clip->timed && plan->timed_rows == clip->frames; /* its rows: cells of the rate's framing */
        if (m->made && m->cells != clip->frames && !timed) { /* framed as baked: the rate the bake chose gives its rows */
            memset(&clip->travel, 0, sizeof clip->travel);
            snprintf(clip->travel.why, sizeof clip->travel.why, "not applied: %u rows baked, %u analyzed", clip->frames, m->cells);
        } else if (m->made) { /* timed: measured at every cell, kept at the rows' */
            for (uint32_t k = 0; k < clip->frames; ++k) {
                uint32_t cell = timed ? plan->row_cells[k] : k;
                offsets[clip->first_row + k] = cell < m->cells ? m->offsets[cell] : 0;
            }
            any = any || clip->travel.applied;
        }
        free(own.offsets);
    }
    if (!any) free(offsets), offsets = NULL;
    free(p->row_travel);
    p->row_travel = offsets;
    return CB_OK;
}

void bake_travel_notes(const cb_palette *p, cb_warnings *w)
{
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        const cb_row_travel *t = &p->clips[c].travel;
        if (t->slide_mean > 0) /* measured: a striding loop in place; the others need no word */
            cb_warn(w, "note", "clip '%s' per-row travel %s", p->clips[c].name, t->why);
    }
}
