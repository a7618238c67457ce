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
 * Three blends are weighed, each with its own rows: the shipped one (global qpos); the same rows
 * blended as dual quaternions, whose pivots move on a screw instead of a chord; and local rows,
 * each joint's transform in its parent joint's frame, blended joint by joint and composed down the
 * skeleton (what a bone pass could do): between rows on the keys, the glTF's own interpolation.
 *
 *   bench_rows MODEL [MAX_ERROR_MM_PER_M]   a JSON line for the skin (joints, and those that skin no
 *                                           vertex), then one per clip: key intervals, the rows the map
 *                                           needs, the rows one key-aligned uniform rate needs,
 *                                           for each blend (dual_*, local_*) */
#include "bench_model.h"

enum { MOST_SPLITS = 16 }; /* an interval needing more counts as this many (the auto bake caps rates too) */

/* A joint in a row: its rotation, position and scale. Global rows (what the palette stores): the
 * position of its pivot and a uniform scale (s[0]); local rows: its transform in its parent
 * joint's frame, translation and scale per axis. */
typedef struct qpos {
    double q[4], p[3], s[3];
} qpos;

typedef struct rig rig;
/* How a runtime would store rows and blend two of them (into r->blended). */
typedef struct blend_kind {
    void (*sample)(rig *r, int32_t anim, double t, qpos *row);
    void (*blend)(rig *r, const qpos *x, const qpos *y, double f);
} blend_kind;

struct rig {
    cb_model *m;
    cb_sampler *s;
    uint32_t bones;
    const float *bind;   /* 3 per bone: the qpos pivots */
    double height;
    double *exact, *blended, *a, *b; /* bones x 16 matrices; vertex scratch */
    size_t vertices;
    const int32_t *parent; /* each joint's nearest ancestor joint, or -1 */
    double *composed;      /* bones x 16: local rows composed to globals */
    blend_kind kind;
};

/* A column-major joint matrix as qpos about the pivot b: rotation, p = M b, uniform scale. */
static qpos qpos_of(const double *g, const float *b)
{
    qpos out;
    double len[3];
    bench_quat_of(g, out.q, len);
    out.s[0] = (len[0] + len[1] + len[2]) / 3;
    for (int k = 0; k < 3; ++k) out.p[k] = g[k] * b[0] + g[4 + k] * b[1] + g[8 + k] * b[2] + g[12 + k];
    return out;
}

/* The rotation of a unit quaternion (x, y, z, w), column-major. */
static void quat_rotation(const double *q, double *r)
{
    double X = q[0], Y = q[1], Z = q[2], W = q[3];
    double m[9] = {1 - 2 * (Y * Y + Z * Z), 2 * (X * Y + Z * W), 2 * (X * Z - Y * W),
                   2 * (X * Y - Z * W), 1 - 2 * (X * X + Z * Z), 2 * (Y * Z + X * W),
                   2 * (X * Z + Y * W), 2 * (Y * Z - X * W), 1 - 2 * (X * X + Y * Y)};
    memcpy(r, m, sizeof m);
}

/* The joint matrix v' = p + s R (v - b), R from the unit quaternion q. */
static void pivot_matrix(const double *q, const double *p, double s, const float *b, double *g)
{
    double r[9];
    quat_rotation(q, r);
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) g[c * 4 + k] = s * r[c * 3 + k];
    for (int k = 0; k < 3; ++k) g[12 + k] = p[k] - (g[k] * b[0] + g[4 + k] * b[1] + g[8 + k] * b[2]);
    g[3] = g[7] = g[11] = 0, g[15] = 1;
}

/* The quaternion product a b. */
static void quat_mul(const double *a, const double *b, double *out)
{
    out[0] = a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1];
    out[1] = a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0];
    out[2] = a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3];
    out[3] = a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2];
}

/* The runtime's blend of two rows (q1 flipped into q0's hemisphere), as a joint matrix: the
 * rotation nlerped, the pivot's position and the scale lerped: v' = p + s R (v - b). A child
 * joint swung by its parent moves on an arc; this blend cuts it as a chord. */
