/* local_rate.c - see local_rate.h: a clip's rate for local rows, its key rate's lowest multiple
 * whose rows, blended and composed as the runtime does, stay within the error budget.
 *
 * Why these candidates: a local row is each bone's transform in its parent's frame, which is the
 * glTF node's own TRS conjugated by constants (the parent's bind and the bone's inverse bind). On
 * the clip's keys, lerping its position is the glTF's LINEAR translation exactly and nlerping its
 * rotation differs from the glTF's slerp only by nlerp's lag, which grows with the angle a key
 * step turns. So the key rate itself meets a millimetre per metre on most clips (bench_rows: every
 * clip of Cow and the fish) and twice it where single key steps turn far (Husky's Gallop, Fox's
 * Run): one or two probes a clip, each sampling the clip once.
 *
 * Why the quarter points: nlerp equals slerp at both rows and, by symmetry, halfway between them;
 * its lag peaks near a quarter of the way from either row. A measurement at the midpoints alone
 * would see only the lerp of the positions (exact on the keys) and miss nlerp's lag entirely. The
 * quarter points see both (bench_rows measures there too). The rows themselves are not measured:
 * composed from exact local rows they are the exact pose to rounding; the bake's own measurement
 * of the finished palette adds what quantisation costs.
 *
 * The poses are framed as the bake frames them (its root motion): an in-place bake takes the same
 * horizontal offset off every bone's global transform, which leaves every local row but the
 * root's unchanged and moves the root's linearly between rows (its lerp is exact), so the error
 * is the same within an interval; but a loop that keeps its travel ends away from its first row,
 * which its last interval blends into (probe). */
#include "local_rate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cb_math.h"
#include "error_bound.h"
#include "key_grid.h"
#include "lanes.h"
#include "local_lanes.h"
#include "local_pose.h"
#include "sampler.h"
#include "timed_rows.h"

/* ---- the skeleton ---- */

bool local_skeleton_build(const cb_model *m, int32_t skin, local_skeleton *out)
{
    const cb_skin *sk = &m->skins[skin];
    uint32_t n = sk->joint_count;
    memset(out, 0, sizeof *out);
    out->bones = n;
    out->parent = malloc((n ? n : 1) * sizeof *out->parent);
    out->order = malloc((n ? n : 1) * sizeof *out->order);
    uint32_t *depth = calloc(n ? n : 1, sizeof *depth);
    bool ok = out->parent && out->order && depth;
    if (ok) palette_local_parents(m, sk, out->parent); /* the .pal bone table's parents */
    uint32_t deepest = 0;
    for (uint32_t j = 0; ok && j < n; ++j) {
        for (int32_t a = out->parent[j]; a >= 0; a = out->parent[a]) ++depth[j];
        deepest = depth[j] > deepest ? depth[j] : deepest;
    }
    uint32_t k = 0; /* by depth: every parent before its children */
    for (uint32_t d = 0; ok && d <= deepest; ++d)
        for (uint32_t j = 0; j < n; ++j)
            if (depth[j] == d) out->order[k++] = j;
    free(depth);
    if (!ok) local_skeleton_free(out);
    return ok;
}

bool local_skeleton_roots(uint32_t bones, local_skeleton *out)
{
    out->bones = bones;
    out->parent = malloc((bones ? bones : 1) * sizeof *out->parent);
    out->order = malloc((bones ? bones : 1) * sizeof *out->order);
    if (!out->parent || !out->order) return local_skeleton_free(out), false;
    for (uint32_t j = 0; j < bones; ++j) out->parent[j] = -1, out->order[j] = j;
    return true;
}

void local_skeleton_free(local_skeleton *k)
{
    free(k->parent), free(k->order);
    memset(k, 0, sizeof *k);
}

/* ---- rows as the runtime blends and composes them ---- */

static cb_vec3 bind_of(const float *bind, uint32_t j)
{
    return (cb_vec3){bind[j * 3], bind[j * 3 + 1], bind[j * 3 + 2]};
}

/* The local row of every bone from the global ones (the spec's conversion, exact in double):
 *   q_L = conj(q_p) q_j,   s_L = s_j / s_p,   p_L = b_p + rotate(conj(q_p), p_j - p_p) / s_p. */
static void to_local(const local_skeleton *k, const float *bind, const local_qpos *global, local_qpos *local)
{
    for (uint32_t j = 0; j < k->bones; ++j) {
        int32_t p = k->parent[j];
        local[j] = p < 0 ? global[j] : local_qpos_localize(global[p], bind_of(bind, (uint32_t)p), global[j]);
    }
}

/* A joint matrix as a row about its pivot b: its rotation from the normalised columns, the
 * columns' mean length as the scale (qpos holds similarities; the bake refuses local rows for a
 * rig that is none). */
