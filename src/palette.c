/* palette.c - baking clips into a bone-matrix palette: framing every clip, encoding each
 * joint matrix in the chosen layout and precision, and measuring the error that costs. */
#include "palette.h"

#include "budget.h"
#include "error_bound.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h"

#include <threads.h>
#include <time.h>

/* Canonical floats per bone and row before the final encoding: the upper 3x4 of the matrix
 * by rows (mat4, affine), or quaternion, position and scale (qpos). */
/* Floats per bone per row before encoding: the texels' values (qpos uses 8 of them). */
#define CANON(layout) ((layout) == CB_LAYOUT_QPOS ? 8u : 12u)
#define QPOS_TOLERANCE 1e-4 /* relative: scale differences and shear qpos may drop */

static const char *const layout_names[] = {"mat4", "affine", "qpos"};
static const char *const precision_names[] = {"float", "half", "u16"};

const char *cb_layout_name(cb_layout l) { return (unsigned)l < 3 ? layout_names[l] : "?"; }
const char *cb_precision_name(cb_precision p) { return (unsigned)p < 3 ? precision_names[p] : "?"; }

bool cb_layout_parse(const char *text, cb_layout *out)
{
    for (int i = 0; i < 3; ++i)
        if (strcmp(text, layout_names[i]) == 0) return *out = (cb_layout)i, true;
    return false;
}

bool cb_precision_parse(const char *text, cb_precision *out)
{
    for (int i = 0; i < 3; ++i)
        if (strcmp(text, precision_names[i]) == 0) return *out = (cb_precision)i, true;
    return false;
}

uint32_t cb_layout_texels_per_bone(cb_layout l) { return l == CB_LAYOUT_MAT4 ? 4 : l == CB_LAYOUT_AFFINE ? 3 : 2; }
uint32_t cb_precision_texel_bytes(cb_precision p) { return p == CB_PRECISION_FLOAT ? 16 : 8; }

cb_bake_options cb_default_bake_options(void)
{
    cb_bake_options o;
    o.fps = 30;
    o.layout = CB_LAYOUT_QPOS;
    o.precision = CB_PRECISION_U16;
    o.max_texture_size = 16384;
    o.root_motion = CB_ROOT_MOTION_KEEP;
    o.limits = cb_default_limits();
    o.threads = 1;
    o.affine_fallback = false;
    o.fit = false;
    o.error_goal = 0;
    return o;
}

void cb_palette_free(cb_palette *p)
{
    if (!p) return;
    free(p->clips);
    free(p->bind_positions);
    free(p->position_offsets);
    free(p->texels);
    memset(p, 0, sizeof *p);
}

void cb_palette_texel_xy(const cb_palette *p, uint32_t row, uint32_t bone, uint32_t *x, uint32_t *y)
{
    *x = (row / p->height) * p->row_texels + bone * p->texels_per_bone;
    *y = row % p->height;
}

/* ---- geometry of the texture ---- */

static cb_status plan_texture(cb_palette *p, uint32_t max_size, const char *source, cb_error *err)
{
    if (max_size < 1) return cb_fail(err, CB_ERR_USAGE, "--max-texture-size must be at least 1");
    if (p->row_texels > max_size)
        return cb_fail(err, CB_ERR_INPUT,
                       "%s: %u bones x %u texels = %u texels per row, wider than --max-texture-size %u; use a layout "
                       "with fewer texels per bone (qpos: 2) or a larger limit",
                       source, p->bone_count, p->texels_per_bone, p->row_texels, max_size);
    cb_texture_geometry g;
    if (!cb_wrap_rows(p->row_texels, p->rows, max_size, &g))
        return cb_fail(err, CB_ERR_INPUT,
                       "%s: %u baked rows do not fit a %ux%u texture even wrapped into %u columns of %u rows; lower "
                       "--fps, bake fewer clips, or raise --max-texture-size",
                       source, p->rows, max_size, max_size, max_size / p->row_texels, max_size);
    p->blocks = g.blocks, p->height = g.height, p->width = g.width;
    return CB_OK;
}

/* ---- pass 1: sample every row into canonical floats ---- */

static cb_status qpos_canon(const double m[16], float out[8], const cb_model *model, const cb_skin *skin, uint32_t bone,
                            const char *clip, uint32_t frame, cb_quat *prev, cb_error *err)
{
    cb_vec3 c[3] = {{m[0], m[1], m[2]}, {m[4], m[5], m[6]}, {m[8], m[9], m[10]}};
    double l[3] = {cb_vec3_length(c[0]), cb_vec3_length(c[1]), cb_vec3_length(c[2])};
    double s = (l[0] + l[1] + l[2]) / 3;
    const char *why = NULL;
    if (cb_mat4_determinant3(m) <= 0)
        why = "a negative (mirroring) scale";
    else if (fabs(l[0] - s) > QPOS_TOLERANCE * s || fabs(l[1] - s) > QPOS_TOLERANCE * s || fabs(l[2] - s) > QPOS_TOLERANCE * s)
        why = "a non-uniform scale";
    else if (fabs(cb_vec3_dot(c[0], c[1])) > QPOS_TOLERANCE * s * s || fabs(cb_vec3_dot(c[0], c[2])) > QPOS_TOLERANCE * s * s ||
             fabs(cb_vec3_dot(c[1], c[2])) > QPOS_TOLERANCE * s * s)
        why = "shear";
    if (why)
        return cb_fail(err, CB_ERR_INPUT,
                       "%s: joint '%s' has %s (axis scales %.7g, %.7g, %.7g) at frame %u of clip '%s', which the qpos "
                       "layout cannot represent; use --layout affine or --layout mat4",
                       model->source, model->nodes[skin->joints[bone]].name, why, l[0], l[1], l[2], frame, clip);
    double r[16], inv = 1 / s;
    memcpy(r, m, sizeof r);
    for (int i = 0; i < 12; ++i) r[i] *= inv;
    cb_quat q = cb_quat_from_mat4(r);
    if (prev) {
        if (cb_quat_dot(q, *prev) < 0) q = (cb_quat){-q.x, -q.y, -q.z, -q.w};
    } else if (q.w < 0) {
        q = (cb_quat){-q.x, -q.y, -q.z, -q.w};
    }
    out[0] = (float)q.x, out[1] = (float)q.y, out[2] = (float)q.z, out[3] = (float)q.w;
    out[7] = (float)s;
    return CB_OK;
}

/* What u16 quantization needs of the values: the box of the translations (or positions) and
 * the largest linear term (or qpos scale). Kept per clip while sampling, merged after. */
typedef struct value_range {
    float lo[3], hi[3], linear;
} value_range;

static void range_reset(value_range *r)
{
    for (int k = 0; k < 3; ++k) r->lo[k] = INFINITY, r->hi[k] = -INFINITY;
    r->linear = 0;
}

/* Compares, not fminf/fmaxf: the values are finite and the compares inline. A qpos bone's
 * position and scale, written out per axis so a local range stays in registers. */
static inline void range_grow_qpos(value_range *r, const float *v)
{
    r->lo[0] = v[4] < r->lo[0] ? v[4] : r->lo[0];
    r->lo[1] = v[5] < r->lo[1] ? v[5] : r->lo[1];
    r->lo[2] = v[6] < r->lo[2] ? v[6] : r->lo[2];
    r->hi[0] = v[4] > r->hi[0] ? v[4] : r->hi[0];
    r->hi[1] = v[5] > r->hi[1] ? v[5] : r->hi[1];
    r->hi[2] = v[6] > r->hi[2] ? v[6] : r->hi[2];
    r->linear = v[7] > r->linear ? v[7] : r->linear;
}

