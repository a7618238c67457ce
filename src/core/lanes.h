/* lanes.h - GCC's vector types for the batched loops (sampling, encoding, measuring: a batch's
 * CB_SAMPLE_BATCH frames as lanes) and the 4x4 transpose that turns rows of values into lanes.
 * Internal. */
#ifndef CB_LANES_H
#define CB_LANES_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "cb_math.h"
#include "crowdbake/core.h"

/* lrint's rounding (to nearest, ties to even) of an |x| < 2^51 without a call: x + 1.5 * 2^52 leaves
 * the integer in the double's low bits (the u16 encoders of palette_codec.c and local_rows.c). */
#define CB_ROUND_MAGIC 6755399441055744.0

#if defined(__GNUC__) /* GCC and clang: vector types and __builtin_shufflevector */
typedef double v4df __attribute__((vector_size(32)));
typedef int64_t v4di __attribute__((vector_size(32)));

/* Four rows of four values (r[l]: row l) as lanes i .. i + 3 of four values: out[c][i + l] =
 * r[l][c]. A 4x4 transpose in 8 shuffles, then four vector stores. (The vectors by pointer: by
 * value, 32-byte vectors change the calling convention of the clone without AVX.) */
static CB_CLONE_INLINE void cb_rows_to_lanes4(const v4df *r, double (*out)[CB_SAMPLE_BATCH], int i)
{
    v4df r0 = r[0], r1 = r[1], r2 = r[2], r3 = r[3];
    v4df t0 = __builtin_shufflevector(r0, r1, 0, 4, 2, 6), t1 = __builtin_shufflevector(r0, r1, 1, 5, 3, 7);
    v4df t2 = __builtin_shufflevector(r2, r3, 0, 4, 2, 6), t3 = __builtin_shufflevector(r2, r3, 1, 5, 3, 7);
    v4df x = __builtin_shufflevector(t0, t2, 0, 1, 4, 5), y = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    v4df z = __builtin_shufflevector(t0, t2, 2, 3, 6, 7), w = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
    memcpy(&out[0][i], &x, sizeof x), memcpy(&out[1][i], &y, sizeof y);
    memcpy(&out[2][i], &z, sizeof z), memcpy(&out[3][i], &w, sizeof w);
}

/* The 4x4 transpose alone: out[c][l] = r[l][c] (rows to lanes, or lanes back to rows). */
static CB_CLONE_INLINE void cb_transpose4(const v4df *r, v4df *out)
{
    v4df t0 = __builtin_shufflevector(r[0], r[1], 0, 4, 2, 6), t1 = __builtin_shufflevector(r[0], r[1], 1, 5, 3, 7);
    v4df t2 = __builtin_shufflevector(r[2], r[3], 0, 4, 2, 6), t3 = __builtin_shufflevector(r[2], r[3], 1, 5, 3, 7);
    out[0] = __builtin_shufflevector(t0, t2, 0, 1, 4, 5), out[1] = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    out[2] = __builtin_shufflevector(t0, t2, 2, 3, 6, 7), out[3] = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}

/* Four lanes at a time: x on every lane, a select by a mask (take's lanes from x, the others
 * from y), |x| (the sign bit cleared), and sqrt on each lane (a loop GCC turns into one vsqrtpd;
 * the vector by pointer, as above). */
#define CB_SPLAT4(x) ((v4df){x, x, x, x})
#define CB_SELECT4(take, x, y) ((v4df)(((v4di)(x) & (take)) | ((v4di)(y) & ~(take))))
#define CB_ABS4(x) ((v4df)((v4di)(x) & (v4di){INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX}))

static CB_CLONE_INLINE void cb_sqrt4(v4df *x)
{
    v4df r = *x;
    for (int i = 0; i < 4; ++i) r[i] = sqrt(r[i]);
    *x = r;
}

/* cb_quat_normalize over four lanes (a zero quaternion is the identity). */
static CB_CLONE_INLINE void cb_normalize4(v4df *q)
{
    v4df len2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], norm = len2;
    cb_sqrt4(&norm);
    v4df inv = CB_SPLAT4(1.0) / norm;
    v4di empty = len2 == CB_SPLAT4(0.0);
    #pragma GCC unroll 4
    for (int k = 0; k < 4; ++k) q[k] = CB_SELECT4(empty, CB_SPLAT4(k == 3 ? 1.0 : 0.0), q[k] * inv);
}

/* Vertex v of prim skinned with the joint matrices mats (cb_skin_positions's arithmetic in its
 * order): the matrices' four rows are the lanes, a column a 32-byte load, so an influence is
 * four multiplies and adds of vectors where the scalar code took twelve of each (the fourth
 * row, lane 3, is computed and dropped). Zero weights skipped as there. */