static local_qpos qpos_of_matrix(const double *m, cb_vec3 b)
{
    double unit[16], len[3];
    memcpy(unit, m, sizeof unit);
    for (int c = 0; c < 3; ++c) {
        len[c] = sqrt(m[c * 4] * m[c * 4] + m[c * 4 + 1] * m[c * 4 + 1] + m[c * 4 + 2] * m[c * 4 + 2]);
        for (int r = 0; r < 3; ++r) unit[c * 4 + r] = len[c] > 0 ? m[c * 4 + r] / len[c] : 0;
    }
    return (local_qpos){cb_quat_from_mat4(unit), cb_mat4_transform_point(m, b), (len[0] + len[1] + len[2]) / 3};
}

/* ---- a probe: the clip at one rate ---- */

/* Times sampled together: four row intervals, each its three quarter points and its end row. */
enum { POINTS = 4, INTERVALS_A_BATCH = CB_SAMPLE_BATCH / POINTS };

typedef struct probe_ctx {
    cb_sampler *s;
    const palette_skin_facts *facts;
    const local_skeleton *k;
    const cb_clip_info *clip;
    const cb_model *m;
    cb_root_motion root_motion; /* the bake's: its poses framed as the bake frames them */
    pose_cache *keep;         /* the bake's cache of this clip's poses, or NULL (matrix rigs only) */
    bool similar;             /* cb_sampler_is_similarity: sampled as similarities */
    bool not_qpos;            /* a pose had a joint that is no similarity (local_rate.not_qpos) */
    bool global_rows;         /* not similar: the poses' global rows wanted (the choice's, for its local rows) */
    bool kept[CB_SAMPLE_BATCH]; /* not similar: pose i is the cache's (its qpos derivation kept with it) */
    cb_joint_subset *all;     /* not similar: every joint, sampled a batch of times at once */
    double *lanes;            /* its lanes */
    double *pose_room;        /* CB_SAMPLE_BATCH x bones x 16: the poses no cache keeps */
    const double *mats[CB_SAMPLE_BATCH]; /* not similar: each pose's joint matrices */
    double *qs;               /* bones x 5: a pose's quaternions and scales (palette_qpos_similarity_pose) */
    local_qpos *poses;         /* CB_SAMPLE_BATCH x bones: global rows at a batch's times */
    local_qpos *rows;          /* (INTERVALS_A_BATCH + 1) x bones: the local rows that bound a batch's intervals */
    local_qpos *first_row;     /* bones: the clip's first row, where a loop's last interval ends */
    double *composed;         /* bones x 32: four points' blends composed, as lanes (local_points4) */
    double *diff;             /* 4 x bones x 16: each of four points' exact less blended */
    cb_joint_error *joints;   /* 4 x bones */
    double *values;           /* bones x 16: a palette row's values (palette_decode_row_values) */
    void *block;
} probe_ctx;

static void probe_ctx_free(probe_ctx *c)
{
    cb_joint_subset_free(c->all);
    free(c->block);
}

static bool probe_ctx_init(probe_ctx *c, cb_sampler *s, const palette_skin_facts *facts, const local_skeleton *k,
                           const cb_clip_info *clip, cb_root_motion root_motion, pose_cache *keep)
{
    size_t n = k->bones ? k->bones : 1;
    size_t sizes[] = {CB_SAMPLE_BATCH * n * sizeof(local_qpos), (INTERVALS_A_BATCH + 1) * n * sizeof(local_qpos),
                      n * sizeof(local_qpos), n * 32 * sizeof(double),
                      4 * n * 16 * sizeof(double), 4 * n * sizeof(cb_joint_error), n * 5 * sizeof(double),
                      (CB_SAMPLE_BATCH + 1) * (n * 16 + 1) * sizeof(double), CB_SAMPLE_BATCH * n * 16 * sizeof(double),
                      n * 16 * sizeof(double)};
    size_t total = 0;
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) total += (sizes[i] + 63) / 64 * 64;
    bool similar = cb_sampler_is_similarity(s);
    *c = (probe_ctx){.s = s, .facts = facts, .k = k, .clip = clip, .m = cb_sampler_model(s), .root_motion = root_motion,
                     .keep = similar ? NULL : keep, .similar = similar, .global_rows = true, .block = malloc(total + 63)};
    if (!c->block) return false;
    char *at = (char *)c->block + (64 - (uintptr_t)c->block % 64) % 64; /* every part 64-byte aligned: lanes */
    void **parts[] = {(void **)&c->poses, (void **)&c->rows, (void **)&c->first_row, (void **)&c->composed,
                      (void **)&c->diff, (void **)&c->joints, (void **)&c->qs,
                      (void **)&c->lanes, (void **)&c->pose_room, (void **)&c->values};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; ++i) *parts[i] = at, at += (sizes[i] + 63) / 64 * 64;
    if (similar) return true;
    bool *every = malloc(n * sizeof *every);
    for (uint32_t j = 0; every && j < k->bones; ++j) every[j] = true;
    c->all = every ? cb_joint_subset_create(s, every) : NULL;
    free(every);
    if (!c->all) probe_ctx_free(c);
    return c->all != NULL;
}

/* Pose i's global rows from its joint matrices (c->mats[i]): rotation and scale four joints at
 * a time (palette_qpos_similarity_pose, the bake's; a cached pose's derived once and kept with
 * it, where the bake's rows and later probes take it), the pivot's position p = M b. */
