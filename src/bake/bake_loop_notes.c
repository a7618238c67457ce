/* bake_loop_notes.c - the bake's note for each loop it closed: a clip whose last key is its
 * closing key slightly off plays over its key span with the mismatch spread over the cycle
 * (CB_LOOP_CLOSED_CORRECTED), which moves the poses off the source; the user is told by how much
 * and how to keep the clip as it is. */
#include "bake_travel.h"
#include "core/loop_decide.h"

#include <math.h>

/* A loop baked over exactly its key span (start and length, float32 in a palette). */
#define BAKED_SPAN_TOLERANCE 1e-4

void bake_loop_notes(const cb_bake_job *job, cb_sampler *s, const cb_palette *p, cb_warnings *w)
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
        cb_error ignored = {0};
        if (cb_clip_analyze(s, a, cl->fps, 1, &job->limits, &info, &ignored) ||
            info.loop_reason != CB_LOOP_CLOSED_CORRECTED)
            continue;
        cb_warn(w, "note",
                "clip '%s' ends a small part of a key step from its first pose (wrap %.3g, under %g of its largest key "
                "step %.3g): its last key is taken for the closing key, slightly off, and the mismatch is spread over "
                "the cycle, which moves the poses up to %.3g mm/m off the source; --one-shot or a catalog's loop = "
                "false plays it as it is, once",
                cl->name, info.wrap_jump, CB_LOOP_CORRECTABLE, info.largest_key_step, info.loop_correction_mm_per_m);
    }
}
