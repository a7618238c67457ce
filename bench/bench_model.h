/* bench_model.h - what the model benchmarks (bench_att.c, bench_rows.c) share: the model and its
 * sampler loaded and a qpos palette baked from it (root motion kept: the glTF's own poses), each
 * failing in one line that names the benchmark; the model file's name for their JSON lines; a
 * rotation's quaternion; and the distance, vertex by vertex, between the skin under two sets of
 * joint matrices. */
#ifndef CB_BENCH_MODEL_H
#define CB_BENCH_MODEL_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "crowdbake/gltf.h"
#include "crowdbake/runtime.h"

typedef struct bench_model {
    cb_model *m;
    cb_sampler *s;
    const char *name; /* the file's name, without its folder */
    uint32_t vertices; /* the largest primitive's vertex count: the skinning scratch's size */
} bench_model;

static inline bench_model bench_load(const char *bench, const char *path)
{
    bench_model out = {NULL, NULL, strrchr(path, '/') ? strrchr(path, '/') + 1 : path, 0};
    cb_error err = {0};
    out.m = cb_gltf_load(path, NULL, &err);
    if (out.m) out.s = cb_sampler_create(out.m, 0, &err);
    if (!out.s) {
        fprintf(stderr, "%s: %s\n", bench, err.message);
        exit(1);
    }
    for (uint32_t i = 0; i < out.m->primitive_count; ++i)
        if (out.m->primitives[i].vertex_count > out.vertices) out.vertices = out.m->primitives[i].vertex_count;
    return out;
}

static inline void bench_free(bench_model *b)
{
    cb_sampler_free(b->s);
    cb_model_free(b->m);
}

/* A qpos palette of every clip at `fps`, root motion kept. */
static inline void bench_bake_qpos(const char *bench, cb_sampler *s, cb_precision precision, double fps, cb_palette *out)
{
    cb_bake_options o = cb_default_bake_options();
    o.layout = CB_LAYOUT_QPOS, o.precision = precision, o.fps = fps, o.root_motion = CB_ROOT_MOTION_KEEP;
    cb_error err = {0};
    if (cb_palette_bake(s, &o, NULL, 0, out, &err) != CB_OK) {
        fprintf(stderr, "%s: %s\n", bench, err.message);
        exit(1);
    }
}

/* The rotation of a column-major 4x4 (its 3x3's columns made unit; their lengths in len) as a
 * quaternion (x, y, z, w), unit up to rounding. */
static inline void bench_quat_of(const double *g, double q[4], double len[3])
{
    double r[9]; /* r[col * 3 + row] */
    for (int c = 0; c < 3; ++c) {
        len[c] = sqrt(g[c * 4] * g[c * 4] + g[c * 4 + 1] * g[c * 4 + 1] + g[c * 4 + 2] * g[c * 4 + 2]);
        for (int k = 0; k < 3; ++k) r[c * 3 + k] = g[c * 4 + k] / len[c];
    }
    double t = r[0] + r[4] + r[8];
    if (t > 0) {
        double s = sqrt(t + 1) * 2;
        q[3] = s / 4, q[0] = (r[5] - r[7]) / s, q[1] = (r[6] - r[2]) / s, q[2] = (r[1] - r[3]) / s;
    } else if (r[0] > r[4] && r[0] > r[8]) {
        double s = sqrt(1 + r[0] - r[4] - r[8]) * 2;
        q[3] = (r[5] - r[7]) / s, q[0] = s / 4, q[1] = (r[3] + r[1]) / s, q[2] = (r[6] + r[2]) / s;
    } else if (r[4] > r[8]) {
        double s = sqrt(1 + r[4] - r[0] - r[8]) * 2;
        q[3] = (r[6] - r[2]) / s, q[0] = (r[3] + r[1]) / s, q[1] = s / 4, q[2] = (r[7] + r[5]) / s;
    } else {
        double s = sqrt(1 + r[8] - r[0] - r[4]) * 2;
        q[3] = (r[1] - r[3]) / s, q[0] = (r[6] + r[2]) / s, q[1] = (r[7] + r[5]) / s, q[2] = s / 4;
    }
}

typedef struct bench_errors {
    double worst, sum;
    size_t count;
} bench_errors;

/* Skins every primitive of the skin with `mats` and with `exact` (into a and b: 3 doubles a vertex
 * of the largest primitive) and adds each vertex's distance between the two to e. */
static inline void bench_skin_errors(const cb_model *m, int32_t skin, const double *mats, const double *exact, double *a,
                                     double *b, bench_errors *e)
{
    for (uint32_t i = 0; i < m->primitive_count; ++i) {
        const cb_primitive *prim = &m->primitives[i];
        if (prim->skin != skin) continue;
        cb_skin_positions(prim, mats, a);
        cb_skin_positions(prim, exact, b);
        for (uint32_t v = 0; v < prim->vertex_count * 3; v += 3) {
            double d = hypot(hypot(a[v] - b[v], a[v + 1] - b[v + 1]), a[v + 2] - b[v + 2]);
            e->worst = fmax(e->worst, d), e->sum += d, e->count++;
        }
    }
}

#endif
