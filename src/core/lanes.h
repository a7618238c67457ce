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

#endif