/* An affine or mat4 bone's 12 canonical values (3 rows of 4). */
static inline void range_grow_affine(value_range *r, const float *v)
{
    for (int k = 0; k < 3; ++k) {
        float t = v[k * 4 + 3];
        if (t < r->lo[k]) r->lo[k] = t;
        if (t > r->hi[k]) r->hi[k] = t;
    }
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k)
            if (fabsf(v[i * 4 + k]) > r->linear) r->linear = fabsf(v[i * 4 + k]);
}

static void merge_ranges(cb_palette *p, const value_range *clips)
{
    value_range all;
    range_reset(&all);
    for (uint32_t c = 0; c < p->clip_count; ++c) {
        for (int k = 0; k < 3; ++k) {
            if (clips[c].lo[k] < all.lo[k]) all.lo[k] = clips[c].lo[k];
            if (clips[c].hi[k] > all.hi[k]) all.hi[k] = clips[c].hi[k];
        }
        if (clips[c].linear > all.linear) all.linear = clips[c].linear;
    }
    bool empty = !(all.lo[0] <= all.hi[0]);
    for (int k = 0; k < 3; ++k) p->bounds_min[k] = empty ? 0 : all.lo[k], p->bounds_max[k] = empty ? 0 : all.hi[k];
    p->linear_range = all.linear;
}

/* Per-thread scratch: each worker samples its own clips with its own sampler. */
typedef struct worker {
    cb_sampler *sampler;
    double *mats;        /* bones * 16 */
    cb_similarity *sims; /* CB_SAMPLE_BATCH rows of bones: the joints, for qpos rows of similarity rigs */
    cb_quat *prev;       /* bones: the previous row's quaternion (qpos) */
    float *rows;         /* the pre-encoding rows of the clip being sampled (max_clip_frames of them) */
} worker;

typedef struct bake_state {
    cb_palette *p;
    const cb_model *model;
    int32_t skin;
    const cb_bake_options *opt;
    const cb_clip_info *infos;
    /* Each worker samples a clip's rows into its own buffer and encodes them from there. Only
     * u16 has to wait for the ranges of every clip: it keeps what it has not yet encoded of
     * every row here (kept_floats per bone), and encodes that after the last clip. */
    float *kept;
    uint32_t max_clip_frames;
    const double *radius;  /* bones: bind-space reach of the vertices each joint moves, or -1 */
    uint32_t *breaks;      /* clips: hemisphere breaks at the loop wrap */
    cb_error *errors;      /* clips: the first error of each */
    uint32_t error_stride; /* measure every n-th row of a clip (and its last) */
    double weight_sum;     /* the largest sum of a vertex's |weights| (error_bound.h) */
    double *clip_error;    /* clips: worst vertex error measured */
    double *clip_blend_error; /* clips: worst vertex error halfway between rows, as the runtime blends them */
    value_range *ranges;   /* clips: the values' ranges */
    double *encode_seconds; /* clips: time spent encoding each, when encoded as sampled */
} bake_state;

/* What u16 keeps of a bone's row until every clip is sampled: qpos's position and scale (its
 * quaternion is snorm, which needs no range, and is encoded at once), or all 12 values. */
static uint32_t kept_floats(cb_layout layout) { return layout == CB_LAYOUT_QPOS ? 4 : 12; }

/* A clip's bounds while it is sampled, kept in double: rounding the extremes to float at the
 * end gives the floats that rounding every candidate would (rounding is monotonic). */
typedef struct extent {
    double lo[3], hi[3];
} extent;

/* Grows a clip's bounds by the sphere a joint's vertices can reach: a vertex weighted to joint
 * j lies within |A_j| * r_j of c = M_j b_j, so the union over joints bounds the skinned mesh. */
static inline void grow_bounds(extent *e, cb_vec3 c, double reach)
{
    /* Compares, not fmin: no NaN reaches here. Written out per axis, so that a local extent
     * stays in registers (a loop here is not unrolled at -O2 and keeps it in memory). */
    e->lo[0] = c.x - reach < e->lo[0] ? c.x - reach : e->lo[0];
    e->lo[1] = c.y - reach < e->lo[1] ? c.y - reach : e->lo[1];
    e->lo[2] = c.z - reach < e->lo[2] ? c.z - reach : e->lo[2];
    e->hi[0] = c.x + reach > e->hi[0] ? c.x + reach : e->hi[0];
    e->hi[1] = c.y + reach > e->hi[1] ? c.y + reach : e->hi[1];
    e->hi[2] = c.z + reach > e->hi[2] ? c.z + reach : e->hi[2];
}

/* |A| for the reach: the Frobenius norm of the 3x3, at least its largest stretch. */
static double frobenius3(const double *M)
{
    double norm = 0;
    for (int k = 0; k < 12; ++k)
        if (k % 4 != 3) norm += M[k] * M[k];
    return sqrt(norm);
}

/* One row from joint matrices: any layout; qpos checks each matrix is a similarity. */
static cb_status matrix_row(bake_state *st, worker *w, uint32_t c, uint32_t f, float *row, extent *bounds,
                            cb_error *err)
{
    cb_palette *p = st->p;
    cb_palette_clip *clip = &p->clips[c];
    cb_clip_frame_matrices(w->sampler, &st->infos[c], f, st->opt->root_motion, w->mats);
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        const double *M = w->mats + (size_t)j * 16;
        const float *b = p->bind_positions + (size_t)j * 3;
        float *out = row + (size_t)j * CANON(p->layout);
        cb_vec3 pos = cb_mat4_transform_point(M, (cb_vec3){b[0], b[1], b[2]}); /* the joint now: M b */
        if (st->radius[j] >= 0) grow_bounds(bounds, pos, st->radius[j] * frobenius3(M));
        if (p->layout != CB_LAYOUT_QPOS) {
            for (int r = 0; r < 3; ++r)
                for (int k = 0; k < 4; ++k) out[r * 4 + k] = (float)M[k * 4 + r];
            range_grow_affine(&st->ranges[c], out);
            continue;
        }
        if (qpos_canon(M, out, st->model, &st->model->skins[st->skin], j, clip->name, f, f ? &w->prev[j] : NULL, err))
            return err->status;
        w->prev[j] = (cb_quat){out[0], out[1], out[2], out[3]};
        out[4] = (float)pos.x, out[5] = (float)pos.y, out[6] = (float)pos.z;
        range_grow_qpos(&st->ranges[c], out);
    }
    return CB_OK;
}

/* One qpos row from joint similarities: what qpos stores, with no matrix to build, check or
 * decompose. */
