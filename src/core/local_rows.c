/* local_rows.c - local rows (.pal version 6, docs/pal-format.md "Local rows"): each bone's
 * transform in its parent's frame, which the runtime blends bone by bone and composes down the
 * skeleton. Blending local rows is the glTF's own interpolation (conjugated by constants), where
 * blending global rows cuts a swung child's arc as a chord.
 *
 * A local bake is a qpos bake in float whose rows are local: a clip sampled from the sampler's
 * lanes (a similarity rig's) local at once, each bone computed in double from the double poses
 * (local_rows_from_lanes); any other (a matrix rig's, a timed clip's kept rows) sampled global
 * and converted here in place, clip by clip on the bake's threads, each bone computed in double
 * from its row's floats. Each bone's value is stored as float (the float file's values), then,
 * for u16, those floats encoded in each bone's ranges. Its errors are then measured composed, as
 * the runtime plays it (cb_verify_clip through cb_runtime_matrices, which composes). */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h"
#include "crowdbake/runtime.h"
#include "internal/plumbing.h"
#include "lanes.h"
#include "local_pose.h"
#include "local_rate.h" /* local_palette_errors */
#include "palette_bake.h"
#include "pool.h"
#include "timed_rows.h"

#define B CB_SAMPLE_BATCH

void palette_local_parents(const cb_model *m, const cb_skin *skin, int32_t *parents)
{
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        parents[j] = -1;
        for (int32_t n = m->nodes[skin->joints[j]].parent; n >= 0 && parents[j] < 0; n = m->nodes[n].parent)
            for (uint32_t k = 0; k < skin->joint_count; ++k)
                if (skin->joints[k] == n) parents[j] = (int32_t)k;
    }
}

static cb_vec3 bind_of(const cb_palette *p, uint32_t bone)
{
    const float *b = p->bind_positions + (size_t)bone * 3;
    return (cb_vec3){b[0], b[1], b[2]};
}

static local_qpos qpos_of_values(const double v[8]) { return (local_qpos){{v[0], v[1], v[2], v[3]}, {v[4], v[5], v[6]}, v[7]}; }

static void values_of_qpos(local_qpos t, double v[16])
{
    cb_quat q = cb_quat_normalize(t.q);
    double out[8] = {q.x, q.y, q.z, q.w, t.p.x, t.p.y, t.p.z, t.s};
    memcpy(v, out, sizeof out);
}

/* One bone's local values at a row, or blended between two, as the runtime blends them. */
static local_qpos local_at(const cb_palette *p, const void *texels, uint32_t r0, uint32_t r1, double fr, uint32_t bone)
{
    double a[16], b[16];
    cb_palette_decode_values(p, texels, r0, bone, a);
    local_qpos t = qpos_of_values(a);
    if (r1 == r0 && fr == 0) return t.q = cb_quat_normalize(t.q), t;
    cb_palette_decode_values(p, texels, r1, bone, b);
    return local_qpos_blend(t, qpos_of_values(b), fr);
}

/* The bone's composed (global) values: its local transform composed with each ancestor's, walked
 * up the chain (a parent may come after its child in bone order). Composition is associative, so
 * the walk needs no stack. At most bone_count steps, whatever the table says. */
void palette_local_composed(const cb_palette *p, const void *texels, uint32_t r0, uint32_t r1, double fr, uint32_t bone,
                            double v[16])
{
    local_qpos acc = local_at(p, texels, r0, r1, fr, bone);
    int32_t a = p->parents[bone];
    for (uint32_t steps = 0; a >= 0 && (uint32_t)a < p->bone_count && steps < p->bone_count; ++steps) {
        acc = local_qpos_compose(local_at(p, texels, r0, r1, fr, (uint32_t)a), bind_of(p, (uint32_t)a), acc);
        a = p->parents[a];
    }
    values_of_qpos(acc, v);
}

/* Every bone's composed matrix at once (16 doubles a bone into out): each bone's local rows blended
 * once (and, in a cross-fade, blended from the other clip's by fade: local rows, as the spec's
 * runtimes fade them), then composed in passes, a bone once its parent is (as many passes as the
 * deepest chain), where composing each bone's chain alone blends every ancestor again. */
