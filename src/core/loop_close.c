/* loop_close.c - closing a loop whose last key is its closing key slightly off
 * (CB_LOOP_CLOSED_CORRECTED): the sampler plays a corrected copy of the clip's channels, so the
 * bake, the rate search, the fit and verify all measure against the same target.
 *
 * Per channel, the mismatch d between its last and first key is spread linearly over the key
 * span, half of it at each end: value(t) - d * (u - 1/2), u = (t - t0) / span (rotations: times
 * the delta's power 1/2 - u). Both ends meet at their midpoint, so the wrap has no pop, and no
 * value moves by more than half its mismatch. The root's horizontal travel is not a mismatch: a
 * travelling loop keeps it (the root motion decision takes it out separately). */
#include "cb_math.h"
#include "crowdbake/core.h"
#include "sampler.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A channel is corrected when its keys span the clip (to this, in seconds): its ends are the
 * clip's ends. */
#define CB_CLOSE_SPAN_TOLERANCE 1e-4

static int channel_components(const cb_channel *ch) { return ch->path == CB_PATH_ROTATION ? 4 : 3; }

static float *channel_value(const cb_channel *ch, uint32_t k, int slot)
{
    int comps = channel_components(ch);
    int stride = comps * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
    return ch->values + (size_t)k * stride + slot * comps;
}

/* q to the power p (a unit quaternion, its shortest arc). */
static cb_quat quat_pow(cb_quat q, double p)
{
    if (q.w < 0) q = (cb_quat){-q.x, -q.y, -q.z, -q.w};
    double v = sqrt(q.x * q.x + q.y * q.y + q.z * q.z);
    if (v < 1e-15) return (cb_quat){0, 0, 0, 1};
    double half = atan2(v, q.w) * p, k = sin(half) / v;
    return (cb_quat){q.x * k, q.y * k, q.z * k, cos(half)};
}

static void correct_rotation(cb_channel *ch, const cb_animation *src, uint32_t c)
{
    int slot = ch->interp == CB_INTERP_CUBICSPLINE ? 1 : 0;
    const float *a = channel_value(&src->channels[c], 0, slot), *b = channel_value(&src->channels[c], ch->key_count - 1, slot);
    cb_quat qa = {a[0], a[1], a[2], a[3]}, qb = {b[0], b[1], b[2], b[3]};
    cb_quat delta = cb_quat_normalize(cb_quat_mul((cb_quat){-qa.x, -qa.y, -qa.z, qa.w}, qb)); /* qb = qa * delta */
    double span = src->t1 - src->t0;
    for (uint32_t k = 0; k < ch->key_count; ++k) {
        float *v = channel_value(ch, k, slot);
        cb_quat q = {v[0], v[1], v[2], v[3]};
        double u = ((double)ch->times[k] - src->t0) / span;
        q = cb_quat_normalize(cb_quat_mul(q, quat_pow(delta, 0.5 - u)));
        v[0] = (float)q.x, v[1] = (float)q.y, v[2] = (float)q.z, v[3] = (float)q.w;
    }
}

/* Translations and scales; `keep` (the root's travel in its parent's space, or 0) is not
 * corrected away. */
static void correct_linear(cb_channel *ch, const cb_animation *src, uint32_t c, const double keep[3])
{
    bool cubic = ch->interp == CB_INTERP_CUBICSPLINE;
    int slot = cubic ? 1 : 0;
    const float *a = channel_value(&src->channels[c], 0, slot), *b = channel_value(&src->channels[c], ch->key_count - 1, slot);
    double span = src->t1 - src->t0, d[3];
    for (int i = 0; i < 3; ++i) d[i] = (double)b[i] - a[i] - keep[i];
    for (uint32_t k = 0; k < ch->key_count; ++k) {
        double u = ((double)ch->times[k] - src->t0) / span;
        float *v = channel_value(ch, k, slot);
        for (int i = 0; i < 3; ++i) v[i] = (float)(v[i] - d[i] * (u - 0.5));
        for (int t = 0; cubic && t < 3; t += 2) { /* the tangents gain the correction's slope */
            float *g = channel_value(ch, k, t);
            for (int i = 0; i < 3; ++i) g[i] = (float)(g[i] - d[i] / span);
        }
    }
}

/* The node that carries the root's travel: the skin's root joint, or its nearest ancestor with a
 * translation channel in the clip; -1 when none moves. */
static int32_t travel_node(const cb_sampler *s, const cb_animation *a)
{
    const cb_model *m = s->model;
    for (int32_t n = m->skins[s->skin].joints[cb_skin_root_joint(m, s->skin)]; n >= 0; n = m->nodes[n].parent)
        for (uint32_t c = 0; c < a->channel_count; ++c)
            if (a->channels[c].node == n && a->channels[c].path == CB_PATH_TRANSLATION) return n;
    return -1;
}

/* travel (scene space) in the parent space of `node` at the clip's start: the inverse of the
 * parent's 3x3 applied to it. */