static void blend_qpos(const qpos *x, const qpos *y, double f, const float *b, double *g)
{
    double d = x->q[0] * y->q[0] + x->q[1] * y->q[1] + x->q[2] * y->q[2] + x->q[3] * y->q[3], q[4], p[3], n = 0;
    for (int k = 0; k < 4; ++k) q[k] = x->q[k] + f * ((d < 0 ? -y->q[k] : y->q[k]) - x->q[k]), n += q[k] * q[k];
    for (int k = 0; k < 4; ++k) q[k] /= sqrt(n);
    for (int k = 0; k < 3; ++k) p[k] = x->p[k] + f * (y->p[k] - x->p[k]);
    pivot_matrix(q, p, x->s[0] + f * (y->s[0] - x->s[0]), b, g);
}

/* A row as a unit dual quaternion of its rigid part about the pivot, u -> R u + (p - R b): the
 * real part q, the dual part (t, 0) q / 2. */
static void dual_of(const qpos *x, const float *b, double *dual)
{
    double r[9], t[4] = {0, 0, 0, 0};
    quat_rotation(x->q, r);
    for (int k = 0; k < 3; ++k) t[k] = x->p[k] - (r[k] * b[0] + r[3 + k] * b[1] + r[6 + k] * b[2]);
    quat_mul(t, x->q, dual);
    for (int k = 0; k < 4; ++k) dual[k] *= 0.5;
}

/* A blend that follows the arc (weighed here, no runtime has it): the rows' rigid parts blended as
 * dual quaternions (linear, normalized: a screw motion between them), the scale lerped about the
 * pivot: v' = R (b + s (v - b)) + t. */
static void blend_dual(const qpos *x, const qpos *y, double f, const float *b, double *g)
{
    double d = x->q[0] * y->q[0] + x->q[1] * y->q[1] + x->q[2] * y->q[2] + x->q[3] * y->q[3];
    double sign = d < 0 ? -1 : 1, dx[4], dy[4], q[4], e[4], n = 0;
    dual_of(x, b, dx), dual_of(y, b, dy);
    for (int k = 0; k < 4; ++k) {
        q[k] = (1 - f) * x->q[k] + f * sign * y->q[k];
        e[k] = (1 - f) * dx[k] + f * sign * dy[k];
        n += q[k] * q[k];
    }
    n = sqrt(n);
    for (int k = 0; k < 4; ++k) q[k] /= n, e[k] /= n;
    double conj[4] = {-q[0], -q[1], -q[2], q[3]}, t[4];
    quat_mul(e, conj, t); /* the translation is twice the vector part of e q* */
    double r[9], s = x->s[0] + f * (y->s[0] - x->s[0]), pivot[3];
    quat_rotation(q, r);
    for (int k = 0; k < 3; ++k) pivot[k] = 2 * t[k] + r[k] * b[0] + r[3 + k] * b[1] + r[6 + k] * b[2];
    pivot_matrix(q, pivot, s, b, g); /* R b + t is where the pivot goes */
}

static void sample_qpos(rig *r, int32_t anim, double t, qpos *out)
{
    cb_sample_joint_matrices(r->s, anim, t, r->exact);
    for (uint32_t j = 0; j < r->bones; ++j) out[j] = qpos_of(r->exact + j * 16, r->bind + j * 3);
}

static void blend_rows_chord(rig *r, const qpos *x, const qpos *y, double f)
{
    for (uint32_t j = 0; j < r->bones; ++j) blend_qpos(&x[j], &y[j], f, r->bind + j * 3, r->blended + j * 16);
}

static void blend_rows_dual(rig *r, const qpos *x, const qpos *y, double f)
{
    for (uint32_t j = 0; j < r->bones; ++j) blend_dual(&x[j], &y[j], f, r->bind + j * 3, r->blended + j * 16);
}

/* c = a b, column-major 4x4 affine. */
static void affine_mul(const double *a, const double *b, double *c)
{
    for (int col = 0; col < 4; ++col)
        for (int k = 0; k < 4; ++k)
            c[col * 4 + k] = a[k] * b[col * 4] + a[4 + k] * b[col * 4 + 1] + a[8 + k] * b[col * 4 + 2] + a[12 + k] * b[col * 4 + 3];
}