static void similarity_row(bake_state *st, worker *w, uint32_t c, uint32_t f, const cb_similarity *sims, float *row,
                           extent *clip_bounds)
{
    cb_palette *p = st->p;
    extent bounds = *clip_bounds;         /* locals, which the compiler keeps in registers */
    value_range range = st->ranges[c];
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        const cb_similarity *J = &sims[j];
        const float *b = p->bind_positions + (size_t)j * 3;
        float *out = row + (size_t)j * 8;
        cb_quat q = {J->rotation[0], J->rotation[1], J->rotation[2], J->rotation[3]};
        cb_vec3 rb = cb_quat_rotate(q, (cb_vec3){b[0], b[1], b[2]});
        cb_vec3 pos = {J->translation[0] + J->scale * rb.x, J->translation[1] + J->scale * rb.y,
                       J->translation[2] + J->scale * rb.z};
        if (st->radius[j] >= 0) grow_bounds(&bounds, pos, st->radius[j] * J->scale * sqrt(3.0)); /* |s R| = sqrt(3) s */
        if (f ? cb_quat_dot(q, w->prev[j]) < 0 : q.w < 0) q = (cb_quat){-q.x, -q.y, -q.z, -q.w};
        out[0] = (float)q.x, out[1] = (float)q.y, out[2] = (float)q.z, out[3] = (float)q.w;
        out[4] = (float)pos.x, out[5] = (float)pos.y, out[6] = (float)pos.z, out[7] = (float)J->scale;
        w->prev[j] = (cb_quat){out[0], out[1], out[2], out[3]};
        range_grow_qpos(&range, out);
    }
    *clip_bounds = bounds;
    st->ranges[c] = range;
}

/* The exact values halfway through each row interval of clip c (the clip framed at twice the
 * steps, odd frames), into mids; quaternions on the side of the row before. */
static cb_status sample_mids(bake_state *st, worker *w, uint32_t c, const float *rows, float *mids, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_clip_info *info = &st->infos[c];
    cb_clip_info framing = *info;
    framing.steps *= 2;
    uint32_t intervals = info->loops ? info->frames : info->frames - 1, vals = CANON(p->layout);
    for (uint32_t i = 0; i < intervals; ++i) {
        cb_clip_frame_matrices(w->sampler, &framing, 2 * i + 1, st->opt->root_motion, w->mats);
        float *out = mids + (size_t)i * p->bone_count * vals;
        for (uint32_t j = 0; j < p->bone_count; ++j) {
            const double *M = w->mats + (size_t)j * 16;
            float *o = out + (size_t)j * vals;
            if (p->layout != CB_LAYOUT_QPOS) {
                for (int r = 0; r < 3; ++r)
                    for (int k = 0; k < 4; ++k) o[r * 4 + k] = (float)M[k * 4 + r];
                continue;
            }
            const float *prev = rows + ((size_t)i * p->bone_count + j) * vals, *b = p->bind_positions + (size_t)j * 3;
            cb_quat q = {prev[0], prev[1], prev[2], prev[3]};
            if (qpos_canon(M, o, st->model, &st->model->skins[st->skin], j, p->clips[c].name, i, &q, err))
                return err->status;
            cb_vec3 pos = cb_mat4_transform_point(M, (cb_vec3){b[0], b[1], b[2]});
            o[4] = (float)pos.x, o[5] = (float)pos.y, o[6] = (float)pos.z;
        }
    }
    return CB_OK;
}

/* --fit: the clip's rows moved to split the linear blend's error between rows and mid-rows. */
static cb_status fit_clip(bake_state *st, worker *w, uint32_t c, float *rows, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_clip_info *info = &st->infos[c];
    size_t row_floats = (size_t)p->bone_count * CANON(p->layout);
    float *mids = malloc((size_t)info->frames * row_floats * sizeof(float));
    if (!mids) return cb_fail(err, CB_ERR_INTERNAL, "out of memory fitting %s", st->model->source);
    if (!sample_mids(st, w, c, rows, mids, err)) {
        cb_fit_rows(rows, mids, info->frames, p->bone_count, CANON(p->layout), info->loops, p->layout == CB_LAYOUT_QPOS);
        range_reset(&st->ranges[c]); /* the fitted values' range */
        for (size_t b = 0; b < (size_t)info->frames * p->bone_count; ++b) {
            if (p->layout == CB_LAYOUT_QPOS) range_grow_qpos(&st->ranges[c], rows + b * 8);
            else range_grow_affine(&st->ranges[c], rows + b * 12);
        }
    }
    free(mids);
    return err->status;
}

static cb_status sample_clip(bake_state *st, worker *w, uint32_t c, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_clip_info *info = &st->infos[c];
    cb_palette_clip *clip = &p->clips[c];
    extent bounds = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    range_reset(&st->ranges[c]);
    bool similar = p->layout == CB_LAYOUT_QPOS && cb_sampler_is_similarity(w->sampler);
    size_t row_floats = (size_t)p->bone_count * CANON(p->layout);
    if (!w->rows && !(w->rows = malloc(st->max_clip_frames * row_floats * sizeof(float)))) /* only sampling needs them */
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory sampling %s", st->model->source);
    float *rows = w->rows;
    for (uint32_t f = 0; similar && f < info->frames; f += CB_SAMPLE_BATCH) {
        uint32_t frames[CB_SAMPLE_BATCH], count = 0;
        while (count < CB_SAMPLE_BATCH && f + count < info->frames) frames[count] = f + count, ++count;
        cb_clip_frame_similarities(w->sampler, info, frames, count, st->opt->root_motion, w->sims);
        for (uint32_t i = 0; i < count; ++i)
            similarity_row(st, w, c, f + i, w->sims + (size_t)i * p->bone_count, rows + (f + i) * row_floats, &bounds);
    }
    for (uint32_t f = 0; !similar && f < info->frames; ++f)
        if (matrix_row(st, w, c, f, rows + f * row_floats, &bounds, err)) return err->status;
    if (st->opt->fit && fit_clip(st, w, c, rows, err)) return err->status;
    bool empty = !(bounds.lo[0] <= bounds.hi[0]); /* no skinned vertex */
    for (int k = 0; k < 3; ++k) {
        clip->bounds_min[k] = empty ? 0 : (float)bounds.lo[k];
        clip->bounds_max[k] = empty ? 0 : (float)bounds.hi[k];
    }
    if (p->layout == CB_LAYOUT_QPOS && info->loops && info->frames > 1) {
        /* The wrap from the last row to the first: a full turn over the loop ends on -q. */
        const float *last = rows + (info->frames - 1) * row_floats;
        for (uint32_t j = 0; j < p->bone_count; ++j) {
            const float *qa = rows + (size_t)j * CANON(p->layout), *qb = last + (size_t)j * CANON(p->layout);
            if (qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3] < 0) st->breaks[c]++;
        }
    }
    return CB_OK;
}

/* ---- running clips on several threads ---- */

typedef struct job {
    bake_state *st;
    uint32_t first, stride;
    void (*run)(bake_state *st, worker *w, uint32_t clip);
    bool samples; /* run uses the worker's sampler and scratch */
} job;

static int job_main(void *arg)
{
    job *jb = arg;
    bake_state *st = jb->st;
    worker w = {0};
    cb_error *err0 = &st->errors[jb->first < st->p->clip_count ? jb->first : 0];
    if (jb->samples) {
        w.sampler = cb_sampler_create(st->model, st->skin, err0);
        /* Loops without a closing key wrap. (One-shots never sample past their last key: a clip
         * planned twice, as a loop and as a one-shot, keeps its loop's period.) */
        for (uint32_t c = 0; w.sampler && c < st->p->clip_count; ++c)
            if (st->infos[c].loops) cb_sampler_set_period(w.sampler, st->infos[c].animation, st->infos[c].duration);
        w.mats = malloc((size_t)st->p->bone_count * 16 * sizeof(double));
        w.sims = malloc((size_t)st->p->bone_count * CB_SAMPLE_BATCH * sizeof(cb_similarity));
        w.prev = malloc((size_t)st->p->bone_count * sizeof(cb_quat));
    }
    if (jb->samples && (!w.sampler || !w.mats || !w.sims || !w.prev)) {
        cb_fail(err0, CB_ERR_INTERNAL, "out of memory sampling %s", st->model->source);
    } else {
        for (uint32_t c = jb->first; c < st->p->clip_count; c += jb->stride) jb->run(st, &w, c);
    }
    cb_sampler_free(w.sampler);
    free(w.mats);
    free(w.sims);
    free(w.prev);
    free(w.rows);
    return 0;
}