static void travel_in_parent(cb_sampler *s, int32_t animation, int32_t node, const double travel[3], double out[3])
{
    memcpy(out, travel, 3 * sizeof(double));
    int32_t p = s->model->nodes[node].parent;
    if (p < 0) return;
    const double *g = cb_sample_globals(s, animation, s->model->animations[animation].t0) + (size_t)p * 16;
    double c0[3] = {g[0], g[1], g[2]}, c1[3] = {g[4], g[5], g[6]}, c2[3] = {g[8], g[9], g[10]};
    double r0[3] = {c1[1] * c2[2] - c1[2] * c2[1], c1[2] * c2[0] - c1[0] * c2[2], c1[0] * c2[1] - c1[1] * c2[0]};
    double r1[3] = {c2[1] * c0[2] - c2[2] * c0[1], c2[2] * c0[0] - c2[0] * c0[2], c2[0] * c0[1] - c2[1] * c0[0]};
    double r2[3] = {c0[1] * c1[2] - c0[2] * c1[1], c0[2] * c1[0] - c0[0] * c1[2], c0[0] * c1[1] - c0[1] * c1[0]};
    double det = c0[0] * r0[0] + c0[1] * r0[1] + c0[2] * r0[2];
    if (fabs(det) < 1e-300) return;
    for (int i = 0; i < 3; ++i) out[i] = 0;
    for (int i = 0; i < 3; ++i) out[0] += r0[i] * travel[i] / det, out[1] += r1[i] * travel[i] / det, out[2] += r2[i] * travel[i] / det;
}

void cb_sampler_open_clip(cb_sampler *s, int32_t animation)
{
    cb_animation *a = s->closed[animation];
    if (!a) return;
    for (uint32_t c = 0; c < a->channel_count; ++c) free(a->channels[c].values);
    free(a->channels);
    free(a);
    s->closed[animation] = NULL;
}

static bool spans_clip(const cb_channel *ch, const cb_animation *a)
{
    return ch->key_count >= 2 && fabs(ch->times[0] - a->t0) <= CB_CLOSE_SPAN_TOLERANCE &&
           fabs(ch->times[ch->key_count - 1] - a->t1) <= CB_CLOSE_SPAN_TOLERANCE;
}

