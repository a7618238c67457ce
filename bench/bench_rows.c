/* bench_rows.c - where a palette's rows go, and what rows placed per key interval (a time -> row
 * map, issue 43) would need against one uniform rate per clip, each within the same budget.
 *
 * The runtime blends two rows of global qpos (nlerp of the rotation, lerp of the position and
 * scale), while the glTF interpolates each joint's local TRS: between two rows a child joint
 * moves on an arc that the blend cuts as a chord. That error falls as the square of the row
 * spacing, but it is not spread evenly: a kick or a landing errs where the body moves fast, the
 * rest of the clip barely. A uniform rate is set by the worst interval; rows placed per key
 * interval pay for each interval alone.
 *
 * For every key interval of every clip (the union of its channels' key times, and a loop's wrap
 * from its last key back to its first pose), this finds the fewest evenly spaced rows n that keep
 * the blend within the budget at the quarter points of every row interval, skinning every vertex
 * in float64 against the glTF's own skinning (no quantisation: u16 adds 0.03-0.05 mm/m on the
 * shared animals). Sampled rows; fitted rows would halve these errors. For LINEAR (and cubic)
 * keys: a STEP-keyed clip is baked as held rows, exact (docs/pal-format.md), not estimated here.
 * qpos only: a rig with non-uniform scale is refused as the bake refuses it.
 *
 *   bench_rows MODEL [MAX_ERROR_MM_PER_M]   a JSON line for the skin (joints, and those that skin no
 *                                           vertex), then one per clip: key intervals, the rows the map
 *                                           needs, the rows one key-aligned uniform rate needs */
#include "bench_model.h"

enum { MOST_SPLITS = 16 }; /* an interval needing more counts as this many (the auto bake caps rates too) */

typedef struct qpos {
    double q[4], p[3], s;
} qpos;

typedef struct rig {
    cb_model *m;
    cb_sampler *s;
    uint32_t bones;
    const float *bind;   /* 3 per bone: the qpos pivots */
    double height;
    double *exact, *blended, *a, *b; /* bones x 16 matrices; vertex scratch */
    size_t vertices;
} rig;

/* A column-major joint matrix as qpos about the pivot b: rotation, p = M b, uniform scale. */
static qpos qpos_of(const double *g, const float *b)
{
    qpos out;
    double len[3];
    bench_quat_of(g, out.q, len);
    out.s = (len[0] + len[1] + len[2]) / 3;
    for (int k = 0; k < 3; ++k) out.p[k] = g[k] * b[0] + g[4 + k] * b[1] + g[8 + k] * b[2] + g[12 + k];
    return out;
}

/* The runtime's blend of two rows (q1 flipped into q0's hemisphere), as a joint matrix:
 * v' = p + s R (v - b). */
static void blend_matrix(const qpos *x, const qpos *y, double f, const float *b, double *g)
{
    double d = x->q[0] * y->q[0] + x->q[1] * y->q[1] + x->q[2] * y->q[2] + x->q[3] * y->q[3], q[4], n = 0;
    for (int k = 0; k < 4; ++k) q[k] = x->q[k] + f * ((d < 0 ? -y->q[k] : y->q[k]) - x->q[k]), n += q[k] * q[k];
    n = sqrt(n);
    double X = q[0] / n, Y = q[1] / n, Z = q[2] / n, W = q[3] / n, s = x->s + f * (y->s - x->s);
    double r[9] = {1 - 2 * (Y * Y + Z * Z), 2 * (X * Y + Z * W), 2 * (X * Z - Y * W),
                   2 * (X * Y - Z * W), 1 - 2 * (X * X + Z * Z), 2 * (Y * Z + X * W),
                   2 * (X * Z + Y * W), 2 * (Y * Z - X * W), 1 - 2 * (X * X + Y * Y)}; /* column-major */
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) g[c * 4 + k] = s * r[c * 3 + k];
    for (int k = 0; k < 3; ++k) {
        double p = x->p[k] + f * (y->p[k] - x->p[k]);
        g[12 + k] = p - (g[k] * b[0] + g[4 + k] * b[1] + g[8 + k] * b[2]);
    }
    g[3] = g[7] = g[11] = 0, g[15] = 1;
}

static void sample_qpos(rig *r, int32_t anim, double t, qpos *out)
{
    cb_sample_joint_matrices(r->s, anim, t, r->exact);
    for (uint32_t j = 0; j < r->bones; ++j) out[j] = qpos_of(r->exact + j * 16, r->bind + j * 3);
}

/* The worst vertex distance between the skin under r->blended and under r->exact. */
static double skin_distance(rig *r)
{
    bench_errors e = {0};
    bench_skin_errors(r->m, cb_sampler_skin(r->s), r->blended, r->exact, r->a, r->b, &e);
    return e.worst;
}

/* The worst error of rows at t0 and t1 blended, at the quarter points between them. */
static double blend_error(rig *r, int32_t anim, double t0, double t1, qpos *x, qpos *y)
{
    sample_qpos(r, anim, t0, x);
    sample_qpos(r, anim, t1, y);
    double worst = 0;
    for (int k = 1; k < 4; ++k) {
        double f = k / 4.0;
        for (uint32_t j = 0; j < r->bones; ++j) blend_matrix(&x[j], &y[j], f, r->bind + j * 3, r->blended + j * 16);
        cb_sample_joint_matrices(r->s, anim, t0 + f * (t1 - t0), r->exact);
        worst = fmax(worst, skin_distance(r));
    }
    return worst;
}