bool palette_local_matrices(const cb_palette *p, const void *texels, const palette_frame *to,
                            const palette_frame *from, double fade, double *out)
{
    local_qpos *pose = malloc((size_t)p->bone_count * sizeof *pose);
    unsigned char *done = calloc(p->bone_count ? p->bone_count : 1, 1);
    if (!pose || !done) return free(pose), free(done), false;
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        pose[j] = local_at(p, texels, to->row0, to->row1, to->fr, j);
        if (from) pose[j] = local_qpos_blend(local_at(p, texels, from->row0, from->row1, from->fr, j), pose[j], fade);
    }
    bool progress = true;
    for (uint32_t pass = 0; progress && pass <= p->bone_count; ++pass) {
        progress = false;
        for (uint32_t j = 0; j < p->bone_count; ++j) {
            int32_t a = p->parents[j];
            if (done[j] || (a >= 0 && !done[a])) continue;
            if (a >= 0) pose[j] = local_qpos_compose(pose[a], bind_of(p, (uint32_t)a), pose[j]);
            done[j] = 1, progress = true;
        }
    }
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        double v[16];
        values_of_qpos(pose[j], v);
        cb_palette_values_to_matrix(p, j, v, out + (size_t)j * 16);
    }
    free(pose), free(done);
    return true;
}

/* ---- local rows sampled: a batch of joint lanes, local at once ---- */

/* Four of a batch's lanes at a time where GCC's vectors are (one otherwise): the same operations
 * in the same order either way, so the same bits. Macros, not functions: a function returning a
 * 32-byte vector changes its calling convention in the clone without AVX. */
#if defined(__GNUC__)
typedef v4df lanes4;
typedef double lanes4_at __attribute__((vector_size(32), aligned(8), may_alias)); /* at any double */
typedef float floats4 __attribute__((vector_size(16)));
enum { WIDTH = 4 };
#define AT(x) ((lanes4)*(const lanes4_at *)(x))
#define PUT(x, v) (*(lanes4_at *)(x) = (v))
#define INVERSE(s) CB_SELECT4((s) != CB_SPLAT4(0.0), CB_SPLAT4(1.0) / (s), CB_SPLAT4(0.0))
/* Floats loaded as floats, then converted (GCC 12 fails to compile the conversion of a float
 * vector read in place, in the clone without AVX); by pointer, as above. */
static CB_CLONE_INLINE void at_float(lanes4 *out, const float *x)
{
    floats4 f;
    memcpy(&f, x, sizeof f);
    *out = __builtin_convertvector(f, lanes4);
}
static CB_CLONE_INLINE void put_float(float *x, const lanes4 *v)
{
    floats4 f = __builtin_convertvector(*v, floats4);
    memcpy(x, &f, sizeof f);
}
#define MIN4(a, b) CB_SELECT4((a) < (b), (a), (b))
#define MAX4(a, b) CB_SELECT4((a) > (b), (a), (b))
#else
typedef double lanes4;
enum { WIDTH = 1 };
#define AT(x) (*(x))
#define PUT(x, v) (*(x) = (v))
#define INVERSE(s) ((s) != 0 ? 1 / (s) : 0)
static void at_float(lanes4 *out, const float *x) { *out = *x; }
static void put_float(float *x, const lanes4 *v) { *x = (float)*v; }
#define MIN4(a, b) ((a) < (b) ? (a) : (b))
#define MAX4(a, b) ((a) > (b) ? (a) : (b))
#endif

/* One bone's local values over the batch's lanes into l (l[k][i + 1]: value k of lane i) from
 * its global qpos lanes g (q, the pivot p = t + s rotate(q, b), s) and its parent's pg, pb the
 * parent's bind position: local_qpos_localize's arithmetic. A root (pg NULL) keeps its own. */
static CB_CLONE_INLINE void bone_local_lanes(const double (*g)[B], const double (*pg)[B], const float *pb, double (*l)[B + 1])
{
    for (int i = 0; i < B; i += WIDTH) {
        if (!pg) {
            for (int k = 0; k < 8; ++k) PUT(&l[k][i + 1], AT(&g[k][i]));
            continue;
        }
        /* conj(q_p) rotating p_j - p_p (cb_quat_rotate), over s_p, about the parent's bind position */
        lanes4 ix = -AT(&pg[0][i]), iy = -AT(&pg[1][i]), iz = -AT(&pg[2][i]), iw = AT(&pg[3][i]), sp = AT(&pg[7][i]);
        lanes4 k = INVERSE(sp);
        lanes4 vx = AT(&g[4][i]) - AT(&pg[4][i]), vy = AT(&g[5][i]) - AT(&pg[5][i]), vz = AT(&g[6][i]) - AT(&pg[6][i]);
        lanes4 wx = iy * vz - iz * vy, wy = iz * vx - ix * vz, wz = ix * vy - iy * vx;
        lanes4 wwx = iy * wz - iz * wy, wwy = iz * wx - ix * wz, wwz = ix * wy - iy * wx;
        PUT(&l[4][i + 1], pb[0] + (vx + 2 * (iw * wx + wwx)) * k);
        PUT(&l[5][i + 1], pb[1] + (vy + 2 * (iw * wy + wwy)) * k);
        PUT(&l[6][i + 1], pb[2] + (vz + 2 * (iw * wz + wwz)) * k);
        PUT(&l[7][i + 1], AT(&g[7][i]) * k);
        /* conj(q_p) q_j (cb_quat_mul) */
        lanes4 qx = AT(&g[0][i]), qy = AT(&g[1][i]), qz = AT(&g[2][i]), qw = AT(&g[3][i]);
        PUT(&l[0][i + 1], iw * qx + ix * qw + iy * qz - iz * qy);
        PUT(&l[1][i + 1], iw * qy - ix * qz + iy * qw + iz * qx);
        PUT(&l[2][i + 1], iw * qz + ix * qy - iy * qx + iz * qw);
        PUT(&l[3][i + 1], iw * qw - ix * qx - iy * qy - iz * qz);
    }
}

