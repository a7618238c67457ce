/* row_travel.c - the per-row travel offset of a striding loop (row_travel.h). */
#include "crowdbake/row_travel.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/stride.h"
#include "foot_sole.h"
#include "loop_decide.h"

/* A foot is planted while its sole is within 2% of the model's height of its lowest, as
 * cb_stride_measure plants it (stride.c's STANCE_BAND): the offsets keep still what it calls planted. */
#define PLANTED_BAND 0.02
/* Samples a row interval: at least 4, and at least 240 over the cycle (cb_stride_measure's). */
enum { MIN_SAMPLES = 240, MIN_PER_ROW = 4 };

/* The striding feet over the cycle, in the frame an in-place bake stores (the root's average
 * travel taken off): per sample, each foot's ground position, and per interval whether it is planted. */
typedef struct feet_track {
    uint32_t feet, samples;
    double *x;   /* feet x (samples + 1) x 2: ground position x, z */
    bool *down;  /* feet x samples */
} feet_track;

static bool track_feet(cb_sampler *s, const cb_clip_info *clip, const cb_stride *st, feet_track *tr)
{
    const cb_model *m = cb_sampler_model(s);
    uint32_t bones = m->skins[cb_sampler_skin(s)].joint_count, n = tr->samples;
    double *mats = malloc((size_t)bones * 16 * sizeof(double)), size = 0;
    double *h = malloc((size_t)tr->feet * (n + 1) * sizeof(double));
    foot_sole soles[CB_MAX_FEET] = {{0}};
    uint32_t found = 0;
    bool ok = mats && h && tr->x && tr->down;
    if (ok) {
        cb_sample_joint_matrices(s, -1, 0, mats);
        found = foot_soles_find(s, mats, soles, CB_MAX_FEET, &size);
        ok = found == st->foot_count && size > 0;
    }
    double dt = clip->duration / n, span = clip->t1 - clip->t0;
    for (uint32_t i = 0; ok && i <= n; ++i) {
        double t = i * dt, tau = cb_root_travel_time(t, span, clip->duration, clip->loops), xz[2];
        cb_sample_joint_matrices(s, clip->animation, clip->t0 + (i == n ? 0 : t), mats); /* the loop ends on its start */
        if (i == n) tau = 0;
        for (uint32_t k = 0; k < tr->feet; ++k) {
            foot_sole_at(&soles[k], mats, &h[(size_t)k * (n + 1) + i], xz);
            double *x = tr->x + ((size_t)k * (n + 1) + i) * 2;
            x[0] = xz[0] - clip->root_velocity[0] * tau, x[1] = xz[1] - clip->root_velocity[2] * tau;
        }
    }
    for (uint32_t k = 0; ok && k < tr->feet; ++k) {
        const double *hk = h + (size_t)k * (n + 1);
        double lo = INFINITY;
        for (uint32_t i = 0; i <= n; ++i) lo = fmin(lo, hk[i]);
        for (uint32_t i = 0; i < n; ++i)
            tr->down[(size_t)k * n + i] = st->feet[k].strides && fmax(hk[i], hk[i + 1]) <= lo + PLANTED_BAND * size;
    }
    foot_soles_free(soles, found);
    free(mats), free(h);
    return ok;
}

/* Foot k's velocity over interval i, model units/s. */
static void foot_velocity(const feet_track *tr, uint32_t k, uint32_t i, double dt, double u[2])
{
    const double *a = tr->x + ((size_t)k * (tr->samples + 1) + i) * 2;
    u[0] = (a[2] - a[0]) / dt, u[1] = (a[3] - a[1]) / dt;
}

/* The offsets: over each row interval, the body's speed along the heading that the feet planted
 * then ask for (the mean of their backward speeds; v where none is planted), integrated, the
 * drift over the cycle taken off evenly (so it travels at v on average) and centred on 0. */
static void integrate_offsets(const feet_track *tr, const cb_stride *st, double dt, uint32_t rows, double *o)
{
    uint32_t per_row = tr->samples / rows;
    o[0] = 0;
    for (uint32_t r = 0; r < rows; ++r) {
        double sum = 0;
        for (uint32_t i = r * per_row; i < (r + 1) * per_row; ++i) {
            double w = 0, u[2];
            uint32_t planted = 0;
            for (uint32_t k = 0; k < tr->feet; ++k)
                if (tr->down[(size_t)k * tr->samples + i])
                    foot_velocity(tr, k, i, dt, u), w -= u[0] * st->heading[0] + u[1] * st->heading[2], ++planted;
            sum += ((planted ? w / planted : st->speed) - st->speed) * dt;
        }
        o[r + 1] = o[r] + sum;
    }
    double mean = 0;
    for (uint32_t r = 0; r <= rows; ++r) o[r] -= o[rows] * r / rows;
    for (uint32_t r = 0; r < rows; ++r) mean += o[r] / rows;
    for (uint32_t r = 0; r <= rows; ++r) o[r] -= mean;
}

/* The planted feet's mean slide, a fraction of v, with the body moving at v plus the offsets'
 * slope over each row interval (o NULL: at v alone). */