static uint32_t threads_used(const bake_state *st)
{
    uint32_t threads = st->opt->threads ? st->opt->threads : 1;
    if (threads > st->p->clip_count) threads = st->p->clip_count ? st->p->clip_count : 1;
    return threads > 64 ? 64 : threads;
}

/* Runs `run` for every clip, clip c on thread c % threads. Each clip writes only its own rows
 * and slots, so the result does not depend on the thread count. */
static void for_each_clip(bake_state *st, void (*run)(bake_state *, worker *, uint32_t), bool samples)
{
    uint32_t threads = threads_used(st);
    job jobs[64];
    thrd_t ids[64];
    bool started[64] = {false};
    for (uint32_t t = 0; t < threads; ++t) {
        jobs[t] = (job){st, t, threads, run, samples};
        started[t] = t > 0 && thrd_create(&ids[t], job_main, &jobs[t]) == thrd_success;
    }
    job_main(&jobs[0]);
    for (uint32_t t = 1; t < threads; ++t) {
        if (started[t]) thrd_join(ids[t], NULL);
        else job_main(&jobs[t]); /* no thread: do its share here */
    }
}

static double seconds_now(void)
{
    struct timespec ts;
    timespec_get(&ts, TIME_UTC);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

static void encode_rows(cb_palette *p, const float *rows, uint32_t first, uint32_t count);
static void encode_qpos_u16(cb_palette *p, const float *rows, uint32_t stride, uint32_t v0, uint32_t first,
                            uint32_t count);
static void encode_qpos_half(cb_palette *p, const float *rows, uint32_t stride, uint32_t v0, uint32_t first,
                             uint32_t count);

/* Values encoding waits for: u16's need the ranges of every clip, half's positions each bone's
 * offset (the centre of its positions over every clip). */
static bool keeps_values(const cb_palette *p) { return p->precision != CB_PRECISION_FLOAT; }

/* The joint's position p = M b of a kept mat4/affine row (the upper 3x4 by rows), axis r. */
static double row_position(const float *c, const float *b, int r)
{
    return (double)c[r * 4] * b[0] + (double)c[r * 4 + 1] * b[1] + (double)c[r * 4 + 2] * b[2] + c[r * 4 + 3];
}

/* Encodes a clip as soon as it is sampled, from rows still in cache: all of it, or for u16
 * what needs no range, keeping the rest for encode_kept_job. */
static void sample_clip_job(bake_state *st, worker *w, uint32_t c)
{
    if (st->errors[c].status || sample_clip(st, w, c, &st->errors[c])) return;
    cb_palette *p = st->p;
    const cb_palette_clip *clip = &p->clips[c];
    double start = seconds_now();
    size_t bones = (size_t)clip->frames * p->bone_count, kept = kept_floats(p->layout);
    if (!keeps_values(p)) {
        encode_rows(p, w->rows, clip->first_row, clip->frames);
    } else if (p->layout == CB_LAYOUT_QPOS) {
        float *keep = st->kept + (size_t)clip->first_row * p->bone_count * kept;
        if (p->precision == CB_PRECISION_U16) encode_qpos_u16(p, w->rows, 8, 0, clip->first_row, clip->frames);
        else encode_qpos_half(p, w->rows, 8, 0, clip->first_row, clip->frames);
        for (size_t b = 0; b < bones; ++b) memcpy(keep + b * 4, w->rows + b * 8 + 4, 4 * sizeof(float));
    } else {
        memcpy(st->kept + (size_t)clip->first_row * p->bone_count * kept, w->rows, bones * kept * sizeof(float));
    }
    st->encode_seconds[c] = seconds_now() - start;
}

/* u16 and qpos/half, once the ranges and offsets of every clip are known: the values a clip kept. */
static void encode_kept_job(bake_state *st, worker *w, uint32_t c)
{
    (void)w;
    cb_palette *p = st->p;
    const cb_palette_clip *clip = &p->clips[c];
    const float *kept = st->kept + (size_t)clip->first_row * p->bone_count * kept_floats(p->layout);
    if (p->layout == CB_LAYOUT_QPOS && p->precision == CB_PRECISION_HALF)
        encode_qpos_half(p, kept, 4, 4, clip->first_row, clip->frames);
    else if (p->layout == CB_LAYOUT_QPOS)
        encode_qpos_u16(p, kept, 4, 4, clip->first_row, clip->frames);
    else
        encode_rows(p, kept, clip->first_row, clip->frames);
}

/* ---- pass 2: encode ---- */

/* Quantization arithmetic runs in double so it adds nothing to the half-step of the format. */
static double snorm16_decode(uint16_t u)
{
    double v = (int16_t)u / 32767.0;
    return v < -1 ? -1 : v;
}

static double unorm16_decode(uint16_t u, double lo, double hi) { return hi > lo ? lo + (hi - lo) * (u / 65535.0) : lo; }

/* The 4 * texels_per_bone values of one bone, in texel order, as floats. */
static void texel_values(const cb_palette *p, const float *v, float out[16])
{
    switch (p->layout) {
    case CB_LAYOUT_MAT4: /* texel k = column k */
        for (int k = 0; k < 4; ++k) {
            for (int r = 0; r < 3; ++r) out[k * 4 + r] = v[r * 4 + k];
            out[k * 4 + 3] = k == 3 ? 1.0f : 0.0f;
        }
        break;
    case CB_LAYOUT_AFFINE: /* texel k = row k */
        memcpy(out, v, 12 * sizeof(float));
        break;
    case CB_LAYOUT_QPOS:
        memcpy(out, v, 8 * sizeof(float));
        break;
    }
}

/* Which kind of u16 quantization each of a bone's values gets: 0 snorm over linear_range,
 * 1..3 unorm over the box axis (k - 1), 4 snorm as is (quaternions), 5 unorm over
 * [0, linear_range] (qpos scale), 6 a constant (mat4's last row). */
static int u16_kind(cb_layout layout, int i)
{
    if (layout == CB_LAYOUT_QPOS) return i < 4 ? 4 : i < 7 ? 1 + (i - 4) : 5;
    if (layout == CB_LAYOUT_AFFINE) return i % 4 == 3 ? 1 + i / 4 : 0;
    if (i % 4 == 3) return 6;                 /* mat4: w of each column */
    return i >= 12 ? 1 + (i - 12) : 0;        /* column 3 is the translation */
}

static double decode_u16(const cb_palette *p, int kind, uint16_t u)
{
    switch (kind) {
    case 0: return snorm16_decode(u) * p->linear_range;
    case 4: return snorm16_decode(u);
    case 5: return unorm16_decode(u, 0, p->linear_range);
    case 6: return u ? 1.0 : 0.0;
    default: return unorm16_decode(u, p->bounds_min[kind - 1], p->bounds_max[kind - 1]);
    }
}

static void store_le16(unsigned char *d, uint16_t v) { d[0] = (unsigned char)v, d[1] = (unsigned char)(v >> 8); }
static uint16_t load_le16(const unsigned char *d) { return (uint16_t)(d[0] | d[1] << 8); }

static void store_le32f(unsigned char *d, float f)
{
    uint32_t v;
    memcpy(&v, &f, 4);
    for (int i = 0; i < 4; ++i) d[i] = (unsigned char)(v >> (8 * i));
}

static float load_le32f(const unsigned char *d)
{
    uint32_t v = (uint32_t)d[0] | (uint32_t)d[1] << 8 | (uint32_t)d[2] << 16 | (uint32_t)d[3] << 24;
    float f;
    memcpy(&f, &v, 4);
    return f;
}

/* How each of a bone's values is quantized to u16: x = (v - offset) * scale, clamped to
 * [lo, hi], times `steps`, rounded; snorm values are stored as two's complement. */
typedef struct u16_slot {
    double offset, scale, lo, hi, steps;
} u16_slot;

static void u16_slots(const cb_palette *p, u16_slot slots[16])
{
    for (int i = 0; i < 16; ++i) {
        u16_slot *q = &slots[i];
        int kind = u16_kind(p->layout, i);
        double range = kind == 0 || kind == 5 ? p->linear_range : kind >= 1 && kind <= 3
                       ? (double)p->bounds_max[kind - 1] - p->bounds_min[kind - 1] : 1;
        bool snorm = kind == 0 || kind == 4;
        q->offset = kind >= 1 && kind <= 3 ? p->bounds_min[kind - 1] : 0;
        q->scale = range > 0 ? 1 / range : 0;
        q->lo = snorm ? -1 : 0;
        q->hi = 1;
        q->steps = snorm ? 32767 : 65535;
        if (kind == 6) q->offset = 0, q->scale = 1, q->lo = 0; /* mat4's constant 0/1 row */
    }
}

static inline uint16_t quantize(const u16_slot *q, double v)
{
    double x = (v - q->offset) * q->scale;
    x = x < q->lo ? q->lo : x; /* two selects, not nested ones: they compile to max and min, */
    x = x > q->hi ? q->hi : x; /* where the nested ones branch (and mispredict) */
    long n = lrint(x * q->steps);
    return (uint16_t)(int16_t)n; /* snorm: two's complement; unorm: 0..65535 fits */
}

/* Encodes `count` rows of canonical floats into the texels of rows first, first + 1, ... */
static void encode_rows(cb_palette *p, const float *rows, uint32_t first, uint32_t count)
{
    uint32_t tb = cb_precision_texel_bytes(p->precision), nvalues = p->texels_per_bone * 4;
    u16_slot slots[16];
    u16_slots(p, slots);
    for (uint32_t r = first; r < first + count; ++r) {
        uint32_t x0, y;
        cb_palette_texel_xy(p, r, 0, &x0, &y);
        unsigned char *d = (unsigned char *)p->texels + ((size_t)y * p->width + x0) * tb;
        const float *row = rows + (size_t)(r - first) * p->bone_count * CANON(p->layout);
        for (uint32_t j = 0; j < p->bone_count; ++j, d += (size_t)p->texels_per_bone * tb) {
            float vals[16], rel[12];
            const float *c = row + (size_t)j * CANON(p->layout), *o = p->position_offsets + (size_t)j * 3;
            if (p->positions_relative && p->layout != CB_LAYOUT_QPOS) { /* the translation: p = M b, less o */
                memcpy(rel, c, sizeof rel);
                for (int r = 0; r < 3; ++r) rel[r * 4 + 3] = (float)(row_position(c, p->bind_positions + (size_t)j * 3, r) - o[r]);
                c = rel;
            }
            texel_values(p, c, vals);
            for (int k = 0; p->positions_relative && p->layout == CB_LAYOUT_QPOS && k < 3; ++k) vals[4 + k] -= o[k];
            if (p->precision == CB_PRECISION_FLOAT)
                for (uint32_t i = 0; i < nvalues; ++i) store_le32f(d + i * 4, vals[i]);
            else if (p->precision == CB_PRECISION_HALF)
                for (uint32_t i = 0; i < nvalues; ++i) store_le16(d + i * 2, cb_float_to_half(vals[i]));
            else
                for (uint32_t i = 0; i < nvalues; ++i) store_le16(d + i * 2, quantize(&slots[i], vals[i]));
        }
    }
}

/* Encodes qpos values v0..v0 + 3 (the quaternion, or position and scale) of `count` rows as
 * u16; `rows` holds `stride` floats per bone, starting with value v0. (qpos texel order is its
 * canonical order.) */
static void encode_qpos_u16(cb_palette *p, const float *rows, uint32_t stride, uint32_t v0, uint32_t first,
                            uint32_t count)
{
    u16_slot slots[16];
    u16_slots(p, slots);
    for (uint32_t r = first; r < first + count; ++r) {
        uint32_t x0, y;
        cb_palette_texel_xy(p, r, 0, &x0, &y);
        unsigned char *d = (unsigned char *)p->texels + ((size_t)y * p->width + x0) * 8 + v0 * 2; /* RGBA16 */
        const float *row = rows + (size_t)(r - first) * p->bone_count * stride;
        for (uint32_t j = 0; j < p->bone_count; ++j, d += 16)
            for (uint32_t i = 0; i < 4; ++i) store_le16(d + i * 2, quantize(&slots[v0 + i], row[j * stride + i]));
    }
}

/* Encodes qpos values v0..v0 + 3 of `count` rows as half floats, positions less their bone's
 * offset; `rows` holds `stride` floats per bone, starting with value v0. */
static void encode_qpos_half(cb_palette *p, const float *rows, uint32_t stride, uint32_t v0, uint32_t first,
                             uint32_t count)
{
    for (uint32_t r = first; r < first + count; ++r) {
        uint32_t x0, y;
        cb_palette_texel_xy(p, r, 0, &x0, &y);
        unsigned char *d = (unsigned char *)p->texels + ((size_t)y * p->width + x0) * 8 + v0 * 2; /* RGBA16F */
        const float *row = rows + (size_t)(r - first) * p->bone_count * stride;
        for (uint32_t j = 0; j < p->bone_count; ++j, d += 16)
            for (uint32_t i = 0; i < 4; ++i) {
                float v = row[j * stride + i];
                if (v0 == 4 && i < 3) v -= p->position_offsets[(size_t)j * 3 + i];
                store_le16(d + i * 2, cb_float_to_half(v));
            }
    }
}

/* qpos/half: each bone's position offset, the centre of the box of its positions over every
 * row. A half float's step grows with the value; positions less the centre stay within half
 * the bone's reach (Cow: 0.60 -> 0.32 mm/m; less its bind position, a body that falls or
 * travels still lands far from it). */
static void position_offsets(cb_palette *p, const float *kept)
{
    uint32_t stride = kept_floats(p->layout);
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t r = 0; r < p->rows; ++r) {
            const float *v = kept + ((size_t)r * p->bone_count + j) * stride;
            for (int k = 0; k < 3; ++k) {
                double x = p->layout == CB_LAYOUT_QPOS ? v[k] : row_position(v, p->bind_positions + (size_t)j * 3, k);
                lo[k] = x < lo[k] ? x : lo[k], hi[k] = x > hi[k] ? x : hi[k];
            }
        }
        for (int k = 0; k < 3; ++k) p->position_offsets[(size_t)j * 3 + k] = p->rows ? (float)(0.5 * (lo[k] + hi[k])) : 0;
    }
}