static void rows_of_matrices(probe_ctx *c, uint32_t i)
{
    uint32_t bones = c->k->bones;
    const float *bind = c->facts->bind_positions;
    const double *mats = c->mats[i];
    local_qpos *out = c->poses + (size_t)i * bones;
    const double *qs = c->kept[i] ? palette_kept_qpos(mats, bones)
                                  : palette_qpos_similarity_pose(mats, bones, c->qs) ? c->qs : NULL;
    if (!qs) { /* a joint no similarity: the bake falls back */
        c->not_qpos = true;
        for (uint32_t j = 0; j < bones; ++j) out[j] = qpos_of_matrix(mats + 16 * (size_t)j, bind_of(bind, j));
        return;
    }
    for (uint32_t j = 0; j < bones; ++j) {
        const double *q = qs + 5 * (size_t)j;
        out[j] = (local_qpos){{q[0], q[1], q[2], q[3]}, cb_mat4_transform_point(mats + 16 * (size_t)j, bind_of(bind, j)), q[4]};
    }
}

/* A similarity rig's poses as the sampler hands them over, joint by joint (cb_clip_frame_lanes_each):
 * each joint's global row, its pivot p = t + rotate(q, b) s over the lanes at once, into pose i
 * of c->poses for its first `count` lanes. */
typedef struct poses_in_making {
    probe_ctx *c;
    uint32_t count;
} poses_in_making;

CB_TARGET_CLONES
static void joint_into_poses(void *ctx, uint32_t j, double (*lanes)[CB_SAMPLE_BATCH])
{
    const poses_in_making *m = ctx;
    const double(*q)[CB_SAMPLE_BATCH] = (const double(*)[CB_SAMPLE_BATCH])lanes, *s = lanes[7];
    double p[3][CB_SAMPLE_BATCH];
    cb_pivot_lanes(q, m->c->facts->bind_positions + (size_t)j * 3, p);
    uint32_t bones = m->c->k->bones;
    for (uint32_t i = 0; i < m->count; ++i)
        m->c->poses[(size_t)i * bones + j] = (local_qpos){{q[0][i], q[1][i], q[2][i], q[3][i]}, {p[0][i], p[1][i], p[2][i]}, s[i]};
}

/* The global rows at `count` increasing frames of `framing` into c->poses, framed as the bake
 * frames them (its root motion). A matrix rig's poses at the frames `kept` says (the bake's rows
 * and the midpoints its measurement reads) go into the bake's pose cache, where the bake finds
 * them instead of sampling them again; poses the cache has already are read from it. */
static void sample_frames(probe_ctx *c, const cb_clip_info *framing, const uint32_t *frames, uint32_t count,
                          const bool *kept)
{
    uint32_t bones = c->k->bones;
    if (c->similar) { /* count <= CB_SAMPLE_BATCH: one batch */
        poses_in_making m = {c, count};
        cb_clip_frame_lanes_each(c->s, framing, frames, count, c->root_motion, joint_into_poses, &m);
        return;
    }
    uint32_t missing[CB_SAMPLE_BATCH], n = 0;
    double *room[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < count; ++i) {
        double t = cb_clip_frame_time(framing, frames[i]);
        const double *found = c->keep && kept[i] ? pose_cache_find(c->keep, t) : NULL;
        double *add = found || !c->keep || !kept[i] ? NULL : pose_cache_add(c->keep, t); /* NULL: full */
        if (!found) {
            room[n] = add ? add : c->pose_room + (size_t)i * bones * 16;
            missing[n++] = frames[i];
        }
        c->mats[i] = found ? found : room[n - 1];
        c->kept[i] = found || add;
    }
    if (n) cb_clip_frame_matrices_batch(c->s, framing, missing, n, c->root_motion, c->all, c->lanes, room);
    for (uint32_t i = 0; c->global_rows && i < count; ++i) rows_of_matrices(c, i);
}

/* A point measured: the local rows a and b blended by f against pose `pose` of the batch, its
 * worst error into *worst. */
typedef struct point {
    const local_qpos *a, *b;
    double f;
    uint32_t pose;
    double *worst;
} point;

/* The worst vertex error of lane l of local_points4 (c->joints, c->diff) against `worst`, or
 * `worst` when no vertex exceeds it; above `goal` it stops at the first group over it (any value
 * over the goal decides alike). Skinned only where a vertex group's bound (error_bound.h)
 * exceeds the worst so far: the maximum skinning every vertex gives. */
static double lane_error(probe_ctx *c, int l, bool finite, double worst, double goal)
{
    const palette_skin_facts *f = c->facts;
    uint32_t bones = c->k->bones;
    const cb_joint_error *joints = c->joints + (size_t)l * bones;
    const double *diff = c->diff + (size_t)l * bones * 16;
    if (!finite) return INFINITY;
    if (cb_row_error_cap(joints, bones, f->group_reach, f->weight_sum) <= worst) return worst;
    const cb_vertex_groups *g = &f->groups;
    for (uint32_t k = 0; k < g->group_count && !(worst > goal); ++k) {
        if (cb_group_error_bound(g, k, joints, worst) <= worst) continue;
        const cb_vertex_group *grp = &g->groups[k];
        double e = sqrt(cb_skin_group_worst(&c->m->primitives[grp->primitive], g->vertices + grp->first, grp->count, diff));
        worst = e > worst ? e : worst; /* a NaN error leaves it: cb_joint_errors let only finite differences by */
    }
    return worst;
}

