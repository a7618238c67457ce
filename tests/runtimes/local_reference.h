/* local_reference.h - local rows (.pal version 6) done the spec's way in double precision, written
 * from /work/plan/notes8/local_spec.md ("What a runtime does") and not from any runtime: decode
 * each bone's rows (u16 with the bone's own ranges), blend them bone by bone (hemisphere flip,
 * nlerp, lerp), cross-fade the two clips' blended local rows the same way, then compose from the
 * root in a parent-first order built here (q_j = q_p q_L, s_j = s_p s_L, p_j = p_p + s_p
 * rotate(q_p, p_L - b_p)) and turn each bone into its skinning matrix. The HLSL tests hold the
 * shaders' cross-fades to it (the C runtime's cb_runtime_matrices has no cross-fade to compare
 * with) and its fade-free matrices to cb_runtime_matrices. Header-only, like testutil.h. */
#ifndef CB_LOCAL_REFERENCE_H
#define CB_LOCAL_REFERENCE_H

#include <math.h>
#include <stdint.h>

#include "crowdbake/runtime.h"

/* A bone as qpos: q (x, y, z, w) 0-3, p 4-6, s 7. */
typedef struct local_qpos {
    double v[8];
} local_qpos;

/* Row `row` of bone `bone`, decoded: float as is; u16 quaternions snorm, positions in the bone's
 * box (pos_min + (pos_max - pos_min) u / 65535) and scale scale_max u / 65535. */
static inline local_qpos local_row(const cb_palette *p, uint32_t row, uint32_t bone)
{
    local_qpos out;
    uint32_t x, y;
    cb_palette_texel_xy(p, row, bone, &x, &y);
    const float *range = p->bone_ranges + (size_t)bone * 8; /* pos_min[3], scale_max, pos_max[3], 0 */
    for (int k = 0; k < 2; ++k)
        for (int i = 0; i < 4; ++i) {
            size_t at = ((size_t)y * p->width + x + k) * 4 + i;
            if (p->precision != CB_PRECISION_U16) {
                out.v[k * 4 + i] = ((const float *)p->texels)[at];
                continue;
            }
            double u = ((const uint16_t *)p->texels)[at];
            out.v[k * 4 + i] = k == 0  ? fmax((u >= 32768 ? u - 65536 : u) / 32767.0, -1.0)
                               : i < 3 ? range[i] + (range[4 + i] - range[i]) * (u / 65535.0)
                                       : range[3] * u / 65535.0;
        }
    return out;
}

/* a and b blended with weight w on b: the quaternion the shorter way, renormalised. */
static inline local_qpos local_mix(local_qpos a, local_qpos b, double w)
{
    local_qpos o;
    double dot = a.v[0] * b.v[0] + a.v[1] * b.v[1] + a.v[2] * b.v[2] + a.v[3] * b.v[3], n = 0;
    for (int i = 0; i < 8; ++i) o.v[i] = a.v[i] + ((dot < 0 && i < 4 ? -b.v[i] : b.v[i]) - a.v[i]) * w;
    for (int i = 0; i < 4; ++i) n += o.v[i] * o.v[i];
    for (int i = 0; i < 4; ++i) o.v[i] /= sqrt(n);
    return o;
}

/* An instance's blended local row of a bone at `time`. */
static inline local_qpos local_blended(const cb_palette *p, const cb_instance *in, double time, uint32_t bone)
{
    uint32_t r0, r1;
    double fr;
    cb_runtime_frame(in, time, &r0, &r1, &fr);
    return local_mix(local_row(p, r0, bone), local_row(p, r1, bone), fr);
}

/* Parent's composed qpos (its bind position b) in front of a child's local one. */
static inline local_qpos local_compose(const local_qpos *a, const float b[3], const local_qpos *l)
{
    const double *q = a->v, *m = l->v;
    local_qpos o;
    double v[3] = {m[4] - b[0], m[5] - b[1], m[6] - b[2]}, n = 0;
    double t[3] = {2 * (q[1] * v[2] - q[2] * v[1]), 2 * (q[2] * v[0] - q[0] * v[2]), 2 * (q[0] * v[1] - q[1] * v[0])};
    double r[3] = {v[0] + q[3] * t[0] + q[1] * t[2] - q[2] * t[1], v[1] + q[3] * t[1] + q[2] * t[0] - q[0] * t[2],
                   v[2] + q[3] * t[2] + q[0] * t[1] - q[1] * t[0]};
    o.v[0] = q[3] * m[0] + m[3] * q[0] + q[1] * m[2] - q[2] * m[1];
    o.v[1] = q[3] * m[1] + m[3] * q[1] + q[2] * m[0] - q[0] * m[2];
    o.v[2] = q[3] * m[2] + m[3] * q[2] + q[0] * m[1] - q[1] * m[0];
    o.v[3] = q[3] * m[3] - q[0] * m[0] - q[1] * m[1] - q[2] * m[2];
    for (int i = 0; i < 4; ++i) n += o.v[i] * o.v[i];
    for (int i = 0; i < 4; ++i) o.v[i] /= sqrt(n);
    for (int i = 0; i < 3; ++i) o.v[4 + i] = a->v[4 + i] + a->v[7] * r[i];
    o.v[7] = a->v[7] * m[7];
    return o;
}

/* Composes bone j (and, first, its ancestors) into composed[], done[] marking those finished: a
 * parent-first order whatever the bone order. */
static inline void local_compose_bone(const cb_palette *p, const local_qpos *local, local_qpos *composed, bool *done, uint32_t j)
{
    if (done[j]) return;
    int32_t parent = p->parents[j];
    if (parent < 0) composed[j] = local[j];
    else {
        local_compose_bone(p, local, composed, done, (uint32_t)parent);
        composed[j] = local_compose(&composed[parent], p->bind_positions + (size_t)parent * 3, &local[j]);
    }
    done[j] = true;
}

/* Every bone's skinning matrix (16 doubles, column-major) of `in` at `time`, cross-faded from
 * `from` by `fade` (1: `in` alone) through the local rows. */
static inline void local_matrices(const cb_palette *p, const cb_instance *in, const cb_instance *from, double fade, double time,
                                  double *out)
{
    uint32_t n = p->bone_count;
    local_qpos *local = malloc(n * sizeof *local), *composed = malloc(n * sizeof *composed);
    bool *done = calloc(n, sizeof *done);
    for (uint32_t j = 0; j < n; ++j) {
        local[j] = local_blended(p, in, time, j);
        if (fade < 1) local[j] = local_mix(local_blended(p, from, time, j), local[j], fade);
    }
    for (uint32_t j = 0; j < n; ++j) {
        local_compose_bone(p, local, composed, done, j);
        const double *c = composed[j].v, x = c[0], y = c[1], z = c[2], w = c[3], s = c[7];
        const float *b = p->bind_positions + (size_t)j * 3;
        double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y),
                       2 * (x * y - w * z), 1 - 2 * (x * x + z * z), 2 * (y * z + w * x),
                       2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)};
        double *m = out + (size_t)j * 16;
        memset(m, 0, 16 * sizeof *m);
        m[15] = 1;
        for (int k = 0; k < 9; ++k) m[k / 3 * 4 + k % 3] = s * r[k];
        for (int k = 0; k < 3; ++k) m[12 + k] = c[4 + k] - (m[k] * b[0] + m[4 + k] * b[1] + m[8 + k] * b[2]);
    }
    free(local), free(composed), free(done);
}

#endif