/* Grows a bone's range (lo[3], hi[3], scale max) by its local floats v of the batch's lanes (those
 * past count repeat the last frame's), WIDTH lanes at once, then folded in lane order. */
static CB_CLONE_INLINE void grow_range(const float (*v)[B], double *e)
{
    lanes4 lo[3], hi[3], smax, x;
    at_float(&smax, &v[7][0]);
    for (int k = 0; k < 3; ++k) at_float(&lo[k], &v[4 + k][0]), hi[k] = lo[k];
    for (int i = WIDTH; i < B; i += WIDTH) {
        for (int k = 0; k < 3; ++k) {
            at_float(&x, &v[4 + k][i]);
            lo[k] = MIN4(x, lo[k]), hi[k] = MAX4(x, hi[k]);
        }
        at_float(&x, &v[7][i]);
        smax = MAX4(x, smax);
    }
    double t[WIDTH];
    for (int k = 0; k < 3; ++k) {
        PUT(t, lo[k]);
        for (int m = 0; m < WIDTH; ++m) e[k] = t[m] < e[k] ? t[m] : e[k];
        PUT(t, hi[k]);
        for (int m = 0; m < WIDTH; ++m) e[3 + k] = t[m] > e[3 + k] ? t[m] : e[3 + k];
    }
    PUT(t, smax);
    for (int m = 0; m < WIDTH; ++m) e[6] = t[m] > e[6] ? t[m] : e[6];
}

/* w->prev holds each bone's last local quaternion (the global rows bone_lanes would have stored
 * are not made: joint_into_local). */
CB_TARGET_CLONES
void local_rows_from_lanes(bake_state *st, worker *w, uint32_t c, uint32_t f, uint32_t count, float *rows)
{
    const cb_palette *p = st->p;
    const local_sampling *ls = st->local;
    uint32_t bones = p->bone_count;
    const double(*lanes)[8][B] = (const double(*)[8][B])w->local_lanes;
    double *range = ls->ranges + (size_t)c * bones * 7;
    for (uint32_t j = 0; j < bones; ++j) {
        double l[8][B + 1], dot[B]; /* l: lane i at i + 1, after a zero (dot[0], unused, 0) */
        float v[8][B], sign[B];
        int32_t a = ls->parents[j];
        for (int k = 0; k < 8; ++k) l[k][0] = 0;
        bone_local_lanes(lanes[j], a >= 0 ? lanes[a] : NULL, a >= 0 ? p->bind_positions + (size_t)a * 3 : NULL, l);
        for (int i = 0; i < B; i += WIDTH) /* lane i against lane i - 1 as computed (palette_row_signs) */
            PUT(&dot[i], AT(&l[0][i + 1]) * AT(&l[0][i]) + AT(&l[1][i + 1]) * AT(&l[1][i]) +
                             AT(&l[2][i + 1]) * AT(&l[2][i]) + AT(&l[3][i + 1]) * AT(&l[3][i]));
        cb_quat q0 = {l[0][1], l[1][1], l[2][1], l[3][1]};
        palette_row_signs(dot, f ? cb_quat_dot(q0, w->prev[j]) < 0 : q0.w < 0, sign);
        for (int i = 0; i < B; i += WIDTH) { /* unrolled: GCC 12 kept a loop with a branch in it */
            lanes4 sg, x;
            at_float(&sg, &sign[i]);
            #pragma GCC unroll 4
            for (int k = 0; k < 4; ++k) x = sg * AT(&l[k][i + 1]), put_float(&v[k][i], &x);
            #pragma GCC unroll 4
            for (int k = 4; k < 8; ++k) x = AT(&l[k][i + 1]), put_float(&v[k][i], &x);
        }
        palette_store_rows((const float(*)[B])v, count, rows + (size_t)j * 8, (size_t)bones * 8);
        double *e = range + (size_t)j * 7;
        if (f == 0)
            for (int k = 0; k < 7; ++k) e[k] = k < 3 ? INFINITY : k < 6 ? -INFINITY : 0;
        grow_range((const float(*)[B])v, e);
        float last = sign[count - 1];
        w->prev[j] = (cb_quat){last * l[0][count], last * l[1][count], last * l[2][count], last * l[3][count]};
    }
}