/* The points' errors into their worsts, four at a time (local_points4), in order: a point's
 * measurement starts from the worst the points before it left. Stops after the four where a
 * worst passes `goal` (a maximum is the same whatever the order: it only ever grows, and a
 * group's bound only skips what cannot raise it). compose_bind: where the rows are composed
 * about (the palette's bind positions, or the skin's). */
static void measure_points(probe_ctx *c, const float *compose_bind, const point *pts, uint32_t n, double goal)
{
    uint32_t bones = c->k->bones;
    for (uint32_t at = 0; at < n; at += 4) {
        uint32_t lanes = n - at < 4 ? n - at : 4;
        const local_qpos *a[4], *b[4], *exact[4];
        const double *mats[4];
        double f[4];
        bool finite[4], past = false;
        for (uint32_t l = 0; l < 4; ++l) { /* lanes past the points repeat the first: computed, not read */
            const point *pt = &pts[at + (l < lanes ? l : 0)];
            a[l] = pt->a, b[l] = pt->b, f[l] = pt->f;
            exact[l] = c->poses + (size_t)pt->pose * bones;
            mats[l] = c->similar ? NULL : c->mats[pt->pose];
        }
        local_points4(c->k, compose_bind, c->facts->bind_positions, c->facts->reach, a, b, f, c->similar ? NULL : mats,
                      exact, c->composed, c->diff, c->joints, finite);
        for (uint32_t l = 0; l < lanes; ++l) {
            double *worst = pts[at + l].worst;
            *worst = lane_error(c, (int)l, finite[l], *worst, goal);
            past = past || *worst > goal;
        }
        if (past) return;
    }
}

/* The worst error of the clip's local rows at `fps` at the quarter points of every row interval,
 * framed as the bake frames them: N = round(D fps) steps, row i at t0 + i D / N. The points are
 * frames of the clip framed at 4N steps (row i is frame 4i, the same double; its midpoint, where
 * the bake measures, frame 4i + 2). A loop's last interval blends into its first row, as the
 * bake ships it (its rows are frames 0 .. 4N - 4): the pose at frame 4N, t0 + D, is the first
 * pose only where the sampler wraps (a loop without a closing key). A closed loop ends on its
 * closing key, and with its travel kept (root motion keep, or a loop correction that keeps a
 * drift too small to take it in place) that pose is the first moved by the travel: the palette
 * pulls the body back over the last interval, which blending into the pose at t0 + D missed
 * (Cow's Gallop_Jump: 0.256 mm/m chosen, 0.531 measured in the float palette; its 3.2 mm drift,
 * 0.71 mm/m, reaches 3/4 of it at the last quarter point). Stops above `goal` (INFINITY: in
 * full). */
static double probe(probe_ctx *c, double fps, double goal)
{
    cb_clip_info framing = *c->clip;
    uint32_t steps = cb_clip_step_count(c->clip->duration, fps), bones = c->k->bones, row0 = 0;
    framing.steps = POINTS * steps;
    const float *bind = c->facts->bind_positions;
    const bool row_kept = true;
    double worst = 0;
    sample_frames(c, &framing, &row0, 1, &row_kept);
    to_local(c->k, bind, c->poses, c->rows);
    memcpy(c->first_row, c->rows, bones * sizeof *c->first_row);
    for (uint32_t first = 0; first < steps && !(worst > goal); first += INTERVALS_A_BATCH) {
        uint32_t count = steps - first < INTERVALS_A_BATCH ? steps - first : INTERVALS_A_BATCH, frames[CB_SAMPLE_BATCH], n = 0;
        bool kept[CB_SAMPLE_BATCH];
        for (uint32_t i = 0; i < count * POINTS; ++i) /* all kept: the bake reads rows and midpoints, its measure all */
            frames[i] = POINTS * first + i + 1, kept[i] = true;
        sample_frames(c, &framing, frames, count * POINTS, kept);
        point pts[INTERVALS_A_BATCH * (POINTS - 1)];
        for (uint32_t i = 0; i < count; ++i) {
            local_qpos *from = c->rows + (size_t)i * bones, *to = from + bones;
            if (c->clip->loops && first + i + 1 == steps) /* the wrap: into the first row */
                memcpy(to, c->first_row, bones * sizeof *to);
            else
                to_local(c->k, bind, c->poses + (size_t)(i * POINTS + POINTS - 1) * bones, to);
            for (uint32_t q = 1; q < POINTS; ++q) pts[n++] = (point){from, to, (double)q / POINTS, i * POINTS + q - 1, &worst};
        }
        measure_points(c, bind, pts, n, goal);
        memcpy(c->rows, c->rows + (size_t)count * bones, bones * sizeof *c->rows); /* the next batch's first */
    }
    return worst;
}