static CB_CLONE_INLINE void cb_skin_vertex(const cb_primitive *prim, uint32_t v, const double *mats, double r[3])
{
    const float *p = prim->positions + (size_t)v * 3;
    const v4df x = CB_SPLAT4((double)p[0]), y = CB_SPLAT4((double)p[1]), z = CB_SPLAT4((double)p[2]);
    v4df sum = {0, 0, 0, 0};
    for (int i = 0; i < 4; ++i) {
        double w = prim->weights[(size_t)v * 4 + i];
        if (w == 0) continue;
        const double *m = mats + (size_t)prim->joints[(size_t)v * 4 + i] * 16;
        v4df c0, c1, c2, c3;
        memcpy(&c0, m, 32), memcpy(&c1, m + 4, 32), memcpy(&c2, m + 8, 32), memcpy(&c3, m + 12, 32);
        sum = sum + CB_SPLAT4(w) * (c0 * x + c1 * y + c2 * z + c3);
    }
    r[0] = sum[0], r[1] = sum[1], r[2] = sum[2];
}
/* Values at .. at + n - 1 (n: 8 or 16) of the rows x[0 .. 3] as lanes: v[k][l] = x[l][at + k],
 * four values at a time by four 32-byte loads and a 4x4 transpose (cb_rows_to_lanes4's). */
static CB_CLONE_INLINE void load_lanes4(const double *const *x, size_t at, int n, v4df *v)
{
    #pragma GCC unroll 16
    for (int h = 0; h < n; h += 4) {
        v4df r0, r1, r2, r3;
        memcpy(&r0, x[0] + at + h, 32), memcpy(&r1, x[1] + at + h, 32);
        memcpy(&r2, x[2] + at + h, 32), memcpy(&r3, x[3] + at + h, 32);
        v4df t0 = __builtin_shufflevector(r0, r1, 0, 4, 2, 6), t1 = __builtin_shufflevector(r0, r1, 1, 5, 3, 7);
        v4df t2 = __builtin_shufflevector(r2, r3, 0, 4, 2, 6), t3 = __builtin_shufflevector(r2, r3, 1, 5, 3, 7);
        v[h] = __builtin_shufflevector(t0, t2, 0, 1, 4, 5), v[h + 1] = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
        v[h + 2] = __builtin_shufflevector(t0, t2, 2, 3, 6, 7), v[h + 3] = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
    }
}

/* cb_mat4_from_trs over four lanes: m[k] is element k, with m[12 .. 14] = t and the scale s on
 * all three axes (the constant elements, 0 and 1, are left out). */
static CB_CLONE_INLINE void trs4(const v4df *t, const v4df *q, const v4df *scale, v4df *m)
{
    const v4df s = *scale;
    const v4df one = CB_SPLAT4(1.0), two = CB_SPLAT4(2.0);
    v4df x = q[0], y = q[1], z = q[2], w = q[3];
    v4df xx = x * x, yy = y * y, zz = z * z;
    v4df xy = x * y, xz = x * z, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
    m[0] = (one - two * (yy + zz)) * s, m[1] = (two * (xy + wz)) * s, m[2] = (two * (xz - wy)) * s;
    m[4] = (two * (xy - wz)) * s, m[5] = (one - two * (xx + zz)) * s, m[6] = (two * (yz + wx)) * s;
    m[8] = (two * (xz + wy)) * s, m[9] = (two * (yz - wx)) * s, m[10] = (one - two * (xx + yy)) * s;
    m[12] = t[0], m[13] = t[1], m[14] = t[2];
}

/* Each lane's difference matrix into out + l * stride, from its 12 elements d (column c is
 * d[3c .. 3c + 2], then a 0): a transpose of shuffles and 32-byte stores a column. */
static CB_CLONE_INLINE void store_differences4(const v4df *d, double *out, size_t stride)
{
    const v4df zero = CB_SPLAT4(0.0);
    #pragma GCC unroll 16
    for (int c = 0; c < 4; ++c) {
        v4df r0 = d[3 * c], r1 = d[3 * c + 1], r2 = d[3 * c + 2];
        v4df t0 = __builtin_shufflevector(r0, r1, 0, 4, 2, 6), t1 = __builtin_shufflevector(r0, r1, 1, 5, 3, 7);
        v4df t2 = __builtin_shufflevector(r2, zero, 0, 4, 2, 6), t3 = __builtin_shufflevector(r2, zero, 1, 5, 3, 7);
        v4df l0 = __builtin_shufflevector(t0, t2, 0, 1, 4, 5), l1 = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
        v4df l2 = __builtin_shufflevector(t0, t2, 2, 3, 6, 7), l3 = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
        double *o = out + 4 * c;
        memcpy(o, &l0, 32), memcpy(o + stride, &l1, 32), memcpy(o + 2 * stride, &l2, 32), memcpy(o + 3 * stride, &l3, 32);
    }
}