/* The inverse of a column-major 4x4 affine. */
static void affine_inverse(const double *m, double *out)
{
    double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
    double A = e * i - f * h, B = f * g - d * i, C = d * h - e * g, det = a * A + b * B + c * C;
    double inv[9] = {A / det, (c * h - b * i) / det, (b * f - c * e) / det, B / det, (a * i - c * g) / det,
                     (c * d - a * f) / det, C / det, (b * g - a * h) / det, (a * e - b * d) / det}; /* row-major */
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) out[col * 4 + row] = inv[row * 3 + col];
        out[12 + row] = -(inv[row * 3] * m[12] + inv[row * 3 + 1] * m[13] + inv[row * 3 + 2] * m[14]);
        out[row * 4 + 3] = 0;
    }
    out[15] = 1;
}

/* Local rows: each joint's transform in its parent joint's frame (a root joint's in the scene's),
 * as the glTF interpolates it. */
static void sample_local(rig *r, int32_t anim, double t, qpos *out)
{
    const cb_skin *skin = &r->m->skins[cb_sampler_skin(r->s)];
    const double *g = cb_sample_globals(r->s, anim, t);
    double inverse[16], local[16];
    for (uint32_t j = 0; j < r->bones; ++j) {
        const double *mine = g + 16 * (size_t)skin->joints[j];
        if (r->parent[j] < 0) {
            memcpy(local, mine, sizeof local);
        } else {
            affine_inverse(g + 16 * (size_t)skin->joints[r->parent[j]], inverse);
            affine_mul(inverse, mine, local);
        }
        bench_quat_of(local, out[j].q, out[j].s);
        memcpy(out[j].p, local + 12, sizeof out[j].p);
    }
}

/* Joint j's global from the blended local rows, its parents first (memoized in done). */
static const double *compose_joint(rig *r, const qpos *x, const qpos *y, double f, uint32_t j, bool *done)
{
    double *g = r->composed + 16 * (size_t)j;
    if (done[j]) return g;
    qpos l;
    double d = 0, n = 0, local[16];
    for (int k = 0; k < 4; ++k) d += x[j].q[k] * y[j].q[k];
    for (int k = 0; k < 4; ++k) l.q[k] = x[j].q[k] + f * ((d < 0 ? -y[j].q[k] : y[j].q[k]) - x[j].q[k]), n += l.q[k] * l.q[k];
    for (int k = 0; k < 4; ++k) l.q[k] /= sqrt(n);
    double rot[9];
    quat_rotation(l.q, rot);
    for (int c = 0; c < 3; ++c) {
        double s = x[j].s[c] + f * (y[j].s[c] - x[j].s[c]);
        for (int k = 0; k < 3; ++k) local[c * 4 + k] = s * rot[c * 3 + k];
        local[12 + c] = x[j].p[c] + f * (y[j].p[c] - x[j].p[c]);
        local[c * 4 + 3] = 0;
    }
    local[15] = 1;
    if (r->parent[j] < 0) memcpy(g, local, sizeof local);
    else affine_mul(compose_joint(r, x, y, f, (uint32_t)r->parent[j], done), local, g);
    done[j] = true;
    return g;
}

/* The runtime composes the skeleton from local rows blended joint by joint (nlerp, lerp): at rows
 * on the clip's keys, the glTF's own interpolation but for nlerp against slerp. */