/* ---- the candidates ---- */

/* The common rates rate_search.c walks for a clip with no key grid. */
static const double ladder[] = {2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 24, 30, 40, 48, 60, 90, 120, 180, 240, 360, 480, 720, 960};
enum { MOST_CANDIDATES = 48 };

/* The rates a clip may take up to CB_FPS_LIMIT, increasing, max_fps among them; *key_fps its key
 * rate (cb_key_grid_fps; 0: none, the common rates instead). Multiples of the key rate: 1, 2, 3, 4,
 * 6, 8, 12, 16, ... (each twice the one two before), so a clip whose nlerp lag needs more than
 * twice its keys is a few probes. */
static uint32_t candidates(const cb_animation *a, const cb_clip_info *clip, double max_fps, double *out, double *key_fps)
{
    double k = *key_fps = cb_key_grid_fps(a, clip->t0, clip->duration, max_fps);
    uint32_t n = 0;
    if (k > 0) {
        double before = 1, next = 2; /* the last multiple taken and the next */
        out[n++] = k;
        while (n + 1 < MOST_CANDIDATES && next * k <= CB_FPS_LIMIT) {
            out[n++] = round(next * k * 1000) / 1000;
            double after = next == 2 ? 3 : 2 * before;
            before = next, next = after;
        }
    } else {
        for (size_t i = 0; i < sizeof ladder / sizeof ladder[0] && ladder[i] <= CB_FPS_LIMIT; ++i) out[n++] = ladder[i];
    }
    uint32_t at = 0; /* max_fps in its place (once) */
    while (at < n && out[at] < max_fps) ++at;
    if (at == n || out[at] != max_fps) {
        memmove(out + at + 1, out + at, (n - at) * sizeof *out);
        out[at] = max_fps, ++n;
    }
    return n;
}

static bool on_key_grid(double fps, double key_fps)
{
    double multiple = fps / key_fps;
    return key_fps > 0 && fabs(multiple - round(multiple)) < 1e-6;
}

cb_status local_clip_rate(cb_sampler *s, const palette_skin_facts *facts, const local_skeleton *skeleton,
                          const cb_clip_info *clip, cb_root_motion root_motion, pose_cache *keep, double max_error,
                          double max_fps, local_rate *out, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    double rates[MOST_CANDIDATES];
    memset(out, 0, sizeof *out);
    uint32_t n = candidates(&m->animations[clip->animation], clip, max_fps, rates, &out->key_fps);
    probe_ctx c;
    if (!probe_ctx_init(&c, s, facts, skeleton, clip, root_motion, keep))
        return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory choosing clip %d's rate for local rows", m->source,
                       clip->animation);
    cb_sampler_set_loop(s, clip); /* out of memory: sampled uncorrected, a measurement's detail */
    bool still = !(clip->duration > 0); /* one pose: every rate is exact */
    uint32_t i = 0;
    for (; i < n && rates[i] <= max_fps; ++i) {
        out->fps = rates[i], ++out->probes;
        /* max_fps in full: where nothing meets the goal its error is what the bake reports */
        out->error = still ? 0 : probe(&c, rates[i], rates[i] == max_fps ? INFINITY : max_error);
        if ((out->met = out->error <= max_error)) break;
    }
    for (uint32_t k = i; !out->met && !still && k < n; ++k) /* what it would take: for the message */
        if (probe(&c, rates[k], max_error) <= max_error) {
            out->fps_needed = rates[k];
            break;
        }
    out->error_mm = cb_mm_per_m(out->error, facts->height);
    out->on_keys = on_key_grid(out->fps, out->key_fps);
    out->not_qpos = c.not_qpos;
    probe_ctx_free(&c);
    return CB_OK;
}

/* ---- timed rows: rows on the keys ---- */

enum { MOST_SPLITS = 4, FINE = 12 /* lcm(1..MOST_SPLITS): every split's rows lie on a FINE-th of a key step */ };

/* The steps of the key grid (key_fps, G steps over the clip) where some channel has a key, 0
 * always, a one-shot's end G too (a loop's G is its wrap, no row), increasing, into *count. */
static uint32_t *key_steps(const cb_animation *a, const cb_clip_info *clip, double key_fps, uint32_t G, uint32_t *count)
{
    bool *on = calloc((size_t)G + 1, sizeof *on);
    uint32_t *out = malloc(((size_t)G + 1) * sizeof *out), n = 0;
    if (!on || !out) return free(on), free(out), NULL;
    on[0] = true, on[G] = !clip->loops;
    for (uint32_t c = 0; c < a->channel_count; ++c) {
        const cb_channel *ch = &a->channels[c];
        if (c > 0 && ch->times == a->channels[c - 1].times) continue;
        for (uint32_t k = 0; k < ch->key_count; ++k) {
            double g = round((ch->times[k] - clip->t0) * key_fps);
            if (g >= 0 && g < G) on[(uint32_t)g] = true;
        }
    }
    for (uint32_t g = 0; g <= G; ++g)
        if (on[g]) out[n++] = g;
    free(on);
    *count = n;
    return out;
}

