/* measure_lanes.c - see measure_lanes.h.
 *
 * Measuring a search's probes takes every bone of every measured row: exact less decoded,
 * then the difference's bound terms (Cow's default bake: 388 K bone-rows, 79 M instructions, at -O2
 * about 200 a bone, the blend, the normalisation and the differences one element at a time).
 * Here four rows are the lanes of GCC's vector types (lanes.h) and each lane runs the scalar
 * operations in their order - the blend, cb_quat_normalize's, cb_mat4_from_trs's, the
 * differences and cb_joint_error_terms's (selects for its compares, a lane's own branch) - so
 * its values are the same bits (speed43g: 79 -> 46 M on Cow, with the small loops unrolled so the
 * vectors stay in registers). Compilers without vector types take the same operations one lane
 * at a time. */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "cb_math.h"
#include "lanes.h" /* v4df, v4di */
#include "measure_lanes.h"

#define B CB_SAMPLE_BATCH

#if defined(__GNUC__)
/* load_lanes4, trs4, store_differences4 and joint_error_terms4: lanes.h (local_lanes.c takes them too). */

/* Lanes first .. first + 3 of palette_bone_differences: their differences stored, their terms
 * and sums (at_bind + slack_fixed) into terms[k][first ..] and sum[first ..]. */
static CB_CLONE_INLINE void differences4(const cb_palette *p, uint32_t j, const double (*sim)[B], const double *const *mats,
                                         const double *const *a, const double *const *b, double fr, int first,
                                         double *diff, double (*terms)[B], double *sum)
{
    v4df v[8], exact[16], decoded[15];
    load_lanes4(a + first, (size_t)j * 16, 8, v); /* the rows' values as lanes */
    if (b) {
        v4df w[8];
        load_lanes4(b + first, (size_t)j * 16, 8, w);
        v4df dot = v[0] * w[0] + v[1] * w[1] + v[2] * w[2] + v[3] * w[3]; /* the shorter way between the rows */
        v4df sign = CB_SELECT4(dot < CB_SPLAT4(0.0), CB_SPLAT4(-1.0), CB_SPLAT4(1.0)), keep = CB_SPLAT4(1 - fr), take = CB_SPLAT4(fr);
        #pragma GCC unroll 16
        for (int k = 0; k < 8; ++k) v[k] = v[k] * keep + (k < 4 ? sign * w[k] : w[k]) * take;
    }
    cb_normalize4(v); /* the quaternion */
    if (sim) {
        v4df s[8];
        #pragma GCC unroll 16
        for (int k = 0; k < 8; ++k) memcpy(&s[k], &sim[k][first], 32);
        trs4(s + 4, s, &s[7], exact);
    } else { /* (elements 3, 7, 11 and 15 are read by nothing a difference feeds: error_bound.h, skinning) */
        load_lanes4(mats + first, (size_t)j * 16, 16, exact);
    }
    trs4(v + 4, v, &v[7], decoded); /* t = p for now: t = p - A b below */
    const float *bind = p->bind_positions + (size_t)j * 3;
    double bx = bind[0], by = bind[1], bz = bind[2];
    const v4df x = CB_SPLAT4(bx), y = CB_SPLAT4(by), z = CB_SPLAT4(bz);
    decoded[12] = v[4] - (decoded[0] * x + decoded[4] * y + decoded[8] * z);
    decoded[13] = v[5] - (decoded[1] * x + decoded[5] * y + decoded[9] * z);
    decoded[14] = v[6] - (decoded[2] * x + decoded[6] * y + decoded[10] * z);
    v4df d[12]; /* the differences' elements 0-2, 4-6, 8-10, 12-14 (3, 7, 11, 15 are 0 - 0, 1 - 1) */
    #pragma GCC unroll 16
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r) d[3 * c + r] = exact[4 * c + r] - decoded[4 * c + r];
    size_t stride = (size_t)p->bone_count * 16;
    store_differences4(d, diff + (size_t)first * stride + (size_t)j * 16, stride);
    v4df t[4], total;
    joint_error_terms4(d, bx, by, bz, sqrt(bx * bx + by * by + bz * bz), t, &total);
    #pragma GCC unroll 16
    for (int k = 0; k < 4; ++k) memcpy(&terms[k][first], &t[k], 32);
    memcpy(sum + first, &total, 32);
}

CB_TARGET_CLONES
void palette_bone_differences(const cb_palette *p, uint32_t j, const double (*sim)[B], const double *const *mats,
                              const double *const *a, const double *const *b, uint32_t count, double fr, double *diff,
                              cb_joint_error *joints, bool *finite)
{
    double terms[4][B], sum[B];
    /* the lanes past count are read by nothing: only groups of four that hold a row are made */
    for (uint32_t first = 0; first < count; first += 4) differences4(p, j, sim, mats, a, b, fr, (int)first, diff, terms, sum);
    for (uint32_t i = 0; i < count; ++i) {
        size_t at = (size_t)i * p->bone_count + j;
        joints[at] = (cb_joint_error){terms[0][i], terms[1][i], terms[2][i], terms[3][i], diff + at * 16};
        finite[i] &= isfinite(sum[i]);
    }
}
#else
/* The scalar operations, one lane at a time. */
/* cb_mat4_from_trs over the lanes: m[k][i] is lane i's m[k], with m[12..14] = t and the
 * scale s on all three axes (the constant elements, 0 and 1, are left out). */
