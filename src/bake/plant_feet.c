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
    double *hold;     /* per planned clip, the hold it was planted with (seconds) */
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
/* The holds tried (plant_keys.c): none, and one row interval of a 30 fps bake before each landing
 * and after each lift, which takes the worst moment of the slide from the row that holds the
 * landing (Husky's Walk 98% -> 13%, its Gallop 110% -> 24%, Cow's Gallop 80% -> 9%, through the C
 * reader). A hold is kept only where the knees then bend no faster from key to key than the
 * clip's own do (10% over, as the pop test allows): held longer, a nearly straight leg (Cow's
 * front legs in its Walk) must reach further, and its knee would snap. */
static const double holds[] = {0, 1.0 / 30};
#define KNEE_RATE_SLACK 1.1

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

/* One planting of a clip: its animation, what it did, how far its feet slide, how fast its knees bend. */
typedef struct plant_trial {
    cb_animation anim;
    cb_plant_clip clip;
    double slide, knees, hold;
} plant_trial;

/* Less slide (by more than a hair), else knees that bend slower. */
static bool better(const plant_trial *a, const plant_trial *b)
{
    return a->slide < b->slide - 1e-4 || (a->slide <= b->slide + 1e-4 && a->knees < b->knees);
}

/* Plants clip i at each fade and hold into trials[] (count them). */
static uint32_t plant_trials(cb_sampler *s, const cb_bake_job *job, uint32_t i, const cb_clip_info *info,
                             const cb_stride *st, plant_state *ps, plant_trial *trials, double *source_knees)
{
    const cb_animation *anim = &ps->model.animations[ps->report.clips[i].animation];
    uint32_t n = 0;
    for (size_t h = 0; h < sizeof holds / sizeof holds[0]; ++h)
        for (size_t f = 0; f < sizeof fade_shares / sizeof fade_shares[0]; ++f) {
            plant_trial *t = &trials[n];
            plant_knees knees;
            t->anim = *anim, t->clip = ps->report.clips[i], t->hold = holds[h];
            /* Its own channel table: planting replaces entries, and the model's stays the caller's. */
            cb_channel *channels = malloc((anim->channel_count ? anim->channel_count : 1) * sizeof *channels);
            if (!plant_owned_add(&ps->owned, channels)) return n;
            t->anim.channels = memcpy(channels, anim->channels, anim->channel_count * sizeof *channels);
            plant_timing timing = {fade_shares[f], holds[h]};
            if (!plant_clip(s, info, st, timing, &t->anim, &ps->owned, &t->clip, &knees) || !t->clip.feet) continue;
            t->slide = trial_slide(job, ps, i, &t->anim, ps->duration[i]), t->knees = knees.planted;
            *source_knees = knees.source, ++n;
        }
    return n;
}

/* Plants clip i at each fade and hold; keeps the one that slides least (knees that bend slower
 * break a tie) of those whose knees bend no faster from key to key than the clip's own (10% over)
 * or than the best planting without a hold does. */
static bool plant_best(cb_sampler *s, const cb_bake_job *job, uint32_t i, const cb_clip_info *info, const cb_stride *st,
                       plant_state *ps)
{
    plant_trial trials[sizeof holds / sizeof holds[0] * sizeof fade_shares / sizeof fade_shares[0]];
    double source_knees = 0;
    uint32_t n = plant_trials(s, job, i, info, st, ps, trials, &source_knees);
    const plant_trial *unheld = NULL, *best = NULL;
    for (uint32_t k = 0; k < n; ++k)
        if (trials[k].hold == 0 && (!unheld || better(&trials[k], unheld))) unheld = &trials[k];
    double bound = fmax(KNEE_RATE_SLACK * source_knees, unheld ? unheld->knees : 0);
    for (uint32_t k = 0; k < n; ++k)
        if (trials[k].knees <= bound && (!best || better(&trials[k], best))) best = &trials[k];
    if (!best) return false;
    ps->model.animations[ps->report.clips[i].animation] = best->anim;
    ps->report.clips[i] = best->clip, ps->hold[i] = best->hold;
    return true;
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
            *pc = ps->report.clips[k], ps->hold[i] = ps->hold[k];
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
        if (ps->hold[i] > 0 && n > 0 && (size_t)n < sizeof pc->why)
            n += snprintf(pc->why + n, sizeof pc->why - (size_t)n, "; held %.2g s more each end",
                          ps->hold[i]);
        if (reframed && n > 0 && (size_t)n < sizeof pc->why)
            snprintf(pc->why + n, sizeof pc->why - (size_t)n, "; kept the %.4g s loop it was", info.duration);
    }
    cb_sampler_free(s);
}

static void free_state(plant_state *ps)
{
    for (uint32_t i = 0; i < ps->owned.count; ++i) free(ps->owned.ptr[i]);
    free(ps->owned.ptr), free(ps->report.clips), free(ps->duration), free(ps->hold), free(ps);
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
    ps->hold = calloc(job->plan_count ? job->plan_count : 1, sizeof *ps->hold);
    cb_sampler *s = ps->report.clips && ps->duration && ps->hold ? cb_sampler_create(m, job->skin, err) : NULL;
    for (uint32_t i = 0; s && i < job->plan_count; ++i) plant_one(s, job, i, ps);
    cb_sampler_free(s);
    if (!err->status && (!ps->report.clips || !ps->duration || !ps->hold)) cb_fail(err, CB_ERR_INTERNAL, "out of memory");
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