/* ---- the conversion of a global float qpos palette, in place ---- */

/* The conversion, shared out clip by clip: each clip's rows not sampled local localized in place
 * (a float qpos texel pair holds a bone's 8 values, global before, local after) and its bones'
 * value ranges kept in its own slots, then, once every clip's ranges are merged, its rows
 * encoded. Each clip writes only its own rows and slots: the texels depend neither on the thread
 * count nor on the order taken. */
typedef struct convert_share {
    cb_palette *g;              /* float texels, global (those not sampled local), then local */
    unsigned char *out;         /* the encoded texels (u16), or NULL (float: the local floats are the texels) */
    double *ranges;             /* local_sampling's: clip c, bone j at ((c * bones) + j) * 7 */
    double *boxes;              /* the encode's, per bone: (pos_min, 0) and (pos_max, scale_max), the range table's
                                 * floats as doubles once, not at every row */
    const unsigned char *sampled; /* local_sampling's: clips already local, their ranges filled */
    unsigned char *out_of_memory; /* a clip's */
    bool encode;                /* the second run: encoding, not localizing */
    atomic_uint next;
} convert_share;

/* The index of row r's first texel: a row's bones lie side by side from it. */
static size_t row_texel(const cb_palette *g, uint32_t row)
{
    uint32_t x, y;
    cb_palette_texel_xy(g, row, 0, &x, &y);
    return (size_t)y * g->width + x;
}

/* Row r's float values, 8 a bone (RGBA32F: 16 bytes a texel). */
static float *float_row(const cb_palette *g, uint32_t row) { return (float *)g->texels + row_texel(g, row) * 4; }

static local_qpos qpos_of_floats(const float v[8])
{
    return (local_qpos){{v[0], v[1], v[2], v[3]}, {v[4], v[5], v[6]}, v[7]};
}

/* Clip c's rows localized: each bone's global values (a copy of its row's floats, as its children
 * still need them) in its parent's frame, its quaternion kept on the side of the row before's (in
 * double, before it is rounded; the clip's first row: w >= 0, as local_rows_from_lanes keeps it),
 * stored as floats over the global ones, its ranges grown. */
static bool localize_clip(convert_share *cs, uint32_t c)
{
    const cb_palette *g = cs->g;
    size_t bones = g->bone_count ? g->bone_count : 1;
    float *global = malloc(bones * 8 * sizeof *global);
    double *before = malloc(bones * 4 * sizeof *before), *range = cs->ranges + (size_t)c * g->bone_count * 7;
    if (!global || !before) return free(global), free(before), false;
    for (uint32_t j = 0; j < g->bone_count; ++j)
        for (int k = 0; k < 7; ++k) range[j * 7 + k] = k < 3 ? INFINITY : k < 6 ? -INFINITY : 0;
    for (uint32_t f = 0; f < g->clips[c].frames; ++f) {
        float *texel = float_row(g, g->clips[c].first_row + f);
        memcpy(global, texel, (size_t)g->bone_count * 8 * sizeof *global);
        for (uint32_t j = 0; j < g->bone_count; ++j, texel += 8) {
            local_qpos t = qpos_of_floats(global + (size_t)j * 8);
            int32_t a = g->parents[j];
            if (a >= 0) t = local_qpos_localize(qpos_of_floats(global + (size_t)a * 8), bind_of(g, (uint32_t)a), t);
            double w[8] = {t.q.x, t.q.y, t.q.z, t.q.w, t.p.x, t.p.y, t.p.z, t.s}, *q = before + (size_t)j * 4;
            if (f > 0 ? w[0] * q[0] + w[1] * q[1] + w[2] * q[2] + w[3] * q[3] < 0 : w[3] < 0)
                for (int k = 0; k < 4; ++k) w[k] = -w[k];
            memcpy(q, w, 4 * sizeof *w);
            double *e = range + (size_t)j * 7;
            for (int k = 0; k < 8; ++k) texel[k] = (float)w[k];
            for (int k = 0; k < 3; ++k) /* the floats' ranges: comparisons, not fmin's call (they are finite) */
                e[k] = texel[4 + k] < e[k] ? texel[4 + k] : e[k], e[3 + k] = texel[4 + k] > e[3 + k] ? texel[4 + k] : e[3 + k];
            e[6] = texel[7] > e[6] ? texel[7] : e[6];
        }
    }
    free(global), free(before);
    return true;
}