void cb_palette_decode_values(const cb_palette *p, const void *texels, uint32_t row, uint32_t bone, double v[16])
{
    uint32_t tb = cb_precision_texel_bytes(p->precision), x, y;
    cb_palette_texel_xy(p, row, bone, &x, &y);
    const unsigned char *d = (const unsigned char *)texels + ((size_t)y * p->width + x) * tb;
    for (uint32_t i = 0; i < p->texels_per_bone * 4; ++i) {
        if (p->precision == CB_PRECISION_FLOAT)
            v[i] = load_le32f(d + i * 4);
        else if (p->precision == CB_PRECISION_HALF)
            v[i] = cb_half_to_float(load_le16(d + i * 2));
        else
            v[i] = decode_u16(p, u16_kind(p->layout, (int)i), load_le16(d + i * 2));
    }
    /* The position values: qpos's texel 1, mat4's column 3, affine's w of each row. */
    static const int at[3][3] = {{12, 13, 14}, {3, 7, 11}, {4, 5, 6}};
    for (int k = 0; p->positions_relative && k < 3; ++k) v[at[p->layout][k]] += p->position_offsets[(size_t)bone * 3 + k];
}

void cb_palette_decode(const cb_palette *p, const void *texels, uint32_t row, uint32_t bone, double out[16])
{
    double v[16];
    cb_palette_decode_values(p, texels, row, bone, v);
    cb_palette_values_to_matrix(p, bone, v, out);
}