static void blend_rows_local(rig *r, const qpos *x, const qpos *y, double f)
{
    const cb_skin *skin = &r->m->skins[cb_sampler_skin(r->s)];
    bool *done = calloc(r->bones, sizeof *done);
    for (uint32_t j = 0; j < r->bones; ++j)
        affine_mul(compose_joint(r, x, y, f, j, done), skin->inverse_bind + 16 * (size_t)j, r->blended + 16 * (size_t)j);
    free(done);
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
    r->kind.sample(r, anim, t0, x);
    r->kind.sample(r, anim, t1, y);
    double worst = 0;
    for (int k = 1; k < 4; ++k) {
        double f = k / 4.0;
        r->kind.blend(r, x, y, f);
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

/* The rows a clip needs under one blend: placed per key interval (a time -> row map; sampled, and
 * an estimate for fitted rows), and at one uniform rate on the shortest key step's grid. */
typedef struct clip_need {
    size_t map_rows, fitted_rows;
    double uniform_fps;
    uint32_t uniform_rows;
} clip_need;

static clip_need clip_needs(rig *r, int32_t anim, const cb_clip_info *info, const double *t, size_t n, double budget)
{
    qpos *x = malloc(r->bones * sizeof *x), *y = malloc(r->bones * sizeof *y);
    clip_need need = {.map_rows = info->loops ? 0 : 1, .fitted_rows = info->loops ? 0 : 1};
    int worst_splits = 1;
    size_t shortest = 1;
    for (size_t i = 0; i + 1 < n; ++i) {
        int k = splits_needed(r, anim, t[i], t[i + 1], budget, x, y);
        need.map_rows += (size_t)k;
        /* Fitted rows halve the blend's error (at best: 0.54-0.71 of it on Cow): an estimate. */
        need.fitted_rows += (size_t)splits_needed(r, anim, t[i], t[i + 1], 2 * budget, x, y);
        worst_splits = k > worst_splits ? k : worst_splits;
        if (t[i + 1] - t[i] < t[shortest] - t[shortest - 1]) shortest = i + 1;
    }
    need.uniform_fps = worst_splits / (t[shortest] - t[shortest - 1]);
    need.uniform_rows = cb_clip_step_count(info->duration, need.uniform_fps) + (info->loops ? 0 : 1);
    free(x), free(y);
    return need;
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
    r->kind = (blend_kind){sample_qpos, blend_rows_chord};
    clip_need chord = clip_needs(r, anim, &info, t, n, budget);
    r->kind = (blend_kind){sample_qpos, blend_rows_dual};
    clip_need arc = clip_needs(r, anim, &info, t, n, budget);
    r->kind = (blend_kind){sample_local, blend_rows_local};
    clip_need local = clip_needs(r, anim, &info, t, n, budget);
    uint32_t rows30 = cb_clip_step_count(info.duration, 30) + (info.loops ? 0 : 1);
    printf("{\"model\": \"%s\", \"clip\": \"%s\", \"key_intervals\": %zu, \"map_rows\": %zu, \"map_rows_fitted_estimate\": %zu, \"uniform_fps\": %.2f, "
           "\"uniform_rows\": %u, \"dual_map_rows\": %zu, \"dual_map_rows_fitted_estimate\": %zu, \"dual_uniform_fps\": %.2f, "
           "\"dual_uniform_rows\": %u, \"local_map_rows\": %zu, \"local_uniform_fps\": %.2f, \"local_uniform_rows\": %u, "
           "\"rows_30fps\": %u, \"bones\": %u}\n",
           model, a->name, n - 1, chord.map_rows, chord.fitted_rows, chord.uniform_fps, chord.uniform_rows, arc.map_rows,
           arc.fitted_rows, arc.uniform_fps, arc.uniform_rows, local.map_rows, local.uniform_fps, local.uniform_rows, rows30,
           r->bones);
    free(t);
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

/* Each joint's nearest ancestor that is a joint of the skin, or -1. */
static int32_t *joint_parents(const cb_model *m, int32_t skin_index)
{
    const cb_skin *skin = &m->skins[skin_index];
    int32_t *parent = malloc(skin->joint_count * sizeof *parent);
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        parent[j] = -1;
        for (int32_t n = m->nodes[skin->joints[j]].parent; n >= 0 && parent[j] < 0; n = m->nodes[n].parent)
            for (uint32_t k = 0; k < skin->joint_count; ++k)
                if (skin->joints[k] == n) parent[j] = (int32_t)k;
    }
    return parent;
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
    int32_t *parent = joint_parents(r.m, cb_sampler_skin(r.s));
    r.parent = parent, r.composed = malloc(r.bones * 16 * sizeof(double));
    printf("{\"model\": \"%s\", \"bones\": %u, \"bones_skinning_nothing\": %u}\n", model.name, r.bones,
           joints_skinning_nothing(&r));
    for (uint32_t c = 0; c < r.m->animation_count; ++c) clip_rows(&r, (int32_t)c, argc > 2 ? atof(argv[2]) : 1, model.name);
    free(r.exact), free(r.blended), free(r.a), free(r.b), free(parent), free(r.composed);
    cb_palette_free(&pal);
    bench_free(&model);
    return 0;
}