/* Each bone's range table entry (pos_min, scale_max, pos_max, 0) over every clip's rows, and the
 * header's informative union of them. */
static void local_ranges(cb_palette *p, const double *ranges)
{
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        float *e = p->bone_ranges + (size_t)j * 8;
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, smax = 0;
        for (uint32_t c = 0; c < p->clip_count; ++c) {
            const double *r = ranges + ((size_t)c * p->bone_count + j) * 7;
            for (int k = 0; k < 3; ++k) lo[k] = r[k] < lo[k] ? r[k] : lo[k], hi[k] = r[3 + k] > hi[k] ? r[3 + k] : hi[k];
            smax = r[6] > smax ? r[6] : smax;
        }
        for (int k = 0; k < 3; ++k) e[k] = p->rows ? (float)lo[k] : 0, e[4 + k] = p->rows ? (float)hi[k] : 0;
        e[3] = smax > 0 ? (float)smax : 1, e[7] = 0;
    }
    for (int k = 0; k < 3; ++k) p->bounds_min[k] = INFINITY, p->bounds_max[k] = -INFINITY;
    p->linear_range = 0;
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        const float *e = p->bone_ranges + (size_t)j * 8;
        for (int k = 0; k < 3; ++k)
            p->bounds_min[k] = fminf(p->bounds_min[k], e[k]), p->bounds_max[k] = fmaxf(p->bounds_max[k], e[4 + k]);
        p->linear_range = fmaxf(p->linear_range, e[3]);
    }
}

#if defined(__GNUC__) && defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
typedef float v4sf __attribute__((vector_size(16))); /* v4df and v4di: lanes.h */
typedef int16_t v16hi __attribute__((vector_size(32)));
typedef int16_t v8hi __attribute__((vector_size(16)));

/* One bone's 8 local floats into its two u16 texels, each bone in its own box (convert_share's
 * boxes): the quaternion snorm16, the position unorm16 over [lo, hi] and the scale over [0, scale
 * max], four lanes at a time: the scalar version's operations in its order, and lrint's rounding
 * (ties to even) by adding 1.5 * 2^52, which leaves the integer in the double's low bits. The
 * same bits. (The floats are loaded as floats and converted: GCC 12 without AVX fails to compile
 * a double vector built from float elements.) */
static CB_CLONE_INLINE void encode_bone_u16(const float *v, const double *box, unsigned char *d)
{
    v4sf qf, xf;
    v4df lo, hi;
    memcpy(&qf, v, sizeof qf), memcpy(&xf, v + 4, sizeof xf), memcpy(&lo, box, sizeof lo), memcpy(&hi, box + 4, sizeof hi);
    v4df q = __builtin_convertvector(qf, v4df), x = __builtin_convertvector(xf, v4df);
    v4df one = CB_SPLAT4(1.0), minus1 = CB_SPLAT4(-1.0), zero = CB_SPLAT4(0.0);
    v4di below = q < minus1, above = q > one, spans = hi > lo; /* all ones where true */
    q = CB_SELECT4(below, minus1, q), q = CB_SELECT4(above, one, q);
    v4df t = (x - lo) / (hi - lo);
    x = CB_SELECT4(spans, t, zero);
    below = x < zero, above = x > one;
    x = CB_SELECT4(below, zero, x), x = CB_SELECT4(above, one, x);
    v16hi a = (v16hi)(q * 32767.0 + CB_ROUND_MAGIC), b = (v16hi)(x * 65535.0 + CB_ROUND_MAGIC);
    v8hi m = __builtin_shufflevector(a, b, 0, 4, 8, 12, 16, 20, 24, 28); /* each double's low 16 bits */
    memcpy(d, &m, sizeof m);
}
#else
static void put16(unsigned char *d, long v) { d[0] = (unsigned char)(v & 0xff), d[1] = (unsigned char)((v >> 8) & 0xff); }