void cb_palette_values_to_matrix(const cb_palette *p, uint32_t bone, const double v[16], double out[16])
{
    cb_mat4_identity(out);
    if (p->layout == CB_LAYOUT_MAT4) {
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 3; ++r) out[c * 4 + r] = v[c * 4 + r];
    } else if (p->layout == CB_LAYOUT_AFFINE) {
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) out[c * 4 + r] = v[r * 4 + c];
    }
    if (p->layout != CB_LAYOUT_QPOS && p->positions_relative) { /* the translation holds p = M b: t = p - A b */
        const float *b = p->bind_positions + (size_t)bone * 3;
        cb_vec3 ab = cb_mat4_transform_dir(out, (cb_vec3){b[0], b[1], b[2]});
        out[12] -= ab.x, out[13] -= ab.y, out[14] -= ab.z;
    } else if (p->layout == CB_LAYOUT_QPOS) {
        /* v' = p + s * rotate(q, v - b)  =>  A = s R(q), t = p - A b */
        cb_quat q = cb_quat_normalize((cb_quat){v[0], v[1], v[2], v[3]});
        double s = v[7];
        cb_vec3 one = {s, s, s};
        cb_mat4_from_trs(out, (cb_vec3){0, 0, 0}, q, one);
        const float *b = p->bind_positions + (size_t)bone * 3;
        cb_vec3 ab = cb_mat4_transform_dir(out, (cb_vec3){b[0], b[1], b[2]});
        out[12] = v[4] - ab.x, out[13] = v[5] - ab.y, out[14] = v[6] - ab.z;
    }
}

/* ---- pass 3: the error against exact skinning ---- */

/* The worst vertex error of the given rows of clip c (parts = 1), or between each of them and
 * the next at fraction sub / parts, blended as the runtime does. Skinning is linear in the
 * matrices, so one skinning with (exact - decoded) gives each vertex's error directly: half
 * the work of skinning twice, and no cancellation. Rows baked from similarities are measured
 * against those, sampled together like the bake did. */
static double measure_rows(bake_state *st, worker *w, uint32_t c, const uint32_t *frames, uint32_t count,
                           uint32_t sub, uint32_t parts, double *diff, double *err_pos, double *bounds)
{
    cb_palette *p = st->p;
    const cb_model *m = st->model;
    const cb_palette_clip *clip = &p->clips[c];
    /* Fraction sub / parts between rows f and f + 1 is row parts * f + sub of the clip framed at
     * `parts` times the steps. */
    cb_clip_info framing = st->infos[c];
    uint32_t times[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < count; ++i) times[i] = parts * frames[i] + sub;
    framing.steps *= parts;
    bool similar = p->layout == CB_LAYOUT_QPOS && cb_sampler_is_similarity(w->sampler);
    if (similar) cb_clip_frame_similarities(w->sampler, &framing, times, count, st->opt->root_motion, w->sims);
    double worst = 0;
    for (uint32_t i = 0; i < count; ++i) {
        if (!similar) cb_clip_frame_matrices(w->sampler, &framing, times[i], st->opt->root_motion, w->mats);
        uint32_t row = clip->first_row + frames[i], next = clip->first_row + (frames[i] + 1) % clip->frames;
        for (uint32_t j = 0; j < p->bone_count; ++j) {
            double *d = diff + (size_t)j * 16, *exact = w->mats + (size_t)j * 16;
            if (similar) cb_similarity_matrix(&w->sims[(size_t)i * p->bone_count + j], exact);
            if (sub) cb_palette_blend(p, p->texels, row, next, (double)sub / parts, j, d);
            else cb_palette_decode(p, p->texels, row, j, d);
            for (int k = 0; k < 16; ++k) d[k] = exact[k] - d[k];
        }
        if (bounds) { /* only the row's upper bound (error_bound.h) */
            bounds[i] = cb_row_error_bound(diff, p->bone_count, p->bind_positions, st->radius, st->weight_sum);
            continue;
        }
        for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
            const cb_primitive *prim = &m->primitives[pi];
            if (prim->skin != st->skin) continue;
            cb_skin_positions(prim, diff, err_pos);
            for (uint64_t v = 0; v < (uint64_t)prim->vertex_count * 3; v += 3) {
                double d2 = err_pos[v] * err_pos[v] + err_pos[v + 1] * err_pos[v + 1] + err_pos[v + 2] * err_pos[v + 2];
                worst = d2 > worst ? d2 : worst;
            }
        }
    }
    return sqrt(worst);
}

/* The worst vertex error of clip c over every error_stride-th row and the last (sub > 0: at
 * fraction sub / parts from each of those rows to the next, as the runtime blends them; a
 * one-shot's last row has no next). Branch and bound: every row's cheap bound first, then exact
 * skinning in order of bound, largest first, until no row left can exceed the worst found - the
 * same maximum as skinning every row, for a fraction of the work. Rows that cannot exceed
 * `floor` are not measured (0 when none may be skipped): the result is exact when above it.
 * With an error goal, measuring also stops once the worst exceeds it. */
static double measure_clip_rows(bake_state *st, worker *w, uint32_t c, uint32_t sub, uint32_t parts, double floor,
                                double *diff, double *err_pos, cb_bounded_row *rows)
{
    const cb_palette_clip *clip = &st->p->clips[c];
    uint32_t frames = sub && !clip->loops ? clip->frames - 1 : clip->frames, batch[CB_SAMPLE_BATCH], n = 0;
    for (uint32_t f = 0; f < frames; ++f)
        if (f % st->error_stride == 0 || f + 1 == frames) rows[n++].frame = f;
    double bounds[CB_SAMPLE_BATCH], worst = floor, goal = st->opt->error_goal;
    for (uint32_t i = 0; i < n; i += CB_SAMPLE_BATCH) {
        uint32_t count = n - i < CB_SAMPLE_BATCH ? n - i : CB_SAMPLE_BATCH;
        for (uint32_t k = 0; k < count; ++k) batch[k] = rows[i + k].frame;
        measure_rows(st, w, c, batch, count, sub, parts, diff, err_pos, bounds);
        for (uint32_t k = 0; k < count; ++k) rows[i + k].bound = bounds[k];
    }
    cb_sort_bounded_rows(rows, n);
    /* Batches of 1, 2, 4, ... rows: often the first few rows settle it. */
    for (uint32_t i = 0, size = 1; i < n && rows[i].bound > worst && !(goal > 0 && worst > goal); size *= 2) {
        uint32_t count = 0;
        for (; i < n && count < size && count < CB_SAMPLE_BATCH && rows[i].bound > worst; ++i) batch[count++] = rows[i].frame;
        for (uint32_t x = 1; x < count; ++x) /* increasing frames, as the batched sampler wants them */
            for (uint32_t y = x; y > 0 && batch[y - 1] > batch[y]; --y) {
                uint32_t swap = batch[y];
                batch[y] = batch[y - 1], batch[y - 1] = swap;
            }
        worst = fmax(worst, measure_rows(st, w, c, batch, count, sub, parts, diff, err_pos, NULL));
    }
    return worst;
}

