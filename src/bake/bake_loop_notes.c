/* bake_loop_notes.c - the bake's note for each loop it closed: a clip whose last key is its
 * closing key slightly off plays over its key span with the mismatch spread over the cycle
 * (CB_LOOP_CLOSED_CORRECTED), which moves the poses off the source; the user is told by how much
 * and how to keep the clip as it is. */
#include "bake_travel.h"
#include "core/clip_memo.h"
#include "core/loop_decide.h"

#include <math.h>

/* A loop baked over exactly its key span (start and length, float32 in a palette). */
#define BAKED_SPAN_TOLERANCE 1e-4

/* Clip c judged as a loop, as the note reads it: its loop_reason, wrap_jump, largest_key_step and
 * loop_correction_mm_per_m. The bake's own analysis of the clip (the plan's loop override at its
 * rate, in the run's memo) found it a loop, and a loop's judgement is the one forcing it gives: the
 * same poses judged (judge_loop), so the same reason and wrap (forcing it sets CB_LOOP_SET only on
 * a reason that is no closed loop), the same duration and correction. Any other: analyzed forced. */
static cb_status judged_as_loop(const cb_bake_job *job, clip_memo *memo, cb_sampler *s, uint32_t c, double fps,
                                cb_clip_info *info)
{
    cb_error ignored = {0};
    int32_t a = job->plan[c].animation;
    if (clip_memo_take(memo, s, a, cb_bake_job_clip_fps(job, c), job->plan[c].loop, &job->limits, info) && info->loops)
        return CB_OK;
    return cb_clip_analyze(s, a, fps, 1, &job->limits, info, &ignored);
}

void bake_loop_notes(const cb_bake_job *job, clip_memo *memo, cb_sampler *s, const cb_palette *p, cb_warnings *w)
{
    const cb_model *m = cb_sampler_model(s);
    for (uint32_t c = 0; c < p->clip_count && p->clip_count == job->plan_count; ++c) {
        const cb_palette_clip *cl = &p->clips[c];
        int32_t a = job->plan[c].animation;
        if (!cl->loops || a < 0 || a >= (int32_t)m->animation_count) continue;
        const cb_animation *anim = &m->animations[a];
        if (fabs(cl->start - anim->t0) > BAKED_SPAN_TOLERANCE ||
            fabs(cl->duration - (anim->t1 - anim->t0)) > BAKED_SPAN_TOLERANCE)
            continue;
        cb_clip_info info; /* judged again as the bake judged it: as a loop */
        if (judged_as_loop(job, memo, s, c, cl->fps, &info) || info.loop_reason != CB_LOOP_CLOSED_CORRECTED)
            continue;
        cb_warn(w, "note",
                "clip '%s' ends a small part of a key step from its first pose (wrap %.3g, under %g of its largest key "
                "step %.3g): its last key is taken for the closing key, slightly off, and the mismatch is spread over "
                "the cycle, which moves the poses up to %.3g mm/m off the source; --one-shot or a catalog's loop = "
                "false plays it as it is, once",
                cl->name, info.wrap_jump, CB_LOOP_CORRECTABLE, info.largest_key_step, info.loop_correction_mm_per_m);
    }
}