/* cb_joint_error_terms over four lanes, from the differences' elements d (as store_differences4
 * takes them: D[4c + r] is d[3c + r]); `bind` is sqrt(bx^2 + by^2 + bz^2), the same for every
 * lane. Its operations in its order; its compares and selects as masks. *sum: at_bind +
 * slack_fixed. */
static CB_CLONE_INLINE void joint_error_terms4(const v4df *d, double bx, double by, double bz, double bind, v4df *terms,
                                               v4df *sum)
{
    const v4df x = CB_SPLAT4(bx), y = CB_SPLAT4(by), z = CB_SPLAT4(bz);
    v4df ex = d[0] * x + d[3] * y + d[6] * z + d[9];
    v4df ey = d[1] * x + d[4] * y + d[7] * z + d[10];
    v4df ez = d[2] * x + d[5] * y + d[8] * z + d[11];
    const v4df *c0 = d, *c1 = d + 3, *c2 = d + 6; /* columns of A */
    v4df g00 = c0[0] * c0[0] + c0[1] * c0[1] + c0[2] * c0[2], g11 = c1[0] * c1[0] + c1[1] * c1[1] + c1[2] * c1[2];
    v4df g22 = c2[0] * c2[0] + c2[1] * c2[1] + c2[2] * c2[2];
    v4df g01 = CB_ABS4(c0[0] * c1[0] + c0[1] * c1[1] + c0[2] * c1[2]);
    v4df g02 = CB_ABS4(c0[0] * c2[0] + c0[1] * c2[1] + c0[2] * c2[2]);
    v4df g12 = CB_ABS4(c1[0] * c2[0] + c1[1] * c2[1] + c1[2] * c2[2]);
    v4df r0 = g00 + g01 + g02, r1 = g01 + g11 + g12, r2 = g02 + g12 + g22;
    v4df r = CB_SELECT4(r0 > r1, r0, r1);
    v4df a = CB_SELECT4(r > r2, r, r2), t = d[9] * d[9] + d[10] * d[10] + d[11] * d[11], e = ex * ex + ey * ey + ez * ez;
    cb_sqrt4(&a), cb_sqrt4(&t), cb_sqrt4(&e);
    a = a * CB_SPLAT4(1 + 1e-9);
    terms[0] = e;
    terms[1] = a;
    terms[2] = CB_SPLAT4(1e-9) * (a * CB_SPLAT4(bind) + t);
    terms[3] = t;
    *sum = terms[0] + terms[2];
}
#else
static CB_CLONE_INLINE void cb_skin_vertex(const cb_primitive *prim, uint32_t v, const double *mats, double r[3])
{
    const float *p = prim->positions + (size_t)v * 3;
    double x = p[0], y = p[1], z = p[2];
    r[0] = r[1] = r[2] = 0;
    for (int i = 0; i < 4; ++i) {
        double w = prim->weights[(size_t)v * 4 + i];
        if (w == 0) continue;
        const double *m = mats + (size_t)prim->joints[(size_t)v * 4 + i] * 16;
        r[0] += w * (m[0] * x + m[4] * y + m[8] * z + m[12]);
        r[1] += w * (m[1] * x + m[5] * y + m[9] * z + m[13]);
        r[2] += w * (m[2] * x + m[6] * y + m[10] * z + m[14]);
    }
}
#endif

/* A joint's pivots over a batch's lanes of its similarities (q, t, s: x -> s rotate(q, x) + t),
 * b its bind position: p[k][i] = t + s rotate(q, b) (cb_quat_rotate written out), for the bake's
 * rows (palette_rows.c) and the local measurement's poses (local_rate.c) alike. */
static CB_CLONE_INLINE void cb_pivot_lanes(const double (*sim)[CB_SAMPLE_BATCH], const float *b, double (*p)[CB_SAMPLE_BATCH])
{
    const double(*q)[CB_SAMPLE_BATCH] = sim, (*t)[CB_SAMPLE_BATCH] = sim + 4, *s = sim[7];
    double bx = b[0], by = b[1], bz = b[2];
    for (int i = 0; i < CB_SAMPLE_BATCH; ++i) {
        double uvx = q[1][i] * bz - q[2][i] * by, uvy = q[2][i] * bx - q[0][i] * bz, uvz = q[0][i] * by - q[1][i] * bx;
        double uuvx = q[1][i] * uvz - q[2][i] * uvy, uuvy = q[2][i] * uvx - q[0][i] * uvz,
               uuvz = q[0][i] * uvy - q[1][i] * uvx;
        p[0][i] = t[0][i] + s[i] * (bx + 2 * (q[3][i] * uvx + uuvx));
        p[1][i] = t[1][i] + s[i] * (by + 2 * (q[3][i] * uvy + uuvy));
        p[2][i] = t[2][i] + s[i] * (bz + 2 * (q[3][i] * uvz + uuvz));
    }
}

#endif