/* The worst error over the fine steps [from, to) (FINE a key step; `fine` frames the clip at
 * POINTS x FINE steps a key step) with rows at s equal parts of it, exact local rows blended and
 * composed at the quarter points of each (wraps: a loop's last interval, into its first row,
 * c->first_row). Stops above goal. */
static double split_error(probe_ctx *c, const cb_clip_info *fine, uint32_t from, uint32_t to, uint32_t s, bool wraps,
                          double goal)
{
    uint32_t bones = c->k->bones, d = (to - from) / s, frames[CB_SAMPLE_BATCH], n = 0, start = POINTS * from;
    const float *bind = c->facts->bind_positions;
    bool kept[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) kept[i] = true;
    sample_frames(c, fine, &start, 1, kept); /* the first row alone: with 4 splits, 17 times */
    to_local(c->k, bind, c->poses, c->rows);
    for (uint32_t j = 0; j < s; ++j) {
        for (uint32_t q = 1; q <= POINTS; ++q)
            if (q < POINTS || !(wraps && j + 1 == s)) frames[n++] = POINTS * (from + j * d) + q * d;
    }
    sample_frames(c, fine, frames, n, kept);
    double worst = 0;
    point pts[MOST_SPLITS * (POINTS - 1)];
    for (uint32_t j = 0; j < s; ++j) {
        local_qpos *to_row = c->rows + (size_t)(j + 1) * bones;
        if (wraps && j + 1 == s) memcpy(to_row, c->first_row, bones * sizeof *to_row);
        else to_local(c->k, bind, c->poses + (size_t)(POINTS * j + POINTS - 1) * bones, to_row);
        for (uint32_t q = 1; q < POINTS; ++q)
            pts[j * (POINTS - 1) + q - 1] = (point){c->rows + (size_t)j * bones, to_row, (double)q / POINTS, POINTS * j + q - 1, &worst};
    }
    measure_points(c, bind, pts, s * (POINTS - 1), goal);
    return worst;
}

/* The fewest divisions L of a key step (1, 2, 3, 4, 6, 12) on which every key interval's splits
 * land: steps[i] x L a multiple of split[i]. */
static uint32_t cell_divisions(const uint32_t *steps, const uint32_t *split, uint32_t n)
{
    static const uint32_t divisions[] = {1, 2, 3, 4, 6, FINE};
    for (size_t d = 0; d < sizeof divisions / sizeof divisions[0]; ++d) {
        bool all = true;
        for (uint32_t i = 0; all && i < n; ++i) all = steps[i] * divisions[d] % split[i] == 0;
        if (all) return divisions[d];
    }
    return FINE;
}

/* The splits found (split[i] for the key interval from keys[i], steps[i] key steps) as cells. */
static bool timed_cells(const cb_clip_info *clip, const uint32_t *keys, const uint32_t *steps, const uint32_t *split,
                        uint32_t n, uint32_t G, uint32_t row_texels, local_timed *out)
{
    uint32_t L = cell_divisions(steps, split, n), rows = clip->loops ? 0 : 1;
    out->cell_rate = round(out->key_fps * L * 1000) / 1000;
    out->cells = G * L;
    if (cb_clip_step_count(clip->duration, out->cell_rate) != out->cells) return false; /* the bake frames it so */
    for (uint32_t i = 0; i < n; ++i) rows += split[i];
    if (!(out->row_cells = malloc(rows * sizeof *out->row_cells))) return false;
    uint32_t r = 0;
    for (uint32_t i = 0; i < n; ++i)
        for (uint32_t j = 0; j < split[i]; ++j) out->row_cells[r++] = keys[i] * L + j * steps[i] * L / split[i];
    if (!clip->loops) out->row_cells[r++] = out->cells;
    out->rows = rows;
    out->map_rows = cb_timed_map_rows(out->cells, row_texels);
    return true;
}

