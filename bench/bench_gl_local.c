/* bench_gl_local.c - see bench_gl_local.h. */
#include "bench_gl_local.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void bench_joint_parents(const cb_model *m, uint32_t skin, int32_t *parents, float *meta)
{
    const cb_skin *sk = &m->skins[skin];
    for (uint32_t j = 0; j < sk->joint_count; ++j) {
        parents[j] = -1;
        for (int32_t n = m->nodes[sk->joints[j]].parent; n >= 0 && parents[j] < 0; n = m->nodes[n].parent)
            for (uint32_t k = 0; k < sk->joint_count; ++k)
                if (sk->joints[k] == n) { parents[j] = (int32_t)k; break; }
        meta[j * 4] = (float)parents[j];
    }
    int depth_max = 0, depth_sum = 0;
    for (uint32_t j = 0; j < sk->joint_count; ++j) {
        int depth = 0;
        for (int32_t p = parents[j]; p >= 0; p = parents[p]) ++depth;
        depth_max = depth > depth_max ? depth : depth_max, depth_sum += depth;
    }
    fprintf(stderr, "bench_gl: %u bones, chains to the root %d deep at most, %.2f on average (ancestors a bone walks)\n",
            sk->joint_count, depth_max, (double)depth_sum / sk->joint_count);
}

static void quat_mul(const double a[4], const double b[4], double out[4])
{
    double r[4] = {a[3] * b[0] + b[3] * a[0] + a[1] * b[2] - a[2] * b[1], a[3] * b[1] + b[3] * a[1] + a[2] * b[0] - a[0] * b[2],
                   a[3] * b[2] + b[3] * a[2] + a[0] * b[1] - a[1] * b[0], a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2]};
    memcpy(out, r, sizeof r);
}

/* v rotated by the unit quaternion q: q v q*. */
static void quat_rotate(const double q[4], const double v[3], double out[3])
{
    double p[4] = {v[0], v[1], v[2], 0}, c[4] = {-q[0], -q[1], -q[2], q[3]}, t[4];
    quat_mul(q, p, t);
    quat_mul(t, c, t);
    memcpy(out, t, 3 * sizeof(double));
}

/* Joint j's local values (q 0-3, p 4-6, s 7) from its and its parent's decoded values (the shader's). */
static void local_values(const cb_palette *g, const double *vj, const double *vp, int32_t parent, double out[8])
{
    if (parent < 0) return (void)memcpy(out, vj, 8 * sizeof(double));
    double cq[4] = {-vp[0], -vp[1], -vp[2], vp[3]}, d[3] = {vj[4] - vp[4], vj[5] - vp[5], vj[6] - vp[6]}, r[3];
    quat_mul(cq, vj, out);
    quat_rotate(cq, d, r);
    for (int k = 0; k < 3; ++k) out[4 + k] = g->bind_positions[parent * 3 + k] + r[k] / vp[7];
    out[7] = vj[7] / vp[7];
}

static uint16_t unorm16(double x) { return (uint16_t)lround(fmin(fmax(x, 0.0), 1.0) * 65535.0); }
static uint16_t snorm16(double x) { return (uint16_t)(int16_t)lround(fmin(fmax(x, -1.0), 1.0) * 32767.0); }

/* Each bone's box of local positions and its largest local scale, over every row, into meta (cb_bind_positions rows
 * 3 and 4, the spec's bone range table: pos_min xyz, scale_max; pos_max xyz, 0). */
static void bone_ranges(const double *values, size_t count, uint32_t bones, float *meta)
{
    for (uint32_t j = 0; j < bones; ++j) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, scale = 0;
        for (size_t i = j; i < count; i += bones) {
            for (int k = 0; k < 3; ++k) lo[k] = fmin(lo[k], values[i * 8 + 4 + k]), hi[k] = fmax(hi[k], values[i * 8 + 4 + k]);
            scale = fmax(scale, values[i * 8 + 7]);
        }
        for (int k = 0; k < 3; ++k) meta[(bones + j) * 4 + k] = (float)lo[k], meta[(2 * bones + j) * 4 + k] = (float)hi[k];
        meta[(bones + j) * 4 + 3] = (float)scale;
    }
}

void bench_local_palette(const cb_palette *global, const int32_t *parents, cb_palette *local, float *meta)
{
    if (global->layout != CB_LAYOUT_QPOS || global->precision != CB_PRECISION_U16) {
        fprintf(stderr, "bench_gl: --local-rows needs a qpos/u16 palette (the default bake's)\n");
        exit(1);
    }
    uint32_t bones = global->bone_count;
    size_t count = (size_t)global->rows * bones;
    double *decoded = malloc(count * 16 * sizeof(double)), *values = malloc(count * 8 * sizeof(double));
    for (size_t i = 0; i < count; ++i)
        cb_palette_decode_values(global, global->texels, (uint32_t)(i / bones), (uint32_t)(i % bones), decoded + i * 16);
    for (size_t i = 0; i < count; ++i) {
        int32_t p = parents[i % bones];
        local_values(global, decoded + i * 16, p >= 0 ? decoded + (i - i % bones + (size_t)p) * 16 : NULL, p, values + i * 8);
    }
    bone_ranges(values, count, bones, meta);
    *local = *global;
    local->positions_relative = false;
    local->texels = calloc((size_t)global->width * global->height * 4, sizeof(uint16_t));
    for (size_t i = 0; i < count; ++i) {
        const double *o = values + i * 8;
        const float *lo = meta + (bones + i % bones) * 4, *hi = meta + (2 * bones + i % bones) * 4;
        uint32_t x, y;
        cb_palette_texel_xy(local, (uint32_t)(i / bones), (uint32_t)(i % bones), &x, &y);
        uint16_t *t = (uint16_t *)local->texels + ((size_t)y * local->width + x) * 4;
        for (int k = 0; k < 4; ++k) t[k] = snorm16(o[k]);
        for (int k = 0; k < 3; ++k) t[4 + k] = unorm16(hi[k] > lo[k] ? (o[4 + k] - lo[k]) / (hi[k] - lo[k]) : 0.0);
        t[7] = unorm16(lo[3] > 0 ? o[7] / lo[3] : 0.0);
    }
    free(decoded), free(values);
}