/* The fewest even splits of [t0, t1] within the budget, MOST_SPLITS at most. */
static int splits_needed(rig *r, int32_t anim, double t0, double t1, double budget, qpos *x, qpos *y)
{
    for (int n = 1; n < MOST_SPLITS; ++n) {
        bool ok = true;
        for (int k = 0; ok && k < n; ++k) ok = blend_error(r, anim, t0 + (t1 - t0) * k / n, t0 + (t1 - t0) * (k + 1) / n, x, y) <= budget;
        if (ok) return n;
    }
    return MOST_SPLITS;
}

static int compare_times(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The clip's key times (every channel's, merged, within 0.1 ms), and the loop's end. */
static size_t key_times(const cb_animation *a, const cb_clip_info *info, double **out)
{
    size_t n = 0, total = 1;
    for (uint32_t c = 0; c < a->channel_count; ++c) total += a->channels[c].key_count;
    double *t = malloc(total * sizeof *t);
    for (uint32_t c = 0; c < a->channel_count; ++c)
        for (uint32_t k = 0; k < a->channels[c].key_count; ++k) t[n++] = a->channels[c].times[k];
    qsort(t, n, sizeof *t, compare_times);
    size_t m = 0;
    for (size_t i = 0; i < n; ++i)
        if (m == 0 || t[i] - t[m - 1] > 1e-4) t[m++] = t[i];
    if (m > 0 && info->loops && info->t0 + info->duration - t[m - 1] > 1e-4) t[m++] = info->t0 + info->duration;
    *out = t;
    return m;
}

static void clip_rows(rig *r, int32_t anim, double max_error_mm, const char *model)
{
    cb_error err = {0};
    cb_clip_info info;
    if (cb_clip_analyze(r->s, anim, 30, -1, NULL, &info, &err) != CB_OK || info.duration <= 0) return;
    const cb_animation *a = &r->m->animations[anim];
    double *t, budget = max_error_mm / 1000 * r->height;
    size_t n = key_times(a, &info, &t);
    if (n < 2) { /* no interval to place rows in */
        free(t);
        return;
    }
    qpos *x = malloc(r->bones * sizeof *x), *y = malloc(r->bones * sizeof *y);
    int worst_splits = 1;
    size_t map_rows = info.loops ? 0 : 1, fitted_rows = map_rows, shortest = 0;
    for (size_t i = 0; i + 1 < n; ++i) {
        int k = splits_needed(r, anim, t[i], t[i + 1], budget, x, y);
        map_rows += (size_t)k;
        /* Fitted rows halve the blend's error (at best: 0.54-0.71 of it on Cow): an estimate. */
        fitted_rows += (size_t)splits_needed(r, anim, t[i], t[i + 1], 2 * budget, x, y);
        worst_splits = k > worst_splits ? k : worst_splits;
        if (shortest == 0 || t[i + 1] - t[i] < t[shortest] - t[shortest - 1]) shortest = i + 1;
    }
    /* One uniform rate on the shortest key step's grid, split as the worst interval needs. */
    double uniform_fps = worst_splits / (t[shortest] - t[shortest - 1]);
    uint32_t uniform_rows = cb_clip_step_count(info.duration, uniform_fps) + (info.loops ? 0 : 1);
    uint32_t rows30 = cb_clip_step_count(info.duration, 30) + (info.loops ? 0 : 1);
    printf("{\"model\": \"%s\", \"clip\": \"%s\", \"key_intervals\": %zu, \"map_rows\": %zu, \"map_rows_fitted_estimate\": %zu, \"uniform_fps\": %.2f, "
           "\"uniform_rows\": %u, \"rows_30fps\": %u, \"bones\": %u}\n",
           model, a->name, n - 1, map_rows, fitted_rows, uniform_fps, uniform_rows, rows30, r->bones);
    free(x), free(y), free(t);
}

/* Joints no vertex of the skin is weighted to (leaf ends, IK targets): rows only for the joints
 * that skin (or carry a socket) would leave out their texels. */
static uint32_t joints_skinning_nothing(const rig *r)
{
    bool *used = calloc(r->bones, sizeof *used);
    for (uint32_t i = 0; i < r->m->primitive_count; ++i) {
        const cb_primitive *prim = &r->m->primitives[i];
        if (prim->skin != cb_sampler_skin(r->s)) continue;
        for (uint32_t k = 0; k < prim->vertex_count * 4; ++k)
            if (prim->weights[k] > 0 && prim->joints[k] < r->bones) used[prim->joints[k]] = true;
    }
    uint32_t unused = 0;
    for (uint32_t j = 0; j < r->bones; ++j) unused += !used[j];
    free(used);
    return unused;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_rows MODEL.glb [MAX_ERROR_MM_PER_M]\n");
        return 2;
    }
    bench_model model = bench_load("bench_rows", argv[1]);
    rig r = {.m = model.m, .s = model.s, .vertices = model.vertices};
    cb_palette pal = {0};
    bench_bake_qpos("bench_rows", r.s, CB_PRECISION_FLOAT, 2, &pal);
    r.bones = pal.bone_count, r.bind = pal.bind_positions, r.height = pal.model_height;
    r.exact = malloc(r.bones * 16 * sizeof(double)), r.blended = malloc(r.bones * 16 * sizeof(double));
    r.a = malloc(r.vertices * 3 * sizeof(double) + 1), r.b = malloc(r.vertices * 3 * sizeof(double) + 1);
    printf("{\"model\": \"%s\", \"bones\": %u, \"bones_skinning_nothing\": %u}\n", model.name, r.bones,
           joints_skinning_nothing(&r));
    for (uint32_t c = 0; c < r.m->animation_count; ++c) clip_rows(&r, (int32_t)c, argc > 2 ? atof(argv[2]) : 1, model.name);
    free(r.exact), free(r.blended), free(r.a), free(r.b);
    cb_palette_free(&pal);
    bench_free(&model);
    return 0;
}