static long unorm16(double v, double lo, double hi)
{
    double x = hi > lo ? (v - lo) / (hi - lo) : 0;
    return lrint((x < 0 ? 0 : x > 1 ? 1 : x) * 65535);
}

static void encode_bone_u16(const float *v, const double *box, unsigned char *d)
{
    for (int i = 0; i < 4; ++i) put16(d + i * 2, lrint((v[i] < -1 ? -1 : v[i] > 1 ? 1 : (double)v[i]) * 32767));
    for (int k = 0; k < 4; ++k) put16(d + 8 + k * 2, unorm16(v[4 + k], box[k], box[4 + k]));
}
#endif

/* The range table's boxes as the encode reads them (convert_share's boxes). */
static void encode_boxes(const cb_palette *p, double *box)
{
    for (uint32_t j = 0; j < p->bone_count; ++j, box += 8) {
        const float *e = p->bone_ranges + (size_t)j * 8;
        for (int k = 0; k < 3; ++k) box[k] = e[k], box[4 + k] = e[4 + k];
        box[3] = 0, box[7] = e[3]; /* the scale's range: [0, scale max] */
    }
}

/* Clip c's local floats encoded u16 into the texels at out. */
CB_TARGET_CLONES
static void encode_clip(const convert_share *cs, uint32_t c)
{
    const cb_palette *p = cs->g;
    for (uint32_t r = p->clips[c].first_row; r < p->clips[c].first_row + p->clips[c].frames; ++r) {
        const float *v = float_row(p, r);
        unsigned char *d = cs->out + row_texel(p, r) * 8; /* RGBA16: 8 bytes a texel */
        for (uint32_t j = 0; j < p->bone_count; ++j, v += 8, d += 16) encode_bone_u16(v, cs->boxes + (size_t)j * 8, d);
    }
}

static void convert_clips(void *arg, uint32_t thread, uint32_t threads)
{
    (void)thread, (void)threads;
    convert_share *cs = arg;
    for (uint32_t c; (c = atomic_fetch_add(&cs->next, 1)) < cs->g->clip_count;) /* (a timed clip's map rows: no bone) */
        if (cs->encode) encode_clip(cs, c);
        else if (!cs->sampled[c]) cs->out_of_memory[c] = !localize_clip(cs, c);
}

static void run_convert(convert_share *cs, uint32_t threads)
{
    atomic_init(&cs->next, 0);
    threads = threads < 1 ? 1 : threads;
    cb_pool_run(threads > cs->g->clip_count ? cs->g->clip_count : threads, convert_clips, cs);
}

/* The float palette g (its clips sampled local and the others global) made local rows in
 * `precision`, on up to `threads` threads, about the parents it takes (*parents, NULL after). Its
 * texels are its own (palette_bake_local bakes it without texel memory): written over, and for
 * u16 replaced. */
static cb_status convert_palette(cb_palette *g, int32_t **parents, const local_sampling *ls, cb_precision precision,
                                 uint32_t threads, const char *source, cb_error *err)
{
    convert_share cs = {.g = g, .ranges = ls->ranges, .sampled = ls->sampled,
                        .out_of_memory = calloc(g->clip_count ? g->clip_count : 1, 1)};
    g->parents = *parents, *parents = NULL;
    g->bone_ranges = calloc((size_t)g->bone_count * 8, sizeof *g->bone_ranges);
    bool ok = cs.out_of_memory && g->bone_ranges;
    if (ok) {
        run_convert(&cs, threads);
        for (uint32_t c = 0; c < g->clip_count; ++c) ok = ok && !cs.out_of_memory[c];
    }
    size_t out_bytes = (size_t)g->width * g->height * cb_precision_texel_bytes(precision);
    if (ok && precision != CB_PRECISION_FLOAT) {
        cs.out = calloc(out_bytes ? out_bytes : 1, 1);
        cs.boxes = malloc((size_t)(g->bone_count ? g->bone_count : 1) * 8 * sizeof *cs.boxes);
        ok = cs.out && cs.boxes;
    }
    if (ok) {
        local_ranges(g, cs.ranges);
        if (cs.out) {
            encode_boxes(g, cs.boxes);
            cs.encode = true;
            run_convert(&cs, threads);
            free(g->texels);
            g->texels = cs.out, g->texel_bytes = out_bytes;
        }
        g->precision = precision, g->bone_space = CB_BONE_SPACE_LOCAL;
    } else {
        free(cs.out);
    }
    free(cs.out_of_memory), free(cs.boxes);
    return ok ? CB_OK : cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for local rows", source);
}

