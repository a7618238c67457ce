/* plant_feet.c - feet locked at bake time, the job's side (crowdbake/plant_feet.h): which clips
 * are planted and why, the model copy that carries their new leg keys, and what it changed. */
#include "plant_feet.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/stride.h"
#include "internal/plumbing.h"

typedef struct plant_state {
    const cb_model *original;
    cb_model model; /* the copy the bake samples: the original's data, the planted clips' channels its own */
    cb_plant_report report;
    plant_owned owned;
    double *duration; /* per planned clip, its length as framed before planting */
} plant_state;

const cb_plant_report *cb_bake_job_plant_report(const cb_bake_job *job)
{
    return job->planted ? &((const plant_state *)job->planted)->report : NULL;
}

/* The fades tried, as shares of a foot's shortest swing before each landing and after each lift:
 * the one whose feet slide least is kept (a short fade suits a walk whose paws land and lift
 * slowly, a long one a gallop's quick steps: Husky's Walk slides 9% with 0.1, 11% with 0.4; its
 * Gallop 14% and 9%). */
static const double fade_shares[] = {0.1, 0.25, 0.4};

/* The clip's stride on the model the sampler samples (its loop framed as the bake frames it). */
static bool measure(cb_sampler *s, const cb_bake_job *job, uint32_t i, cb_clip_info *info, cb_stride *st)
{
    cb_error e = {0};
    if (cb_clip_analyze(s, job->plan[i].animation, 30, job->plan[i].loop, &job->limits, info, &e)) return false;
    cb_stride_measure(s, info, st);
    return true;
}

/* The mean slide of clip i with its animation `anim` in place of the copy's, framed as the loop
 * it was (a duration of `duration`); 2 (past any) when it cannot be measured. */
static double trial_slide(const cb_bake_job *job, const plant_state *ps, uint32_t i, const cb_animation *anim,
                          double duration)
{
    const cb_model *m = &ps->model;
    cb_model trial = *m;
    cb_animation *anims = malloc((m->animation_count ? m->animation_count : 1) * sizeof *anims);
    double slide = 2;
    cb_error e = {0};
    cb_sampler *s = anims ? (memcpy(anims, m->animations, m->animation_count * sizeof *anims),
                             anims[job->plan[i].animation] = *anim, trial.animations = anims,
                             cb_sampler_create(&trial, job->skin, &e))
                          : NULL;
    cb_clip_info info;
    cb_stride st;
    int loop = job->plan[i].loop;
    if (s && !cb_clip_analyze(s, job->plan[i].animation, 30, loop, &job->limits, &info, &e) &&
        (!info.loops || fabs(info.duration - duration) > 1e-9))
        loop = 1; /* as measure_after frames it */
    if (s && !cb_clip_analyze(s, job->plan[i].animation, 30, loop, &job->limits, &info, &e)) {
        cb_stride_measure(s, &info, &st);
        if (st.stride) slide = st.slide_mean;
    }
    cb_sampler_free(s);
    free(anims);
    return slide;
}

/* Plants clip i at each fade; keeps the one that slides least. */
static bool plant_best(cb_sampler *s, const cb_bake_job *job, uint32_t i, const cb_clip_info *info, const cb_stride *st,
                       plant_state *ps)
{
    cb_plant_clip *pc = &ps->report.clips[i];
    cb_animation *anim = &ps->model.animations[pc->animation], best = *anim;
    double least = INFINITY;
    for (size_t f = 0; f < sizeof fade_shares / sizeof fade_shares[0]; ++f) {
        cb_animation trial = *anim;
        cb_plant_clip out = *pc;
        /* Its own channel table: planting replaces entries, and the model's stays the caller's. */
        cb_channel *channels = malloc((anim->channel_count ? anim->channel_count : 1) * sizeof *channels);
        if (!plant_owned_add(&ps->owned, channels)) break;
        trial.channels = memcpy(channels, anim->channels, anim->channel_count * sizeof *channels);
        if (!plant_clip(s, info, st, fade_shares[f], &trial, &ps->owned, &out) || !out.feet) continue;
        double slide = trial_slide(job, ps, i, &trial, ps->duration[i]);
        if (slide < least) least = slide, best = trial, *pc = out;
    }
    *anim = best;
    return least < INFINITY;
}