static double mean_slide(const feet_track *tr, const cb_stride *st, double dt, uint32_t rows, const double *o)
{
    uint32_t per_row = tr->samples / rows, count = 0;
    double sum = 0, row_time = dt * per_row;
    for (uint32_t i = 0; i < tr->samples; ++i) {
        uint32_t r = i / per_row;
        double speed = st->speed + (o ? (o[r + 1] - o[r]) / row_time : 0), u[2];
        for (uint32_t k = 0; k < tr->feet; ++k)
            if (tr->down[(size_t)k * tr->samples + i]) {
                foot_velocity(tr, k, i, dt, u);
                sum += hypot(u[0] + speed * st->heading[0], u[1] + speed * st->heading[2]), ++count;
            }
    }
    return count ? sum / count / st->speed : 0;
}

/* The range of the striding feet's backward speeds, for the words. */
static void step_speed_range(const cb_stride *st, double *lo, double *hi)
{
    *lo = INFINITY, *hi = 0;
    for (uint32_t k = 0; k < st->foot_count; ++k)
        if (st->feet[k].strides) *lo = fmin(*lo, st->feet[k].step_speed), *hi = fmax(*hi, st->feet[k].step_speed);
}

/* Ships where it cuts the slide by a third, unless the clip's name says an action done once: a
 * runtime moves an instance at the clip's speed only in states that follow the speed, which an
 * attack or a hit reaction never does, so its offsets would never be drawn as travel. */
static void decide(const cb_stride *st, const char *name, cb_row_travel *out)
{
    double cut = out->slide_mean > 0 ? 1 - out->slide_with / out->slide_mean : 0, lo, hi;
    char action[20];
    if (cb_name_says_once(name, action, sizeof action)) {
        snprintf(out->why, sizeof out->why, "not applied: the clip's name says '%s', an action, which no runtime moves at "
                 "the ground speed (they add the travel only to states that follow the speed); it would cut the planted "
                 "feet's mean slide from %.0f%% to %.0f%%", action, 100 * out->slide_mean, 100 * out->slide_with);
        return;
    }
    out->applied = cut >= CB_ROW_TRAVEL_MIN_CUT;
    if (out->applied) {
        snprintf(out->why, sizeof out->why, "applied: the body's travel varied per row cuts the planted feet's mean slide "
                 "from %.0f%% to %.0f%% of the ground speed (%.0f%% less; a third or more ships it)",
                 100 * out->slide_mean, 100 * out->slide_with, 100 * cut);
        return;
    }
    step_speed_range(st, &lo, &hi);
    char cause[96];
    if (hi > 1.25 * lo)
        snprintf(cause, sizeof cause, "its feet step back at %.3g-%.3g units/s at once, which no one body speed plants", lo, hi);
    else
        snprintf(cause, sizeof cause, "its feet slide within each stance, which moving the body does not undo");
    snprintf(out->why, sizeof out->why, "not applied: the body's travel varied per row would cut the planted feet's mean "
             "slide only from %.0f%% to %.0f%% of the ground speed (%.0f%% less, under a third): %s",
             100 * out->slide_mean, 100 * out->slide_with, 100 * cut, cause);
}

void cb_row_travel_measure(cb_sampler *s, const cb_clip_info *clip, bool in_place, uint32_t rows, float *offsets,
                           cb_row_travel *out)
{
    memset(out, 0, sizeof *out);
    memset(offsets, 0, (size_t)rows * sizeof *offsets);
    if (!clip->loops || clip->duration <= 0 || rows < 2) {
        snprintf(out->why, sizeof out->why, "not applied: %s", clip->loops ? "a single pose" : "a one-shot has no cycle to "
                 "travel through; it keeps its own root travel or none");
        return;
    }
    if (!in_place) {
        snprintf(out->why, sizeof out->why, "not applied: its root motion is kept, so the clip carries its own travel");
        return;
    }
    cb_stride *st = malloc(sizeof *st);
    if (!st) return;
    cb_stride_measure(s, clip, st);
    if (!st->stride || !(st->speed > 0)) {
        snprintf(out->why, sizeof out->why, "not applied: no stride (%.200s)", st->why);
        free(st);
        return;
    }
    for (int k = 0; k < 3; ++k) out->heading[k] = (float)st->heading[k];
    uint32_t per_row = rows >= MIN_SAMPLES / MIN_PER_ROW ? MIN_PER_ROW : (MIN_SAMPLES + rows - 1) / rows;
    feet_track tr = {st->foot_count, rows * per_row, NULL, NULL};
    tr.x = malloc((size_t)tr.feet * (tr.samples + 1) * 2 * sizeof(double));
    tr.down = malloc((size_t)tr.feet * tr.samples * sizeof(bool));
    double *o = malloc((size_t)(rows + 1) * sizeof(double)), dt = clip->duration / tr.samples;
    if (o && track_feet(s, clip, st, &tr)) {
        integrate_offsets(&tr, st, dt, rows, o);
        out->slide_mean = mean_slide(&tr, st, dt, rows, NULL);
        out->slide_with = mean_slide(&tr, st, dt, rows, o);
        decide(st, cb_sampler_model(s)->animations[clip->animation].name, out);
        for (uint32_t r = 0; out->applied && r < rows; ++r) offsets[r] = (float)o[r];
    } else {
        snprintf(out->why, sizeof out->why, "not applied: out of memory measuring it");
    }
    free(tr.x), free(tr.down), free(o), free(st);
}