/* One clip's errors measured composed (local_palette_errors), in its own slots. */
typedef struct clip_errors {
    double rows, between;
    uint32_t measured; /* rows */
    cb_error err;
} clip_errors;

/* The measurement of the clips, shared out clip by clip: each thread with its own sampler (a
 * sampler's loop state is the clip it measures), the first its caller's; each answer in its
 * clip's slot, so the errors depend neither on the thread count nor on the order taken. */
typedef struct measure_share {
    cb_sampler *s;
    const cb_clip_plan *plan;
    const palette_skin_facts *facts;
    const palette_probe *probe;
    const cb_palette *p;
    bool timed_only;
    uint32_t stride; /* the measuring budget's (palette.h) */
    clip_errors *out;
    atomic_uint next;
} measure_share;

static void measure_clips(void *arg, uint32_t thread, uint32_t threads)
{
    (void)threads;
    measure_share *ms = arg;
    const cb_model *m = cb_sampler_model(ms->s);
    cb_error fail = {0};
    cb_sampler *s = thread ? cb_sampler_create(m, cb_sampler_skin(ms->s), &fail) : ms->s;
    for (uint32_t c; (c = atomic_fetch_add(&ms->next, 1)) < ms->p->clip_count;) {
        if (ms->timed_only && !ms->p->clips[c].timed) continue;
        clip_errors *e = &ms->out[c];
        pose_cache *kept = ms->probe && ms->probe->clip_poses ? ms->probe->clip_poses[c] : NULL;
        if (!s) e->err = fail;
        else local_palette_errors(s, ms->facts, ms->p, c, ms->plan ? ms->plan[c].animation : (int32_t)c, kept, ms->stride,
                                  &e->rows, &e->between, &e->measured, &e->err);
    }
    if (thread) cb_sampler_free(s);
}

cb_status palette_measure_composed(cb_sampler *s, const cb_clip_plan *plan, const palette_skin_facts *facts,
                                   const palette_probe *probe, uint32_t threads, bool timed_only, uint32_t stride,
                                   cb_palette *p, cb_error *err)
{
    measure_share ms = {.s = s, .plan = plan, .facts = facts, .probe = probe, .p = p, .timed_only = timed_only,
                        .stride = stride ? stride : 1, .out = calloc(p->clip_count ? p->clip_count : 1, sizeof *ms.out)};
    if (!ms.out) return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory measuring its rows", cb_sampler_model(s)->source);
    atomic_init(&ms.next, 0);
    threads = threads < 1 ? 1 : threads;
    cb_pool_run(threads > p->clip_count ? p->clip_count : threads, measure_clips, &ms);
    for (uint32_t c = 0; c < p->clip_count && !err->status; ++c) { /* the first failure in clip order */
        const clip_errors *e = &ms.out[c];
        if (timed_only && !p->clips[c].timed) continue;
        if (e->err.status) {
            *err = e->err;
            break;
        }
        p->max_error = fmax(p->max_error, e->rows);
        p->clips[c].visible_error = fmax(e->rows, e->between);
        p->visible_error = fmax(p->visible_error, p->clips[c].visible_error);
        if (!timed_only) /* a timed clip's map rows as the file counts them (global_timed.c alike) */
            p->error_rows_measured += e->measured + (p->clips[c].timed ? p->clips[c].map_rows : 0);
    }
    free(ms.out);
    return err->status;
}

/* The errors measured composed: at every row (max_error) and at the quarter points between every
 * two (visible_error), on every skinned vertex group that can raise the worst, against the exact
 * pose (local_rate.c: the quarter points, where nlerp's lag peaks; the rows and midpoints the rate
 * search sampled read from its pose caches), on up to `threads` threads. Past the measuring budget
 * (palette_error_stride, as for global rows) an even subset, unless measure_all. */
static cb_status measure_local(cb_sampler *s, const cb_clip_plan *plan, const palette_skin_facts *facts,
                               const palette_probe *probe, const cb_bake_options *opt, cb_palette *p, cb_error *err)
{
    p->max_error = p->visible_error = 0;
    p->error_rows_measured = 0;
    uint32_t stride = palette_error_stride(p->rows, cb_model_skin_vertex_count(cb_sampler_model(s), cb_sampler_skin(s)),
                                           opt->measure_all);
    return palette_measure_composed(s, plan, facts, probe, opt->threads, false, stride, p, err);
}

/* What a local bake's float bake samples local (local_sampling): every clip but a timed one, whose
 * rows on its keys are kept from its global rows and then converted (timed_keep_rows). The parents
 * go to the palette (convert_palette); false: out of memory. */