static CB_CLONE_INLINE void trs_lanes(double m[15][B], const double (*t)[B], const double (*q)[B], const double *s)
{
    for (int i = 0; i < B; ++i) {
        double x = q[0][i], y = q[1][i], z = q[2][i], w = q[3][i];
        double xx = x * x, yy = y * y, zz = z * z;
        double xy = x * y, xz = x * z, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
        m[0][i] = (1 - 2 * (yy + zz)) * s[i], m[1][i] = (2 * (xy + wz)) * s[i], m[2][i] = (2 * (xz - wy)) * s[i];
        m[4][i] = (2 * (xy - wz)) * s[i], m[5][i] = (1 - 2 * (xx + zz)) * s[i], m[6][i] = (2 * (yz + wx)) * s[i];
        m[8][i] = (2 * (xz + wy)) * s[i], m[9][i] = (2 * (yz - wx)) * s[i], m[10][i] = (1 - 2 * (xx + yy)) * s[i];
        m[12][i] = t[0][i], m[13][i] = t[1][i], m[14][i] = t[2][i];
    }
}
static CB_CLONE_INLINE void store_differences(const double (*d)[B], double *out, size_t stride)
{
    for (int i = 0; i < B; ++i)
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r) out[i * stride + 4 * c + r] = r < 3 ? d[3 * c + r][i] : 0;
}

static CB_CLONE_INLINE void values_to_lanes(const double *const *x, size_t at, int n, double (*v)[B])
{
    for (int i = 0; i < B; ++i)
        for (int k = 0; k < n; ++k) v[k][i] = x[i][at + k];
}

CB_TARGET_CLONES
void palette_bone_differences(const cb_palette *p, uint32_t j, const double (*sim)[B], const double *const *mats,
                              const double *const *a, const double *const *b, uint32_t count, double fr, double *diff,
                              cb_joint_error *joints, bool *finite)
{
    double v[8][B], exact[16][B], decoded[15][B], len2[B];
    values_to_lanes(a, (size_t)j * 16, 8, v); /* the rows' values as lanes */
    if (b) {
        double w[8][B];
        values_to_lanes(b, (size_t)j * 16, 8, w);
        double sign[B];
        for (int i = 0; i < B; ++i) { /* the shorter way between the rows */
            double dot = v[0][i] * w[0][i] + v[1][i] * w[1][i] + v[2][i] * w[2][i] + v[3][i] * w[3][i];
            sign[i] = dot < 0 ? -1 : 1;
        }
        for (int k = 0; k < 8; ++k)
            for (int i = 0; i < B; ++i) v[k][i] = v[k][i] * (1 - fr) + (k < 4 ? sign[i] * w[k][i] : w[k][i]) * fr;
    }
    double inv[B];
    for (int i = 0; i < B; ++i) { /* cb_quat_normalize: a zero quaternion is the identity */
        len2[i] = v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i] + v[3][i] * v[3][i];
        inv[i] = 1 / sqrt(len2[i]);
    }
    for (int k = 0; k < 4; ++k)
        for (int i = 0; i < B; ++i) v[k][i] = len2[i] == 0 ? (k == 3 ? 1 : 0) : v[k][i] * inv[i];
    if (sim) {
        trs_lanes(exact, sim + 4, sim, sim[7]);
    } else { /* (elements 3, 7, 11 and 15 are read by nothing a difference feeds: error_bound.h, skinning) */
        values_to_lanes(mats, (size_t)j * 16, 16, exact);
    }
    trs_lanes(decoded, v + 4, v, v[7]); /* t = p for now: t = p - A b below */
    const float *bind = p->bind_positions + (size_t)j * 3;
    double bx = bind[0], by = bind[1], bz = bind[2];
    for (int i = 0; i < B; ++i) {
        double abx = decoded[0][i] * bx + decoded[4][i] * by + decoded[8][i] * bz;
        double aby = decoded[1][i] * bx + decoded[5][i] * by + decoded[9][i] * bz;
        double abz = decoded[2][i] * bx + decoded[6][i] * by + decoded[10][i] * bz;
        decoded[12][i] = v[4][i] - abx, decoded[13][i] = v[5][i] - aby, decoded[14][i] = v[6][i] - abz;
    }
    double d[12][B]; /* the differences' elements 0-2, 4-6, 8-10, 12-14 (3, 7, 11, 15 are 0 - 0, 1 - 1) */
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 3; ++r)
            for (int i = 0; i < B; ++i) d[3 * c + r][i] = exact[4 * c + r][i] - decoded[4 * c + r][i];
    store_differences((const double(*)[B])d, diff + (size_t)j * 16, (size_t)p->bone_count * 16);
    /* Each row's bound terms for the bone (cb_joint_errors's, over the lanes). */
    double terms[4][B], sum[B];
    for (int i = 0; i < B; ++i) {
        double t[4], D[16] = {d[0][i], d[1][i], d[2][i],  0, d[3][i], d[4][i],  d[5][i],  0,
                              d[6][i], d[7][i], d[8][i], 0, d[9][i], d[10][i], d[11][i], 0};
        sum[i] = cb_joint_error_terms(D, bx, by, bz, t);
        terms[0][i] = t[0], terms[1][i] = t[1], terms[2][i] = t[2], terms[3][i] = t[3];
    }
    for (uint32_t i = 0; i < count; ++i) {
        size_t at = (size_t)i * p->bone_count + j;
        joints[at] = (cb_joint_error){terms[0][i], terms[1][i], terms[2][i], terms[3][i], diff + at * 16};
        finite[i] &= isfinite(sum[i]);
    }
}
#endif