cb_status local_clip_timed(cb_sampler *s, const palette_skin_facts *facts, const local_skeleton *skeleton,
                           const cb_clip_info *clip, cb_root_motion root_motion, pose_cache *keep, double max_error,
                           uint32_t row_texels, uint32_t most_rows, local_timed *out, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    const cb_animation *a = &m->animations[clip->animation];
    memset(out, 0, sizeof *out);
    if (!(clip->duration > 0) || !((out->key_fps = cb_key_grid_fps(a, clip->t0, clip->duration, CB_FPS_LIMIT)) > 0))
        return CB_OK;
    uint32_t G = cb_clip_step_count(clip->duration, out->key_fps), count = 0;
    if ((uint64_t)G * POINTS * FINE > UINT32_MAX / 2) return CB_OK;
    uint32_t *keys = key_steps(a, clip, out->key_fps, G, &count);
    uint32_t n = keys ? (clip->loops ? count : count - 1) : 0, end_row = clip->loops ? 0 : 1;
    /* The least they can take: a row a key interval, the map at the key grid's cells. */
    uint32_t least = n + end_row + cb_timed_map_rows(G, row_texels);
    if (keys && most_rows && least >= most_rows) {
        out->too_many = true, out->rows = n + end_row, out->map_rows = cb_timed_map_rows(G, row_texels);
        free(keys);
        return CB_OK;
    }
    uint32_t *steps = calloc(n ? n : 1, sizeof *steps), *split = calloc(n ? n : 1, sizeof *split);
    probe_ctx c;
    bool ready = keys && steps && split && probe_ctx_init(&c, s, facts, skeleton, clip, root_motion, keep);
    if (!ready) {
        free(keys), free(steps), free(split);
        return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory choosing clip %d's timed rows", m->source, clip->animation);
    }
    cb_sampler_set_loop(s, clip);
    cb_clip_info fine = *clip;
    fine.steps = POINTS * FINE * G;
    uint32_t row0 = 0;
    const bool kept = true;
    sample_frames(&c, &fine, &row0, 1, &kept);
    to_local(c.k, facts->bind_positions, c.poses, c.first_row);
    bool ok = n > 0;
    for (uint32_t i = 0; ok && i < n; ++i) {
        uint32_t end = i + 1 < count ? keys[i + 1] : G;
        steps[i] = end - keys[i];
        double e = INFINITY;
        for (split[i] = 1; split[i] <= MOST_SPLITS; ++split[i])
            if ((e = split_error(&c, &fine, FINE * keys[i], FINE * end, split[i], i + 1 == count, max_error)) <= max_error) break;
        ok = e <= max_error;
        out->error = fmax(out->error, e);
        out->split = split[i] > out->split ? split[i] : out->split;
        least += split[i] - 1; /* this interval's rows past its one */
        if (ok && most_rows && least >= most_rows) { /* fewer rows cannot come of it now */
            out->too_many = true, ok = false;
            out->rows = least - cb_timed_map_rows(G, row_texels), out->map_rows = cb_timed_map_rows(G, row_texels);
        }
    }
    out->intervals = n;
    out->not_qpos = c.not_qpos;
    out->possible = ok && timed_cells(clip, keys, steps, split, n, G, row_texels, out);
    if (!out->possible) free(out->row_cells), out->row_cells = NULL;
    probe_ctx_free(&c);
    free(keys), free(steps), free(split);
    return CB_OK;
}

double local_rows_error(cb_sampler *s, const palette_skin_facts *facts, const local_skeleton *skeleton,
                        const cb_clip_info *clip, double fps, cb_error *err)
{
    probe_ctx c;
    if (!probe_ctx_init(&c, s, facts, skeleton, clip, CB_ROOT_MOTION_KEEP, NULL)) {
        cb_fail(err, CB_ERR_INTERNAL, "out of memory measuring local rows");
        return INFINITY;
    }
    cb_sampler_set_loop(s, clip);
    double e = clip->duration > 0 ? probe(&c, fps, INFINITY) : 0;
    probe_ctx_free(&c);
    return e;
}

/* ---- a finished local palette, measured ---- */

/* Palette row r's local rows of every bone, decoded as the runtime decodes them. */
static void decode_row(probe_ctx *c, const cb_palette *p, uint32_t r, local_qpos *out)
{
    palette_decode_row_values(p, r, c->values);
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        const double *v = c->values + (size_t)j * 16;
        out[j] = (local_qpos){{v[0], v[1], v[2], v[3]}, {v[4], v[5], v[6]}, v[7]};
    }
}

/* The runtime's weight of row r1 at cell position u of a timed clip (its map's texel, as
 * cb_runtime_frame_in reads it). */
static double timed_weight(const cb_palette *p, const cb_palette_clip *pc, double u)
{
    double v[4], cell = floor(u);
    if (cell > pc->cells - 1) cell = pc->cells - 1;
    timed_map_read(p, p->texels, pc->first_row, pc->cells, (uint32_t)cell, v);
    return v[2] + (v[3] - v[2]) * (u - cell);
}

/* The clip's rows (frames 4 c_k of framing: c_k = k, or a timed clip's row_cells) and the quarter
 * points between them (4 c_k + q (c_k+1 - c_k)) measured interval by interval, a batch of four
 * intervals at a time, each row decoded once; a timed clip's weights as its map gives them. With
 * stride > 1 (the measuring budget, palette.h) every stride-th batch and the last; the rows measured
 * into *measured. */