static void measure_clip(bake_state *st, worker *w, uint32_t c)
{
    const cb_palette *p = st->p;
    uint64_t verts = cb_model_skin_vertex_count(st->model, st->skin);
    double *diff = malloc((size_t)p->bone_count * 16 * sizeof(double));
    double *err_pos = malloc((size_t)(verts ? verts : 1) * 3 * sizeof(double));
    st->clip_error[c] = st->clip_blend_error[c] = 0;
    cb_bounded_row *rows = malloc((size_t)p->clips[c].frames * sizeof *rows);
    /* A sampled row interval errs most halfway (a chord under an arc); fitted rows err both
     * ways, so their quarter points are measured too. */
    uint32_t parts = p->fitted ? 4 : 2;
    double goal = st->opt->error_goal, blend = 0;
    if (diff && err_pos && rows && verts) {
        /* Each fraction's rows only count where they exceed the worst blend so far. */
        for (uint32_t sub = 1; sub < parts && !(goal > 0 && blend > goal); ++sub)
            blend = measure_clip_rows(st, w, c, sub, parts, blend, diff, err_pos, rows);
        st->clip_blend_error[c] = blend;
        if (goal > 0) { /* only the visible error: the baked rows that could exceed the blend */
            double both = blend > goal ? blend : measure_clip_rows(st, w, c, 0, 1, blend, diff, err_pos, rows);
            st->clip_error[c] = both > blend ? both : 0; /* exact when above the blend; else only <= it */
        } else {
            st->clip_error[c] = measure_clip_rows(st, w, c, 0, 1, 0, diff, err_pos, rows);
        }
    } else if (verts) {
        cb_fail(&st->errors[c], CB_ERR_INTERNAL, "out of memory measuring %s", st->model->source);
    }
    free(diff);
    free(err_pos);
    free(rows);
}

/* Bind-space distance from each joint's bind position to the farthest vertex it moves;
 * -1 for joints that move none. Returns false when no vertex is skinned. */
static bool joint_reach(const cb_palette *p, const cb_model *m, int32_t skin, double *radius)
{
    bool any = false;
    for (uint32_t j = 0; j < p->bone_count; ++j) radius[j] = -1;
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
        const cb_primitive *prim = &m->primitives[pi];
        if (prim->skin != skin) continue;
        for (uint32_t v = 0; v < prim->vertex_count; ++v)
            for (int i = 0; i < 4; ++i) {
                if (prim->weights[(size_t)v * 4 + i] == 0) continue;
                uint16_t j = prim->joints[(size_t)v * 4 + i];
                const float *b = p->bind_positions + (size_t)j * 3, *x = prim->positions + (size_t)v * 3;
                double d = sqrt((double)(x[0] - b[0]) * (x[0] - b[0]) + (double)(x[1] - b[1]) * (x[1] - b[1]) +
                                (double)(x[2] - b[2]) * (x[2] - b[2]));
                if (d > radius[j]) radius[j] = d;
                any = true;
            }
    }
    return any;
}

/* ---- the bake ---- */

static cb_status frame_clips(bake_state *st, cb_sampler *sampler, const cb_clip_plan *plan, uint32_t count,
                             cb_clip_info **infos_out, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_model *m = st->model;
    if (!plan) count = m->animation_count;
    cb_clip_info *infos = calloc(count ? count : 1, sizeof *infos);
    p->clips = calloc(count ? count : 1, sizeof *p->clips);
    *infos_out = infos;
    if (!infos || !p->clips) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    uint64_t rows = 0;
    for (uint32_t i = 0; i < count; ++i) {
        cb_clip_plan one = plan ? plan[i] : (cb_clip_plan){(int32_t)i, NULL, -1, 0};
        double fps = one.fps > 0 ? one.fps : st->opt->fps;
        if (cb_clip_analyze(sampler, one.animation, fps, one.loop, &st->opt->limits, &infos[i], err)) return err->status;
        cb_palette_clip *c = &p->clips[i];
        c->name = one.name ? one.name : m->animations[one.animation].name;
        c->first_row = (uint32_t)rows;
        c->frames = infos[i].frames;
        c->fps = infos[i].effective_fps;
        c->duration = infos[i].duration;
        c->start = infos[i].t0;
        c->loops = infos[i].loops;
        for (int k = 0; k < 3; ++k)
            c->root_velocity[k] = (float)(st->opt->root_motion == CB_ROOT_MOTION_IN_PLACE ? infos[i].root_velocity[k] : 0);
        rows += infos[i].frames;
        if (rows > st->opt->limits.max_frames)
            return cb_fail(err, CB_ERR_INPUT, "%s: %llu baked rows over all clips, over the limit of %u (--max-frames)",
                           m->source, (unsigned long long)rows, st->opt->limits.max_frames);
    }
    p->clip_count = count;
    p->rows = (uint32_t)rows;
    return CB_OK;
}

static void bind_positions(cb_palette *p, const cb_skin *skin)
{
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        /* The joint's bind-pose position is the translation of inverse(IBM). */
        const double *ibm = skin->inverse_bind + (size_t)j * 16;
        double det = cb_mat4_determinant3(ibm);
        cb_vec3 b = {0, 0, 0};
        if (fabs(det) > 1e-300) {
            /* Solve A b = -t with Cramer's rule. */
            double t[3] = {-ibm[12], -ibm[13], -ibm[14]}, col[16];
            double *res[3] = {&b.x, &b.y, &b.z};
            for (int k = 0; k < 3; ++k) {
                memcpy(col, ibm, sizeof col);
                col[k * 4 + 0] = t[0], col[k * 4 + 1] = t[1], col[k * 4 + 2] = t[2];
                *res[k] = cb_mat4_determinant3(col) / det;
            }
        }
        p->bind_positions[j * 3] = (float)b.x, p->bind_positions[j * 3 + 1] = (float)b.y;
        p->bind_positions[j * 3 + 2] = (float)b.z;
    }
}

static void free_bake_state(bake_state *st)
{
    free(st->kept), free(st->breaks), free(st->errors), free(st->clip_error), free(st->clip_blend_error), free(st->ranges);
    free(st->encode_seconds);
}

/* The texels no row covers, which stay zero: in the last block the rows past the last baked
 * one. (Every row's texels are written by the encoder.) */