/* Plants clip i when its feet slide past the goal; says why (not). */
static void plant_one(cb_sampler *s, const cb_bake_job *job, uint32_t i, plant_state *ps)
{
    cb_plant_clip *pc = &ps->report.clips[i];
    cb_clip_info info;
    cb_stride st;
    pc->animation = job->plan[i].animation;
    bool framed = measure(s, job, i, &info, &st);
    ps->duration[i] = framed ? info.duration : 0;
    if (!framed) {
        snprintf(pc->why, sizeof pc->why, "left as is: the clip could not be framed");
        return;
    }
    if (!st.stride) {
        snprintf(pc->why, sizeof pc->why, "left as is: no stride (%.170s)", st.why);
        return;
    }
    pc->speed = st.speed, pc->slide_before = st.slide_mean, pc->slide_worst_before = st.slide_worst;
    cb_herd_slide slide; /* no per-row travel yet: the bake measures the planted clip's, after */
    cb_herd_slide_decide(&st, NULL, &slide);
    if (!slide.plant) {
        snprintf(pc->why, sizeof pc->why, "left as is: its feet slide %.0f%% of the ground speed, within the %.0f%% goal",
                 100 * st.slide_mean, 100 * CB_PLANT_SLIDE_GOAL);
        return;
    }
    for (uint32_t k = 0; k < i; ++k) /* the same animation under another name: planted once */
        if (job->plan[k].animation == pc->animation) {
            *pc = ps->report.clips[k];
            return;
        }
    if (!plant_best(s, job, i, &info, &st, ps)) {
        pc->feet = 0;
        snprintf(pc->why, sizeof pc->why, "left as is: no planted foot hangs from a leg of two bones to turn");
        return;
    }
    pc->planted = true;
}

/* The planted clips measured again, and said. A planted loop is framed as it was: turning its
 * legs can move its last pose far enough from its first that the poses alone would now read it
 * as one that ends elsewhere (Husky's Walk), but its keys were planted over the loop it was. */
static void measure_after(cb_bake_job *job, plant_state *ps, cb_error *err)
{
    cb_sampler *s = cb_sampler_create(&ps->model, job->skin, err);
    for (uint32_t i = 0; s && i < ps->report.clip_count; ++i) {
        cb_plant_clip *pc = &ps->report.clips[i];
        cb_clip_info info;
        cb_stride st;
        if (!pc->planted || !measure(s, job, i, &info, &st)) continue;
        bool reframed = !info.loops || fabs(info.duration - ps->duration[i]) > 1e-9;
        if (reframed) {
            job->plan[i].loop = 1;
            if (!measure(s, job, i, &info, &st)) continue;
        }
        pc->slide_after = st.stride ? st.slide_mean : 0, pc->slide_worst_after = st.stride ? st.slide_worst : 0;
        int n = snprintf(pc->why, sizeof pc->why, "%u feet planted at %.4g units/s: slide %.0f%% -> %.0f%% of the ground "
                         "speed (worst %.0f%% -> %.0f%%), leg joints turned up to %.1f deg", pc->feet, pc->speed,
                         100 * pc->slide_before, 100 * pc->slide_after, 100 * pc->slide_worst_before,
                         100 * pc->slide_worst_after, pc->max_rotation_deg);
        if (pc->max_shortfall > 1e-6 * pc->speed && n > 0 && (size_t)n < sizeof pc->why)
            n += snprintf(pc->why + n, sizeof pc->why - (size_t)n, "; a leg fell %.3g units short of its reach",
                          pc->max_shortfall);
        if (reframed && n > 0 && (size_t)n < sizeof pc->why)
            snprintf(pc->why + n, sizeof pc->why - (size_t)n, "; kept the %.4g s loop it was", info.duration);
    }
    cb_sampler_free(s);
}

static void free_state(plant_state *ps)
{
    for (uint32_t i = 0; i < ps->owned.count; ++i) free(ps->owned.ptr[i]);
    free(ps->owned.ptr), free(ps->report.clips), free(ps->duration), free(ps);
}

cb_status plant_feet_apply(cb_bake_job *job, cb_error *err)
{
    const cb_model *m = job->model;
    plant_state *ps = calloc(1, sizeof *ps);
    cb_animation *anims = malloc((m->animation_count ? m->animation_count : 1) * sizeof *anims);
    if (!ps || !plant_owned_add(&ps->owned, anims)) return free(ps), cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    memcpy(anims, m->animations, m->animation_count * sizeof *anims);
    ps->original = m, ps->model = *m, ps->model.animations = anims;
    ps->model.release = NULL; /* the copy's channels are not the mapped file's */
    ps->report.clip_count = job->plan_count;
    ps->report.clips = calloc(job->plan_count ? job->plan_count : 1, sizeof *ps->report.clips);
    ps->duration = calloc(job->plan_count ? job->plan_count : 1, sizeof *ps->duration);
    cb_sampler *s = ps->report.clips && ps->duration ? cb_sampler_create(m, job->skin, err) : NULL;
    for (uint32_t i = 0; s && i < job->plan_count; ++i) plant_one(s, job, i, ps);
    cb_sampler_free(s);
    if (!err->status && (!ps->report.clips || !ps->duration)) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    if (!err->status) measure_after(job, ps, err);
    if (err->status) return free_state(ps), err->status;
    job->model = &ps->model, job->planted = ps;
    return CB_OK;
}

void plant_feet_release(cb_bake_job *job)
{
    plant_state *ps = job->planted;
    if (!ps) return;
    job->model = ps->original, job->planted = NULL;
    free_state(ps);
}