static void palette_intervals(probe_ctx *c, const cb_palette *p, const cb_palette_clip *pc, const cb_clip_info *framing,
                              uint32_t steps, const uint32_t *row_cells, uint32_t stride, double *at_rows, double *between,
                              uint32_t *measured)
{
    uint32_t row0 = 0, bones = c->k->bones, end_cell = row_cells ? pc->cells : pc->frames;
    const bool all = true;
    bool kept[CB_SAMPLE_BATCH];
    for (uint32_t i = 0; i < CB_SAMPLE_BATCH; ++i) kept[i] = true; /* the bake after a replan reads them again */
    decode_row(c, p, pc->first_row, c->rows);
    sample_frames(c, framing, &row0, 1, &all);
    point start = {c->rows, c->rows, 0, 0, at_rows};
    measure_points(c, p->bind_positions, &start, 1, INFINITY);
    *measured = 1;
    for (uint32_t first = 0; first < steps; first += INTERVALS_A_BATCH) {
        uint32_t count = steps - first < INTERVALS_A_BATCH ? steps - first : INTERVALS_A_BATCH, frames[CB_SAMPLE_BATCH], n = 0;
        if ((first / INTERVALS_A_BATCH) % stride && first + count < steps) continue; /* not in the subset */
        if (stride > 1 && first) decode_row(c, p, pc->first_row + first, c->rows); /* after a gap: its first row */
        *measured += count - (first + count == pc->frames); /* each interval's end row (a loop's wraps to the first) */
        for (uint32_t i = 0; i < count; ++i) {
            uint32_t k = first + i, from = row_cells ? row_cells[k] : k;
            uint32_t to = k + 1 == pc->frames ? end_cell : row_cells ? row_cells[k + 1] : k + 1;
            for (uint32_t q = 1; q <= POINTS; ++q) frames[i * POINTS + q - 1] = POINTS * from + q * (to - from);
        }
        sample_frames(c, framing, frames, count * POINTS, kept);
        point pts[INTERVALS_A_BATCH * POINTS];
        for (uint32_t i = 0; i < count; ++i) {
            uint32_t next = first + i + 1;
            bool wrap = next == pc->frames; /* a loop's last interval ends on its first row */
            local_qpos *from = c->rows + (size_t)i * bones, *end = from + bones;
            decode_row(c, p, pc->first_row + (wrap ? 0 : next), end);
            const local_qpos *to = pc->step ? from : end; /* held rows: the row alone */
            for (uint32_t q = 1; q < POINTS; ++q) {
                double f = (double)q / POINTS;
                if (row_cells) f = timed_weight(p, pc, (frames[i * POINTS + q - 1]) / (double)POINTS);
                pts[n++] = (point){from, to, f, i * POINTS + q - 1, between};
            }
            if (!wrap) pts[n++] = (point){end, end, 0, i * POINTS + POINTS - 1, at_rows};
        }
        measure_points(c, p->bind_positions, pts, n, INFINITY);
        memcpy(c->rows, c->rows + (size_t)count * bones, bones * sizeof *c->rows); /* the next batch's first */
    }
}

cb_status local_palette_errors(cb_sampler *s, const palette_skin_facts *facts, const cb_palette *p, uint32_t clip,
                               int32_t animation, pose_cache *keep, uint32_t stride, double *at_rows, double *between,
                               uint32_t *measured, cb_error *err)
{
    const cb_model *m = cb_sampler_model(s);
    const cb_palette_clip *pc = &p->clips[clip];
    const cb_animation *a = &m->animations[animation];
    uint32_t steps = pc->loops ? pc->frames : pc->frames - 1;
    /* As the bake framed it (cb_verify_clip's reading of the palette's clip): rows at start + i D / N,
     * in-place travel at the clip's recorded velocity (zero where it was kept). */
    cb_clip_info framing = {.animation = animation, .t0 = pc->start, .t1 = pc->start + (a->t1 - a->t0),
                            .duration = pc->duration, .loops = pc->loops,
                            .steps = POINTS * (pc->timed ? pc->cells : steps ? steps : 1)};
    uint32_t *row_cells = pc->timed ? malloc(pc->frames * sizeof *row_cells) : NULL;
    if (pc->timed && !row_cells) return cb_fail(err, CB_ERR_INTERNAL, "out of memory measuring %s's local rows", m->source);
    if (row_cells) timed_map_row_cells(p, p->texels, pc, row_cells);
    for (int k = 0; k < 3; ++k) framing.root_velocity[k] = pc->root_velocity[k];
    local_skeleton k; /* the palette's parents: the same nearest ancestor joints (global rows: roots, composing nothing) */
    probe_ctx c;
    *at_rows = *between = 0, *measured = 0;
    bool built = p->bone_space == CB_BONE_SPACE_LOCAL ? local_skeleton_build(m, cb_sampler_skin(s), &k)
                                                      : local_skeleton_roots(p->bone_count, &k);
    if (!built ||
        !probe_ctx_init(&c, s, facts, &k, &framing, CB_ROOT_MOTION_IN_PLACE, keep)) {
        local_skeleton_free(&k), free(row_cells);
        return cb_fail(err, CB_ERR_INTERNAL, "out of memory measuring %s's local rows", m->source);
    }
    /* The loop as the bake played it: from the analysis its rate choice kept (judged once). */
    const cb_clip_info *judged = palette_kept_analysis_info(keep);
    if (judged && judged->animation == animation)
        sampler_set_baked_loop_judged(s, judged, pc->loops, pc->start, pc->duration);
    else
        cb_sampler_set_baked_loop(s, animation, pc->loops, pc->start, pc->duration);
    c.global_rows = false; /* a matrix rig's poses are measured as matrices: its rows are the palette's */
    palette_intervals(&c, p, pc, &framing, pc->duration > 0 ? steps : 0, row_cells, stride ? stride : 1, at_rows, between,
                      measured);
    probe_ctx_free(&c);
    free(row_cells);
    local_skeleton_free(&k);
    return CB_OK;
}