static void zero_padding(cb_palette *p)
{
    size_t tb = cb_precision_texel_bytes(p->precision);
    unsigned char *texels = p->texels;
    for (uint32_t y = 0; y < p->height; ++y) {
        uint32_t blocks_here = p->rows / p->height + (y < p->rows % p->height);
        size_t x0 = (size_t)blocks_here * p->row_texels;
        if (x0 < p->width) memset(texels + ((size_t)y * p->width + x0) * tb, 0, (p->width - x0) * tb);
    }
}

/* The first error in clip order, so the message does not depend on the thread count. */
static cb_status first_clip_error(const bake_state *st, cb_error *err)
{
    for (uint32_t c = 0; c < st->p->clip_count; ++c)
        if (st->errors[c].status) {
            *err = st->errors[c];
            return err->status;
        }
    return CB_OK;
}

static cb_status bake_once(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                           uint32_t plan_count, cb_palette *p, cb_error *err);

cb_status cb_palette_bake(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                          uint32_t plan_count, cb_palette *p, cb_error *err)
{
    cb_error first = {0};
    cb_status rc = bake_once(sampler, opt, plan, plan_count, p, &first);
    if (rc == CB_ERR_INPUT && opt->affine_fallback && opt->layout == CB_LAYOUT_QPOS && strstr(first.message, "qpos layout")) {
        cb_bake_options affine = *opt; /* a rig qpos cannot hold: the next smallest layout */
        affine.layout = CB_LAYOUT_AFFINE;
        rc = bake_once(sampler, &affine, plan, plan_count, p, err);
        if (!rc) snprintf(p->fallback_note, sizeof p->fallback_note, "%.460s; baked with affine instead", first.message);
        return rc;
    }
    if (rc) *err = err->status ? *err : first;
    return rc;
}

static cb_status bake_once(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                           uint32_t plan_count, cb_palette *p, cb_error *err)
{
    const cb_model *m = cb_sampler_model(sampler);
    int32_t skin_index = cb_sampler_skin(sampler);
    const cb_skin *skin = &m->skins[skin_index];
    memset(p, 0, sizeof *p);
    p->layout = opt->layout;
    p->precision = opt->precision;
    p->fitted = opt->fit;
    p->fps = opt->fps;
    p->bone_count = skin->joint_count;
    p->texels_per_bone = cb_layout_texels_per_bone(opt->layout);
    p->row_texels = p->bone_count * p->texels_per_bone;
    if (m->animation_count == 0 || (plan && plan_count == 0))
        return cb_fail(err, CB_ERR_INPUT, "%s: has no animations to bake (export the clips with the model)", m->source);
    double t0 = seconds_now();
    bake_state st = {0};
    st.p = p, st.model = m, st.skin = skin_index, st.opt = opt;
    cb_clip_info *infos = NULL;
    double *radius = NULL;
    if (frame_clips(&st, sampler, plan, plan_count, &infos, err) || plan_texture(p, opt->max_texture_size, m->source, err))
        goto fail;
    st.infos = infos;
    p->texel_bytes = (size_t)p->width * p->height * cb_precision_texel_bytes(p->precision);
    if (p->texel_bytes > opt->limits.max_palette_bytes) {
        cb_fail(err, CB_ERR_INPUT, "%s: the palette would be %zu bytes (%ux%u texels), over the limit of %llu "
                "(--max-palette-size); lower --fps, bake fewer clips or use a smaller encoding",
                m->source, p->texel_bytes, p->width, p->height, (unsigned long long)opt->limits.max_palette_bytes);
        goto fail;
    }
    p->texels = cb_alloc_large(p->texel_bytes);
    p->bind_positions = calloc((size_t)p->bone_count * 3, sizeof(float));
    p->position_offsets = calloc((size_t)p->bone_count * 3, sizeof(float));
    if (keeps_values(p))
        st.kept = cb_alloc_large((size_t)p->rows * p->bone_count * kept_floats(p->layout) * sizeof(float));
    for (uint32_t c = 0; c < p->clip_count; ++c)
        if (p->clips[c].frames > st.max_clip_frames) st.max_clip_frames = p->clips[c].frames;
    radius = malloc((size_t)p->bone_count * sizeof(double));
    st.breaks = calloc(p->clip_count, sizeof *st.breaks);
    st.errors = calloc(p->clip_count, sizeof *st.errors);
    st.clip_error = calloc(p->clip_count, sizeof *st.clip_error);
    st.clip_blend_error = calloc(p->clip_count, sizeof *st.clip_blend_error);
    st.ranges = calloc(p->clip_count, sizeof *st.ranges);
    st.encode_seconds = calloc(p->clip_count, sizeof *st.encode_seconds);
    if (!p->texels || !p->bind_positions || !p->position_offsets || (keeps_values(p) && !st.kept) || !radius ||
        !st.breaks || !st.errors || !st.clip_error || !st.clip_blend_error || !st.ranges || !st.encode_seconds) {
        cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for a %ux%u palette", m->source, p->width, p->height);
        goto fail;
    }
    zero_padding(p);
    bind_positions(p, skin);
    p->positions_relative = p->precision == CB_PRECISION_HALF;
    bool skinned = joint_reach(p, m, skin_index, radius);
    st.radius = radius;
    for_each_clip(&st, sample_clip_job, true);
    if (first_clip_error(&st, err)) goto fail;
    for (uint32_t c = 0; c < p->clip_count; ++c) p->quat_hemisphere_breaks += st.breaks[c];
    merge_ranges(p, st.ranges);
    if (p->positions_relative) position_offsets(p, st.kept);
    double t1 = seconds_now();
    if (st.kept) for_each_clip(&st, encode_kept_job, false);
    double t2 = seconds_now(), lo[3], hi[3];
    /* Clips encoded as they were sampled: their encoding time, spread over the threads, moves
     * from the sampling phase to the encoding phase. */
    double encoded_while_sampling = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) encoded_while_sampling += st.encode_seconds[c];
    encoded_while_sampling /= threads_used(&st);
    p->model_height = opt->error_goal > 0 ? 0 : cb_skin_rest_bounds(sampler, lo, hi); /* a search knows it */
    /* Exact skinning of every vertex at every row costs rows x vertices; past ~4M vertex-rows
     * an even subset of rows (always each clip's last) measures the error. */
    uint64_t work = (uint64_t)p->rows * cb_model_skin_vertex_count(m, skin_index);
    st.error_stride = work > CB_ERROR_BUDGET ? (uint32_t)((work + CB_ERROR_BUDGET - 1) / CB_ERROR_BUDGET) : 1;
    p->error_rows_measured = 0;
    st.weight_sum = cb_skin_max_weight_sum(m, skin_index);
    if (skinned) {
        for_each_clip(&st, measure_clip, true);
        if (first_clip_error(&st, err)) goto fail;
        for (uint32_t c = 0; c < p->clip_count; ++c) {
            p->max_error = fmax(p->max_error, st.clip_error[c]);
            p->visible_error = fmax(p->visible_error, fmax(st.clip_error[c], st.clip_blend_error[c]));
            p->error_rows_measured += (p->clips[c].frames + st.error_stride - 1) / st.error_stride +
                                      ((p->clips[c].frames - 1) % st.error_stride != 0);
        }
    }
    double t3 = seconds_now();
    p->seconds_sample = t1 - t0 - encoded_while_sampling;
    p->seconds_encode = t2 - t1 + encoded_while_sampling;
    p->seconds_measure = t3 - t2;
    free_bake_state(&st);
    free(radius), free(infos);
    return CB_OK;
fail:
    free_bake_state(&st);
    free(radius), free(infos);
    cb_palette_free(p);
    return err->status;
}