bool cb_sampler_close_clip(cb_sampler *s, int32_t animation, const double travel[3])
{
    cb_sampler_open_clip(s, animation);
    const cb_animation *src = &s->model->animations[animation];
    if (!(src->t1 > src->t0)) return true;
    int32_t mover = travel_node(s, src);
    double keep[3] = {0, 0, 0}, none[3] = {0, 0, 0};
    if (mover >= 0) travel_in_parent(s, animation, mover, travel, keep);
    cb_animation *a = calloc(1, sizeof *a);
    cb_channel *channels = calloc(src->channel_count ? src->channel_count : 1, sizeof *channels);
    if (!a || !channels) return free(a), free(channels), false;
    *a = *src, a->channels = channels;
    s->closed[animation] = a;
    for (uint32_t c = 0; c < src->channel_count; ++c) {
        const cb_channel *from = &src->channels[c];
        size_t floats = (size_t)from->key_count * channel_components(from) * (from->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
        channels[c] = *from;
        channels[c].values = malloc(floats * sizeof(float));
        a->channel_count = c + 1;
        if (!channels[c].values) return cb_sampler_open_clip(s, animation), false;
        memcpy(channels[c].values, from->values, floats * sizeof(float));
        if (!spans_clip(from, src)) continue;
        if (from->path == CB_PATH_ROTATION) correct_rotation(&channels[c], src, c);
        else correct_linear(&channels[c], src, c, from->node == mover && from->path == CB_PATH_TRANSLATION ? keep : none);
    }
    a->channel_count = src->channel_count;
    return true;
}

bool cb_sampler_set_loop(cb_sampler *s, const cb_clip_info *clip)
{
    cb_sampler_set_period(s, clip->animation, clip->loops ? clip->duration : 0);
    if (clip->animation < 0 || clip->animation >= (int32_t)s->model->animation_count) return true;
    if (!clip->loops || clip->loop_reason != CB_LOOP_CLOSED_CORRECTED) {
        cb_sampler_open_clip(s, clip->animation);
        return true;
    }
    double travel[3] = {clip->root_displacement[0], 0, clip->root_displacement[2]};
    /* Closed already with this travel and wrap (a search's probes of one clip set its loop on
     * the search's sampler each time): the copy it would make again is the one it has, made by
     * the same operations from the same source keys, travel and wrap (Cow's search re-closed
     * its clips 19 times, 4.2 M instructions). */
    double *with = s->closed_with + (size_t)clip->animation * 5, key[5] = {travel[0], travel[1], travel[2]};
    memcpy(key + 3, &s->wraps[clip->animation], sizeof(cb_wrap));
    if (s->closed[clip->animation] && !memcmp(with, key, sizeof key)) return true;
    if (!cb_sampler_close_clip(s, clip->animation, travel)) return false;
    memcpy(with, key, sizeof key);
    return true;
}

/* Times a correction's deviation is measured at: the ends, where each channel's correction is
 * half its mismatch, and between (bones chained together could add up elsewhere). */
#define CB_CLOSE_MEASURES 9

/* The largest distance of a skinned vertex between the corrected and the source clip. */
static double skinned_distance(const cb_model *m, int32_t skin, const double *fixed, const double *source, double *a,
                               double *b)
{
    double worst = 0;
    for (uint32_t p = 0; p < m->primitive_count; ++p) {
        const cb_primitive *prim = &m->primitives[p];
        if (prim->skin != skin) continue;
        cb_skin_positions(prim, fixed, a);
        cb_skin_positions(prim, source, b);
        for (size_t v = 0; v < prim->vertex_count; ++v)
            worst = fmax(worst, hypot(hypot(a[3 * v] - b[3 * v], a[3 * v + 1] - b[3 * v + 1]), a[3 * v + 2] - b[3 * v + 2]));
    }
    return worst;
}

int cb_loop_correction_measure(cb_sampler *s, cb_clip_info *clip)
{
    const cb_model *m = s->model;
    size_t n = (size_t)m->skins[s->skin].joint_count * 16, most = 1;
    for (uint32_t p = 0; p < m->primitive_count; ++p)
        if (m->primitives[p].skin == s->skin && m->primitives[p].vertex_count > most) most = m->primitives[p].vertex_count;
    double lo[3], hi[3], height = cb_skin_rest_bounds(s, lo, hi), worst = 0;
    double *mats = malloc(2 * n * sizeof(double)), *pos = malloc(6 * most * sizeof(double));
    if (!mats || !pos) return free(mats), free(pos), 1;
    cb_animation *closed = s->closed[clip->animation];
    for (int i = 0; closed && i < CB_CLOSE_MEASURES; ++i) {
        double t = clip->t0 + (clip->t1 - clip->t0) * i / (CB_CLOSE_MEASURES - 1);
        cb_sample_joint_matrices(s, clip->animation, t, mats);
        s->closed[clip->animation] = NULL; /* the source, for a moment */
        cb_sample_joint_matrices(s, clip->animation, t, mats + n);
        s->closed[clip->animation] = closed;
        worst = fmax(worst, skinned_distance(m, s->skin, mats, mats + n, pos, pos + 3 * most));
    }
    clip->loop_correction_mm_per_m = cb_mm_per_m(worst, height);
    free(mats), free(pos);
    return 0;
}

/* Keys are float32 in files and a .pal's times too: a baked loop over its clip's key span is one
 * within this (seconds). */
#define CB_BAKED_SPAN_TOLERANCE 1e-4

/* cb_sampler_set_baked_loop, judged from `judged` where given (a loop's analysis of the clip). */
static bool set_baked_loop(cb_sampler *s, int32_t animation, bool loops, double start, double duration,
                           const cb_clip_info *judged)
{
    cb_sampler_set_period(s, animation, loops ? duration : 0);
    if (animation < 0 || animation >= (int32_t)s->model->animation_count) return true;
    const cb_animation *a = &s->model->animations[animation];
    bool over_span = loops && !(fabs(start - a->t0) > CB_BAKED_SPAN_TOLERANCE) &&
                     !(fabs(duration - (a->t1 - a->t0)) > CB_BAKED_SPAN_TOLERANCE);
    bool closes = over_span && judged && judged->loop_reason == CB_LOOP_CLOSED_CORRECTED;
    if (!closes) cb_sampler_open_clip(s, animation); /* a copy closed alike is kept: cb_sampler_set_loop */
    if (!over_span) return true;
    if (judged) {
        /* As analyzing it as a loop leaves it: closed with its travel at the period of its span
         * (a closed loop's duration), then the period baked. */
        bool ok = !closes || cb_sampler_set_loop(s, judged);
        cb_sampler_set_period(s, animation, duration);
        return ok;
    }
    /* Judged again as the bake judged it (as a loop, at any rate: framing does not matter). */
    cb_clip_info info;
    cb_error e = {0};
    cb_status rc = cb_clip_analyze(s, animation, 1.0, 1, NULL, &info, &e);
    cb_sampler_set_period(s, animation, duration);
    if (rc || info.loop_reason != CB_LOOP_CLOSED_CORRECTED) cb_sampler_open_clip(s, animation);
    return rc != CB_ERR_INTERNAL;
}

bool cb_sampler_set_baked_loop(cb_sampler *s, int32_t animation, bool loops, double start, double duration)
{
    return set_baked_loop(s, animation, loops, start, duration, NULL);
}

bool sampler_set_baked_loop_judged(cb_sampler *s, const cb_clip_info *judged, bool loops, double start, double duration)
{
    return set_baked_loop(s, judged->animation, loops, start, duration, judged->loops ? judged : NULL);
}