static bool local_sampling_init(local_sampling *ls, int32_t **parents, const cb_model *m, int32_t skin,
                                const cb_clip_plan *plan, uint32_t plan_count)
{
    size_t clips = plan ? plan_count : m->animation_count, bones = m->skins[skin].joint_count;
    *parents = malloc((bones ? bones : 1) * sizeof **parents);
    *ls = (local_sampling){*parents, malloc((clips ? clips : 1) * (bones ? bones : 1) * 7 * sizeof(double)),
                           calloc(clips ? clips : 1, 1)};
    if (!*parents || !ls->ranges || !ls->sampled) return false;
    palette_local_parents(m, &m->skins[skin], *parents);
    for (size_t c = 0; c < clips; ++c) ls->sampled[c] = !(plan && plan[c].timed_rows);
    return true;
}

/* Its float bake, sampled local where it can be, then the rest converted and all encoded in
 * opt's precision (the affine fallback: global, baked again as asked). */
static cb_status bake_local_rows(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                                 uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                                 cb_palette *p, cb_error *err)
{
    const cb_model *m = cb_sampler_model(sampler);
    cb_bake_options global = *opt;
    global.bone_space = CB_BONE_SPACE_GLOBAL, global.precision = CB_PRECISION_FLOAT, global.fit = false;
    global.texel_memory = (cb_texel_memory){0}, global.error_goal = 0;
    cb_clip_plan *sampled = plan ? malloc(plan_count * sizeof *sampled) : NULL;
    int32_t *parents = NULL;
    local_sampling ls;
    bool room = local_sampling_init(&ls, &parents, m, cb_sampler_skin(sampler), plan, plan_count);
    if (!room || (plan && !sampled)) {
        free(sampled), free(parents), free(ls.ranges), free(ls.sampled);
        return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory for local rows", m->source);
    }
    for (uint32_t i = 0; sampled && i < plan_count; ++i) /* uniform: the timed rows are kept below, before converting */
        sampled[i] = plan[i], sampled[i].fit = false, sampled[i].timed_rows = 0, sampled[i].row_cells = NULL;
    /* The global rows' own errors are not the local rows': measured composed after, not here. */
    palette_skin_facts unmeasured = *facts;
    unmeasured.skinned = false;
    cb_status rc = palette_bake_sampled_local(sampler, &global, sampled, plan_count, &unmeasured, probe, &ls, p, err);
    free(sampled);
    if (!rc && p->layout != CB_LAYOUT_QPOS) { /* fell back to affine: a rig qpos cannot hold stays global, as asked */
        cb_palette_free(p);
        global = *opt, global.bone_space = CB_BONE_SPACE_GLOBAL;
        rc = palette_bake_with_facts(sampler, &global, plan, plan_count, facts, probe, p, err);
    } else if (!rc) {
        bool timed = timed_any(plan, plan_count);
        if (!(rc = timed ? timed_keep_rows(p, plan, opt->max_texture_size, m->source, err) : CB_OK) &&
            !(rc = convert_palette(p, &parents, &ls, opt->precision, opt->threads, m->source, err)) && timed)
            timed_fill_maps(p, plan);
        if (rc) cb_palette_free(p);
    }
    free(parents), free(ls.ranges), free(ls.sampled);
    return rc;
}

cb_status palette_bake_local(cb_sampler *sampler, const cb_bake_options *opt, const cb_clip_plan *plan,
                             uint32_t plan_count, const palette_skin_facts *facts, const palette_probe *probe,
                             cb_palette *p, cb_error *err)
{
    const cb_model *m = cb_sampler_model(sampler);
    if (!cb_holds_local_rows(opt->layout, opt->precision))
        return cb_fail(err, CB_ERR_SETTINGS, "%s: local rows need layout qpos and precision u16 or float (half's "
                       "2^-11 compounds down a chain); use layout qpos with precision u16, or bone space global",
                       m->source);
    palette_skin_facts own = {0};
    cb_status rc = facts ? CB_OK : palette_skin_facts_build(sampler, &own, err);
    if (!facts) facts = &own;
    if (!rc) rc = bake_local_rows(sampler, opt, plan, plan_count, facts, probe, p, err);
    if (!rc && p->bone_space == CB_BONE_SPACE_LOCAL && cb_model_skin_vertex_count(m, cb_sampler_skin(sampler)) > 0 &&
        (rc = measure_local(sampler, plan, facts, probe, opt, p, err)))
        cb_palette_free(p);
    palette_skin_facts_free(&own);
    return rc;
}
