/* palette_rows.c - where a bake's rows are made: a clip's frame matrices (kept for a search's
 * probes), rows of any layout from them, the exact mid-rows --fit needs; and qpos rows from joint
 * similarities: what qpos stores (quaternion, position, scale), with no matrix to build, check
 * or decompose, for a batch of frames at a time.
 *
 * Bone by bone, the batch's frames are lanes (structure of arrays, like the sampler's), so the
 * rotation of the bind position, the position and the conversions to float vectorize. Each
 * lane runs cb_quat_rotate's operations in their order: the same bits as one row at a time.
 * What depends on the rows before - the quaternion's hemisphere, the clip's bounds and value
 * ranges - is settled after, in frame order, so it comes out as before too. */

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "lanes.h"
#include "palette_bake.h"
#include "sampler.h"

#define B CB_SAMPLE_BATCH

/* ---- rows from joint matrices, any layout ---- */

#define QPOS_TOLERANCE 1e-4 /* relative: scale differences and shear qpos may drop */

/* What qpos takes of a joint matrix, from the matrix alone: the quaternion of its rotation
 * (either sign) into q[0..3] and its scale into q[4]; fails where it is no similarity. */
static cb_status qpos_similarity(const double m[16], double q[5], const cb_model *model, const cb_skin *skin,
                                 uint32_t bone, const char *clip, uint32_t frame, cb_error *err)
{
    cb_vec3 c[3] = {{m[0], m[1], m[2]}, {m[4], m[5], m[6]}, {m[8], m[9], m[10]}};
    double l[3] = {cb_vec3_length(c[0]), cb_vec3_length(c[1]), cb_vec3_length(c[2])};
    double s = (l[0] + l[1] + l[2]) / 3;
    const char *why = NULL;
    if (cb_mat4_determinant3(m) <= 0)
        why = "a negative (mirroring) scale";
    else if (fabs(l[0] - s) > QPOS_TOLERANCE * s || fabs(l[1] - s) > QPOS_TOLERANCE * s || fabs(l[2] - s) > QPOS_TOLERANCE * s)
        why = "a non-uniform scale";
    else if (fabs(cb_vec3_dot(c[0], c[1])) > QPOS_TOLERANCE * s * s || fabs(cb_vec3_dot(c[0], c[2])) > QPOS_TOLERANCE * s * s ||
             fabs(cb_vec3_dot(c[1], c[2])) > QPOS_TOLERANCE * s * s)
        why = "shear";
    if (why)
        return cb_fail_setting(err, CB_ERR_LAYOUT, CB_SETTING_LAYOUT,
                               "%s: joint '%s' has %s (axis scales %.7g, %.7g, %.7g) at frame %u of clip '%s', which the "
                               "qpos layout cannot represent; use the affine or the mat4 layout",
                       model->source, model->nodes[skin->joints[bone]].name, why, l[0], l[1], l[2], frame, clip);
    double r[16], inv = 1 / s;
#pragma GCC unroll 12 /* not a copy, then a loop of products: -O2 leaves that a loop */
    for (int i = 0; i < 12; ++i) r[i] = m[i] * inv;
    r[12] = m[12], r[13] = m[13], r[14] = m[14], r[15] = m[15];
    cb_quat rot = cb_quat_from_mat4(r);
    q[0] = rot.x, q[1] = rot.y, q[2] = rot.z, q[3] = rot.w, q[4] = s;
    return CB_OK;
}

/* A qpos bone's quaternion and scale (qpos_similarity's q) as canonical floats: the quaternion
 * on the side of the previous row's (prev), or of w >= 0 for a clip's first row. */
static CB_CLONE_INLINE void qpos_store(const double q[5], const cb_quat *prev, float out[8])
{
    cb_quat rot = {q[0], q[1], q[2], q[3]};
    if (prev) {
        if (cb_quat_dot(rot, *prev) < 0) rot = (cb_quat){-rot.x, -rot.y, -rot.z, -rot.w};
    } else if (rot.w < 0) {
        rot = (cb_quat){-rot.x, -rot.y, -rot.z, -rot.w};
    }
    out[0] = (float)rot.x, out[1] = (float)rot.y, out[2] = (float)rot.z, out[3] = (float)rot.w;
    out[7] = (float)q[4];
}

/* A probe pose's extra doubles (pose_cache.h): its state first - NaN before anything is
 * derived, DERIVED_QPOS when its joints' qpos_similarity follows (5 doubles a joint), ROW_KEPT
 * when its qpos row follows those too (kept_row). */
enum { DERIVED_QPOS = 1, ROW_KEPT = 2 };
#define KEPT_ROW_AT(bones) (1 + 5 * (size_t)(bones))

/* What a qpos row takes of its pose alone, kept so that a probe at another rate that has the pose
 * again copies it (Husky: half the search's rows are poses a probe before made a row of). Only
 * each quaternion's hemisphere depends on the rows before: kept as qpos_similarity gives it, and
 * a float's sign flips exactly, so the copy is the same bits. The bounds and range are the
 * pose's own, grown from empty in bone order; merged into the clip's with the same compares they
 * give the same extremes as growing it bone by bone (a compare keeps the first of equal values,
 * and the pose's first extreme comes before every later one). Besides the pose, the row reads
 * the skin's facts (bind positions, reaches), which every bake that shares the cache builds alike
 * from the same skin (the search's and the bake after it). */
typedef struct kept_row {
    extent bounds;      /* grow_bounds over the joints, from empty */
    value_range range;  /* range_grow_qpos over the joints, from empty (linear from -INFINITY) */
    float values[];     /* bones x 8: the row, quaternions unflipped */
} kept_row;
#define KEPT_ROW_DOUBLES(bones) ((sizeof(kept_row) + sizeof(double) - 1) / sizeof(double) + 4 * (size_t)(bones))

pose_cache *palette_probe_poses(pose_arena *arena, uint32_t bones, size_t max_bytes)
{
    return pose_cache_create_in(arena, bones, (uint32_t)(KEPT_ROW_AT(bones) + KEPT_ROW_DOUBLES(bones)), max_bytes);
}

const double *palette_kept_qpos(const double *mats, uint32_t bones)
{
    double *kept = (double *)mats + (size_t)bones * 16; /* the pose's extra doubles: the cache's, writable */
    if (kept[0] >= DERIVED_QPOS) return kept + 1;
    if (!palette_qpos_similarity_pose(mats, bones, kept + 1)) return NULL;
    kept[0] = DERIVED_QPOS;
    return kept + 1;
}

const double *palette_frame_matrices(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, uint32_t frame,
                                     double **extra)
{
    double t = cb_clip_frame_time(framing, frame), *out = w->mats;
    pose_cache *poses = st->poses ? st->poses : st->clip_poses ? st->clip_poses[c] : NULL;
    double *kept = poses ? (double *)pose_cache_find(poses, t) : NULL;
    if (!kept && poses) {
        kept = pose_cache_add(poses, t);
        if (kept) cb_clip_frame_matrices(w->sampler, framing, frame, st->opt->root_motion, kept);
    }
    if (extra) *extra = kept ? kept + (size_t)st->p->bone_count * 16 : NULL;
    if (kept) return kept;
    cb_clip_frame_matrices(w->sampler, framing, frame, st->opt->root_motion, out);
    return out;
}

/* |A| for the reach: the Frobenius norm of the 3x3, at least its largest stretch. */
static double frobenius3(const double *M)
{
    /* The nine squares summed in element order, written out: a loop that skips every fourth
     * element was not unrolled, and its test cost more than the sum (the same additions in the
     * same order, so the same bits). */
    double norm = 0;
    norm += M[0] * M[0], norm += M[1] * M[1], norm += M[2] * M[2];
    norm += M[4] * M[4], norm += M[5] * M[5], norm += M[6] * M[6];
    norm += M[8] * M[8], norm += M[9] * M[9], norm += M[10] * M[10];
    return sqrt(norm);
}

static void merge_bounds(extent *into, const extent *e)
{
    for (int k = 0; k < 3; ++k) {
        into->lo[k] = e->lo[k] < into->lo[k] ? e->lo[k] : into->lo[k];
        into->hi[k] = e->hi[k] > into->hi[k] ? e->hi[k] : into->hi[k];
    }
}

static void merge_range(value_range *into, const value_range *r)
{
    for (int k = 0; k < 3; ++k) {
        into->lo[k] = r->lo[k] < into->lo[k] ? r->lo[k] : into->lo[k];
        into->hi[k] = r->hi[k] > into->hi[k] ? r->hi[k] : into->hi[k];
    }
    into->linear = r->linear > into->linear ? r->linear : into->linear;
}

/* A kept pose's qpos row (kept_row) as palette_matrix_row makes it: each quaternion on the side
 * qpos_store picks, from the same doubles q. */
static void take_kept_row(bake_state *st, worker *w, uint32_t c, uint32_t f, const double *q, const kept_row *k,
                          float *row, extent *bounds)
{
    for (uint32_t j = 0; j < st->p->bone_count; ++j, q += 5) {
        const float *v = k->values + (size_t)j * 8;
        float *out = row + (size_t)j * 8;
        cb_quat rot = {q[0], q[1], q[2], q[3]};
        bool flip = f ? cb_quat_dot(rot, w->prev[j]) < 0 : rot.w < 0;
        memcpy(out, v, 8 * sizeof *out);
        if (flip) out[0] = -out[0], out[1] = -out[1], out[2] = -out[2], out[3] = -out[3];
        w->prev[j] = (cb_quat){out[0], out[1], out[2], out[3]};
    }
    merge_bounds(bounds, &k->bounds);
    merge_range(&st->ranges[c], &k->range);
}

/* One row from joint matrices: any layout; qpos checks each matrix is a similarity. */
cb_status palette_matrix_row(bake_state *st, worker *w, uint32_t c, uint32_t f, float *row, extent *bounds,
                             cb_error *err)
{
    cb_palette *p = st->p;
    cb_palette_clip *clip = &p->clips[c];
    double *kept; /* the pose's qpos_similarity, where a search keeps it (1 + 5 a joint), and its row */
    const double *mats = palette_frame_matrices(st, w, c, &st->infos[c], f, &kept);
    bool qpos = p->layout == CB_LAYOUT_QPOS;
    kept_row *keep = kept && qpos ? (kept_row *)(kept + KEPT_ROW_AT(p->bone_count)) : NULL;
    if (keep && kept[0] == ROW_KEPT) return take_kept_row(st, w, c, f, kept + 1, keep, row, bounds), CB_OK;
    bool derived = kept && kept[0] >= DERIVED_QPOS;
    if (kept && !derived && qpos) /* a new pose: every joint's at once where it can */
        derived = palette_qpos_similarity_pose(mats, p->bone_count, kept + 1);
    extent pose = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    value_range range = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}, -INFINITY};
    for (uint32_t j = 0; j < p->bone_count; ++j) {
        const double *M = mats + (size_t)j * 16;
        const float *b = p->bind_positions + (size_t)j * 3;
        float *out = row + (size_t)j * CANON(p->layout);
        cb_vec3 pos = cb_mat4_transform_point(M, (cb_vec3){b[0], b[1], b[2]}); /* the joint now: M b */
        if (st->radius[j] >= 0) grow_bounds(&pose, pos, st->radius[j] * frobenius3(M));
        if (!qpos) {
            for (int r = 0; r < 3; ++r)
                for (int k = 0; k < 4; ++k) out[r * 4 + k] = (float)M[k * 4 + r];
            range_grow_affine(&st->ranges[c], out);
            continue;
        }
        double fresh[5], *q = kept ? kept + 1 + (size_t)j * 5 : fresh;
        if (!derived && qpos_similarity(M, q, st->model, &st->model->skins[st->skin], j, clip->name, f, err))
            return err->status;
        qpos_store(q, f ? &w->prev[j] : NULL, out);
        w->prev[j] = (cb_quat){out[0], out[1], out[2], out[3]};
        out[4] = (float)pos.x, out[5] = (float)pos.y, out[6] = (float)pos.z;
        if (keep) { /* the row as this pose alone gives it: the quaternion as q has it */
            float *v = keep->values + (size_t)j * 8;
            v[0] = (float)q[0], v[1] = (float)q[1], v[2] = (float)q[2], v[3] = (float)q[3];
            v[4] = out[4], v[5] = out[5], v[6] = out[6], v[7] = out[7];
        }
        range_grow_qpos(&range, out);
    }
    merge_bounds(bounds, &pose);
    if (qpos) merge_range(&st->ranges[c], &range);
    if (keep) { /* every joint's derived, and the row: the next probe takes them */
        keep->bounds = pose, keep->range = range;
        kept[0] = ROW_KEPT;
    }
    return CB_OK;
}

/* ---- a probe's rows, kept for the bake after the search (palette_bake.h) ---- */

typedef struct kept_rows {
    cb_clip_info framing; /* the clip's info (what of it frames and moves the rows: rows_match) */
    cb_layout layout;
    cb_root_motion root_motion;
    uint32_t bones;
    bool fitted;       /* fitted rows, or sampled ones */
    extent bounds;     /* the clip's bounds and value range as making (and fitting) its rows left them */
    value_range range;
    /* What the probe's measurement bounded (palette_pending_point_bounds): each blend's bound, per
     * fraction sub / parts (1 .. parts - 1) and row interval, INFINITY where not bounded, and the
     * box its u16 positions and scales were quantized in. parts 0: none. */
    uint32_t parts;
    double box_lo[4], box_hi[4]; /* positions x y z, then the scale (lo 0) */
    double *point_bounds;        /* 4 x framing.frames, after the rows in the same block: the blends',
                                  * then each baked row's cap (the same, at 3 x frames) */
    float rows[];      /* framing.frames rows of bones * CANON(layout) */
} kept_rows;
_Static_assert(offsetof(kept_rows, rows) % sizeof(double) == 0, "point_bounds follow the rows, aligned for doubles");

/* Whether clip framings a and b sample the same poses at their rows (the times, the loop the
 * sampler is set to, the root travel taken off). */
static bool framed_alike(const cb_clip_info *a, const cb_clip_info *b)
{
    return a->animation == b->animation && a->t0 == b->t0 && a->t1 == b->t1 && a->duration == b->duration &&
           a->steps == b->steps && a->frames == b->frames && a->loops == b->loops &&
           a->root_velocity[0] == b->root_velocity[0] && a->root_velocity[1] == b->root_velocity[1] &&
           a->root_velocity[2] == b->root_velocity[2];
}

static bool rows_match(const kept_rows *k, const bake_state *st, uint32_t c)
{
    return k->layout == st->p->layout && k->root_motion == st->opt->root_motion && k->bones == st->p->bone_count &&
           framed_alike(&k->framing, &st->infos[c]);
}

static size_t kept_floats(const bake_state *st, uint32_t c)
{
    return (size_t)st->infos[c].frames * st->p->bone_count * CANON(st->p->layout);
}

float *palette_keep_rows(bake_state *st, uint32_t c, bool fitted)
{
    /* No search: nothing to keep them with, and nothing pending. (A bake of many clips on many
     * threads ends here, before it touches st: its workers' clips all call this at once.) */
    if (!st->poses) return NULL;
    free(st->pending), st->pending = NULL;
    size_t rows_bytes = (kept_floats(st, c) * sizeof(float) + sizeof(double) - 1) / sizeof(double) * sizeof(double);
    size_t bounds = (size_t)4 * st->infos[c].frames;
    st->pending = malloc(sizeof *st->pending + rows_bytes + bounds * sizeof(double));
    if (!st->pending) return NULL; /* out of memory: the bake after makes them again */
    *st->pending = (kept_rows){.framing = st->infos[c], .layout = st->p->layout, .root_motion = st->opt->root_motion,
                              .bones = st->p->bone_count, .fitted = fitted};
    st->pending->point_bounds = (double *)((unsigned char *)st->pending->rows + rows_bytes);
    for (size_t i = 0; i < bounds; ++i) st->pending->point_bounds[i] = INFINITY;
    return st->pending->rows;
}

void palette_kept_rows_done(bake_state *st, uint32_t c, const extent *bounds)
{
    if (st->pending) st->pending->bounds = *bounds, st->pending->range = st->ranges[c];
}

/* The pose cache's slots for a probe's rows: sampled rows within their goal (a search's answer
 * when sampled rows win), fitted rows within theirs, and the last sampled rows that missed (a
 * fitted probe at the same rate starts from them). */
enum { SLOT_SAMPLED, SLOT_FITTED, SLOT_SAMPLED_MISS };

void palette_settle_rows(bake_state *st, double error)
{
    double goal = st->opt->error_goal;
    bool met = !(goal > 0) || error <= goal;
    kept_rows *k = st->pending;
    if (k && st->poses && (met || !k->fitted))
        pose_cache_attach(st->poses, k->fitted ? SLOT_FITTED : met ? SLOT_SAMPLED : SLOT_SAMPLED_MISS, k);
    else
        free(k);
    st->pending = NULL;
}

/* The kept rows of `poses` in `slot` framed as clip c of st, or NULL. */
static const kept_rows *kept_in(const pose_cache *poses, int slot, const bake_state *st, uint32_t c)
{
    const kept_rows *k = poses ? pose_cache_attached(poses, slot) : NULL;
    return k && rows_match(k, st, c) ? k : NULL;
}

/* Rows framed alike are the same floats whether their probe met its goal or not. */
static const kept_rows *kept_sampled(const pose_cache *poses, const bake_state *st, uint32_t c)
{
    const kept_rows *k = kept_in(poses, SLOT_SAMPLED, st, c);
    return k ? k : kept_in(poses, SLOT_SAMPLED_MISS, st, c);
}

const float *palette_take_rows(bake_state *st, uint32_t c, bool fitted, extent *bounds)
{
    pose_cache *poses = st->clip_poses && !st->poses ? st->clip_poses[c] : NULL;
    const kept_rows *k = fitted ? kept_in(poses, SLOT_FITTED, st, c) : kept_sampled(poses, st, c);
    if (!k) return NULL;
    *bounds = k->bounds, st->ranges[c] = k->range;
    return k->rows;
}

/* Whether a palette's blends of kept rows can be bounded from their probe's: global qpos rows in
 * u16 (each value's decoding is then the same function of the same float but for the position
 * box and the scale range), every range more than a point. */
static bool bounds_carry(const cb_palette *p)
{
    if (p->layout != CB_LAYOUT_QPOS || p->precision != CB_PRECISION_U16 || p->bone_space != CB_BONE_SPACE_GLOBAL ||
        p->positions_relative || !(p->linear_range > 0))
        return false;
    for (int a = 0; a < 3; ++a)
        if (!(p->bounds_max[a] > p->bounds_min[a])) return false;
    return true;
}

double *palette_pending_point_bounds(bake_state *st, uint32_t parts)
{
    kept_rows *k = st->pending;
    const cb_palette *p = st->p;
    if (!k || parts < 2 || parts > 4 || !bounds_carry(p)) return NULL;
    k->parts = parts;
    for (int a = 0; a < 3; ++a) k->box_lo[a] = p->bounds_min[a], k->box_hi[a] = p->bounds_max[a];
    k->box_lo[3] = 0, k->box_hi[3] = p->linear_range;
    return k->point_bounds;
}

/* The kept rows clip c of the bake after the search took (palette_take_rows), or NULL. */
static const kept_rows *taken_rows(const bake_state *st, uint32_t c)
{
    pose_cache *poses = st->clip_poses && !st->poses ? st->clip_poses[c] : NULL;
    return st->p->clips[c].fitted ? kept_in(poses, SLOT_FITTED, st, c) : kept_sampled(poses, st, c);
}

/* How far u16 moves a value from the float it encodes, at most, in the range [lo, hi]: half a
 * step, with room for the rounding of the decode's few operations. */
static double u16_reach(double lo, double hi)
{
    return (hi - lo) / 131070 * (1 + 1e-6) + 1e-12 * (fabs(lo) + fabs(hi));
}

const double *palette_taken_point_bounds(const bake_state *st, uint32_t c, uint32_t parts, double *shift)
{
    const cb_palette *p = st->p;
    const kept_rows *k = taken_rows(st, c);
    if (!k || k->parts != parts || !bounds_carry(p)) return NULL;
    /* A vertex v skinned by bone j decodes to p_j + s_j R_j (v - b_j), R_j the same in both
     * palettes (quaternions need no range): it moves by at most |dp| + |ds| |v - b_j|, and
     * |v - b_j| is within the joint's largest group reach; blends lerp both, and a vertex's
     * weights sum to at most weight_sum. */
    double dp = 0, ds = u16_reach(k->box_lo[3], k->box_hi[3]) + u16_reach(0, p->linear_range), reach = 0;
    for (int a = 0; a < 3; ++a) {
        double d = u16_reach(k->box_lo[a], k->box_hi[a]) + u16_reach(p->bounds_min[a], p->bounds_max[a]);
        dp += d * d;
    }
    for (uint32_t j = 0; j < p->bone_count; ++j)
        reach = st->facts->group_reach[j] > reach ? st->facts->group_reach[j] : reach;
    *shift = st->facts->weight_sum * (sqrt(dp) + ds * reach) * (1 + 1e-6) + 1e-9 * st->facts->height;
    return isfinite(*shift) ? k->point_bounds : NULL;
}

bool palette_take_sampled_for_fit(bake_state *st, uint32_t c, float *rows, extent *bounds)
{
    const kept_rows *k = kept_sampled(st->poses, st, c);
    if (!k) return false;
    memcpy(rows, k->rows, kept_floats(st, c) * sizeof(float));
    *bounds = k->bounds, st->ranges[c] = k->range;
    return true;
}

/* The exact values halfway through each row interval of clip c (the clip framed at twice the
 * steps, odd frames), into mids; quaternions on the side of the row before. */
cb_status palette_mid_rows(bake_state *st, worker *w, uint32_t c, const float *rows, float *mids, cb_error *err)
{
    cb_palette *p = st->p;
    const cb_clip_info *info = &st->infos[c];
    cb_clip_info framing = *info;
    framing.steps *= 2;
    uint32_t intervals = info->loops ? info->frames : info->frames - 1, vals = CANON(p->layout);
    for (uint32_t i = 0; i < intervals; ++i) {
        if (i % CB_SAMPLE_BATCH == 0) { /* the next mid-rows' poses, a batch at once where they are kept */
            uint32_t next[CB_SAMPLE_BATCH], k = 0;
            for (; k < CB_SAMPLE_BATCH && i + k < intervals; ++k) next[k] = 2 * (i + k) + 1;
            palette_prefetch_poses(st, w, c, &framing, next, k);
        }
        double *kept; /* the pose's qpos_similarity, where a search keeps it (as palette_matrix_row) */
        const double *mats = palette_frame_matrices(st, w, c, &framing, 2 * i + 1, &kept);
        bool derived = kept && kept[0] >= DERIVED_QPOS;
        if (kept && !derived && p->layout == CB_LAYOUT_QPOS)
            derived = palette_qpos_similarity_pose(mats, p->bone_count, kept + 1);
        float *out = mids + (size_t)i * p->bone_count * vals;
        for (uint32_t j = 0; j < p->bone_count; ++j) {
            const double *M = mats + (size_t)j * 16;
            float *o = out + (size_t)j * vals;
            if (p->layout != CB_LAYOUT_QPOS) {
                for (int r = 0; r < 3; ++r)
                    for (int k = 0; k < 4; ++k) o[r * 4 + k] = (float)M[k * 4 + r];
                continue;
            }
            const float *prev = rows + ((size_t)i * p->bone_count + j) * vals, *b = p->bind_positions + (size_t)j * 3;
            cb_quat q = {prev[0], prev[1], prev[2], prev[3]};
            double fresh[5], *d = kept ? kept + 1 + (size_t)j * 5 : fresh;
            if (!derived && qpos_similarity(M, d, st->model, &st->model->skins[st->skin], j, p->clips[c].name, i, err))
                return err->status;
            qpos_store(d, &q, o);
            cb_vec3 pos = cb_mat4_transform_point(M, (cb_vec3){b[0], b[1], b[2]});
            o[4] = (float)pos.x, o[5] = (float)pos.y, o[6] = (float)pos.z;
        }
        if (kept && p->layout == CB_LAYOUT_QPOS && !(kept[0] >= DERIVED_QPOS))
            kept[0] = DERIVED_QPOS; /* every joint's derived: the next probe takes them */
    }
    return CB_OK;
}

/* ---- qpos rows from joint similarities, a batch of frames at a time ---- */

/* The clip's bounds and value ranges grown a lane (a frame) at a time: lane i grown by every
 * bone of row i in bone order, with the compares of grow_bounds and range_grow_qpos. A compare
 * keeps the first of equal values (+0 or -0), so lane i holds its row's first extreme; folding
 * the lanes in frame order after (fold_lanes) then gives the first extreme of all the rows, as
 * growing row by row, bone by bone, does - and over the lanes the compares vectorize. */
typedef struct lane_extent {
    double lo[3][B], hi[3][B];       /* the bounds (grow_bounds) */
    float vlo[3][B], vhi[3][B], linear[B]; /* the value range (range_grow_qpos) */
} lane_extent;

static void lane_extent_reset(lane_extent *x)
{
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < B; ++i)
            x->lo[k][i] = INFINITY, x->hi[k][i] = -INFINITY, x->vlo[k][i] = INFINITY, x->vhi[k][i] = -INFINITY;
    for (int i = 0; i < B; ++i) x->linear[i] = -INFINITY; /* no value yet: range_reset's 0 is the clip's */
}

/* Lanes 0 .. count - 1 folded into the clip's bounds and range, in frame order. */
static void fold_lanes(const lane_extent *x, uint32_t count, extent *bounds, value_range *range)
{
    for (uint32_t i = 0; i < count; ++i)
        for (int k = 0; k < 3; ++k) {
            bounds->lo[k] = x->lo[k][i] < bounds->lo[k] ? x->lo[k][i] : bounds->lo[k];
            bounds->hi[k] = x->hi[k][i] > bounds->hi[k] ? x->hi[k][i] : bounds->hi[k];
            range->lo[k] = x->vlo[k][i] < range->lo[k] ? x->vlo[k][i] : range->lo[k];
            range->hi[k] = x->vhi[k][i] > range->hi[k] ? x->vhi[k][i] : range->hi[k];
        }
    for (uint32_t i = 0; i < count; ++i) range->linear = x->linear[i] > range->linear ? x->linear[i] : range->linear;
}

/* Each row's hemisphere, sign[i] = -1 or 1: row 0 flipped when `flip`, and row i flipped when
 * (flipped(i - 1) ? -dot[i] : dot[i]) < 0. Where no dot[i] (i > 0) is zero or NaN, that is the
 * sign of a product: row 0's sign times, for each later row up to i, -1 where dot < 0 and 1
 * where it is above. Products of 1 and -1 are exact, and a prefix product over the lanes in
 * log2(B) steps vectorizes where the chain of compares did not. A zero or NaN ends the chain
 * (the row is not flipped whatever came before): it is a 0 in the product, which then ends
 * in 0, and the rows go one after the other. */
static CB_CLONE_INLINE void row_signs(const double *dot, bool flip, float *sign)
{
    float d[B], p[2][8 + B]; /* p: 8 ones before the lanes, as a shift by up to 8 reads them */
    /* The compares on floats, 8 to a vector: a double's sign survives the conversion, and one
     * so small it becomes 0 only sends the rows one by one. */
    for (int i = 0; i < B; ++i) d[i] = (float)dot[i];
    for (int i = 0; i < 8; ++i) p[0][i] = p[1][i] = 1;
    for (int i = 0; i < B; ++i) p[0][8 + i] = d[i] < 0 ? -1.0f : d[i] > 0 ? 1.0f : 0.0f;
    p[0][8] = flip ? -1.0f : 1.0f; /* lane 0's dot is not used */
    for (int i = 0; i < B; ++i) p[1][8 + i] = p[0][8 + i] * p[0][7 + i];
    for (int i = 0; i < B; ++i) p[0][8 + i] = p[1][8 + i] * p[1][6 + i];
    for (int i = 0; i < B; ++i) p[1][8 + i] = p[0][8 + i] * p[0][4 + i];
    for (int i = 0; i < B; ++i) sign[i] = p[1][8 + i] * p[1][i];
    if (sign[B - 1] != 0) return;
    for (int i = 0; i < B; ++i) {
        if (i) flip = (flip ? -dot[i] : dot[i]) < 0;
        sign[i] = flip ? -1.0f : 1.0f;
    }
}

#if defined(__GNUC__) /* GCC and clang: vector types and __builtin_shufflevector */
typedef float v8sf __attribute__((vector_size(32)));
_Static_assert(B % 8 == 0, "store_rows8 takes a batch's lanes 8 at a time");

/* Lanes first .. first + 7 of a bone's 8 values (v[k][i]: value k of lane i) as 8 rows, to
 * out + m * stride: an 8x8 transpose of 24 shuffles, and each row one 32-byte store where value
 * by value took 8 loads and 8 stores a row. Named vectors, not arrays: they stay in registers. */
static CB_CLONE_INLINE void store_rows8(const float (*v)[B], int first, float *out, size_t stride)
{
    v8sf r0, r1, r2, r3, r4, r5, r6, r7;
    memcpy(&r0, &v[0][first], 32), memcpy(&r1, &v[1][first], 32), memcpy(&r2, &v[2][first], 32);
    memcpy(&r3, &v[3][first], 32), memcpy(&r4, &v[4][first], 32), memcpy(&r5, &v[5][first], 32);
    memcpy(&r6, &v[6][first], 32), memcpy(&r7, &v[7][first], 32);
#define LO(a, b) __builtin_shufflevector(a, b, 0, 8, 1, 9, 4, 12, 5, 13)
#define HI(a, b) __builtin_shufflevector(a, b, 2, 10, 3, 11, 6, 14, 7, 15)
    v8sf t0 = LO(r0, r1), t1 = HI(r0, r1), t2 = LO(r2, r3), t3 = HI(r2, r3);
    v8sf t4 = LO(r4, r5), t5 = HI(r4, r5), t6 = LO(r6, r7), t7 = HI(r6, r7);
#undef LO
#undef HI
#define EVEN(a, b) __builtin_shufflevector(a, b, 0, 1, 8, 9, 4, 5, 12, 13)
#define ODD(a, b) __builtin_shufflevector(a, b, 2, 3, 10, 11, 6, 7, 14, 15)
    /* s_m: values 0-3 of rows m and m + 4; s_m4: values 4-7 of them */
    v8sf s0 = EVEN(t0, t2), s1 = ODD(t0, t2), s2 = EVEN(t1, t3), s3 = ODD(t1, t3);
    v8sf s04 = EVEN(t4, t6), s14 = ODD(t4, t6), s24 = EVEN(t5, t7), s34 = ODD(t5, t7);
#undef EVEN
#undef ODD
#define ROW(a, b) __builtin_shufflevector(a, b, 0, 1, 2, 3, 8, 9, 10, 11)
#define ROW4(a, b) __builtin_shufflevector(a, b, 4, 5, 6, 7, 12, 13, 14, 15)
    v8sf w0 = ROW(s0, s04), w1 = ROW(s1, s14), w2 = ROW(s2, s24), w3 = ROW(s3, s34);
    v8sf w4 = ROW4(s0, s04), w5 = ROW4(s1, s14), w6 = ROW4(s2, s24), w7 = ROW4(s3, s34);
#undef ROW
#undef ROW4
    memcpy(out, &w0, 32), memcpy(out + stride, &w1, 32), memcpy(out + 2 * stride, &w2, 32);
    memcpy(out + 3 * stride, &w3, 32), memcpy(out + 4 * stride, &w4, 32), memcpy(out + 5 * stride, &w5, 32);
    memcpy(out + 6 * stride, &w6, 32), memcpy(out + 7 * stride, &w7, 32);
}

#endif

/* The first `count` lanes of a bone's 8 values as rows, to out + i * stride. */
static CB_CLONE_INLINE void store_rows(const float (*v)[B], uint32_t count, float *out, size_t stride)
{
    uint32_t first = 0;
#if defined(__GNUC__)
    for (; first + 8 <= count; first += 8) store_rows8(v, (int)first, out + first * stride, stride);
#endif
    for (; first < count; ++first) /* a clip's last batch, or no vector types: row by row */
        for (int k = 0; k < 8; ++k) out[first * stride + k] = v[k][first];
}

/* Joint j's pivots over the lanes of its similarities `sim` (e[k][i], k < 3: p = t + s rotate(q,
 * b), b its bind position) and the reach of its vertices (e[3][i]: |s R| r_j = sqrt(3) s r_j). */
static CB_CLONE_INLINE void bone_pivots(const bake_state *st, uint32_t j, const double (*sim)[B], double (*e)[B])
{
    const double *s = sim[7], radius = st->radius[j];
    cb_pivot_lanes(sim, st->p->bind_positions + (size_t)j * 3, e);
    for (int i = 0; i < B; ++i) e[3][i] = radius * s[i] * sqrt(3.0);
}

/* The lanes' bounds grown by a joint's pivots and reach (bone_pivots): every lane (those past
 * count repeat the last frame, and fold_lanes reads count). A joint that moves no vertex
 * (radius < 0) bounds nothing. */
static CB_CLONE_INLINE void grow_lane_bounds(double radius, const double (*e)[B], lane_extent *x)
{
    for (int k = 0; radius >= 0 && k < 3; ++k)
        for (int i = 0; i < B; ++i) {
            double lo = e[k][i] - e[3][i], hi = e[k][i] + e[3][i];
            x->lo[k][i] = lo < x->lo[k][i] ? lo : x->lo[k][i];
            x->hi[k][i] = hi > x->hi[k][i] ? hi : x->hi[k][i];
        }
}

/* One bone at frames f .. f + count - 1, its similarities' lanes `sim` (lanes past count repeat
 * the last frame): its position and reach grow the lanes' bounds, its values their range, its 8
 * values go into the rows and its last quaternion into w->prev. */
static CB_CLONE_INLINE void bone_lanes(bake_state *st, worker *w, uint32_t j, uint32_t f, uint32_t count,
                                       const double (*sim)[B], float *rows, lane_extent *x)
{
    const cb_palette *p = st->p;
    uint32_t bones = p->bone_count;
    const double(*q)[B] = sim, *s = sim[7];
    double dot[B], e[4][B];
    float fq[4][B + 1], v[8][B], (*fp)[B] = v + 4; /* fq: lane i's quaternion as stored at i + 1 (0 at 0); v: the
                                                   * rows' values, lanes of quaternion (below), position, scale (fp) */
    bone_pivots(st, j, sim, e);
    fq[0][0] = fq[1][0] = fq[2][0] = fq[3][0] = 0;
    for (int i = 0; i < B; ++i) {
        fq[0][i + 1] = (float)q[0][i], fq[1][i + 1] = (float)q[1][i], fq[2][i + 1] = (float)q[2][i];
        fq[3][i + 1] = (float)q[3][i];
        fp[0][i] = (float)e[0][i], fp[1][i] = (float)e[1][i], fp[2][i] = (float)e[2][i], fp[3][i] = (float)s[i];
    }
    /* Lane i's quaternion against lane i - 1's as stored (cb_quat_dot's order). Against the
     * stored one negated it is exactly the negation (IEEE rounding is symmetric), so the
     * hemisphere of every row follows from these and the first row's alone. */
    for (int i = 0; i < B; ++i)
        dot[i] = q[0][i] * fq[0][i] + q[1][i] * fq[1][i] + q[2][i] * fq[2][i] + q[3][i] * fq[3][i];
    cb_quat q0 = {q[0][0], q[1][0], q[2][0], q[3][0]};
    bool flip = f ? cb_quat_dot(q0, w->prev[j]) < 0 : q0.w < 0;
    float sign[B]; /* each row's hemisphere */
    row_signs(dot, flip, sign);
    for (int c = 0; c < 4; ++c)
        for (int i = 0; i < B; ++i) v[c][i] = sign[i] * fq[c][i + 1];
    store_rows((const float(*)[B])v, count, rows + (size_t)j * 8, (size_t)bones * 8);
    grow_lane_bounds(st->radius[j], (const double(*)[B])e, x);
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < B; ++i) {
            x->vlo[k][i] = fp[k][i] < x->vlo[k][i] ? fp[k][i] : x->vlo[k][i];
            x->vhi[k][i] = fp[k][i] > x->vhi[k][i] ? fp[k][i] : x->vhi[k][i];
        }
    for (int i = 0; i < B; ++i) x->linear[i] = fp[3][i] > x->linear[i] ? fp[3][i] : x->linear[i];
    const float *last = rows + (size_t)(count - 1) * bones * 8 + (size_t)j * 8;
    w->prev[j] = (cb_quat){last[0], last[1], last[2], last[3]};
}

CB_TARGET_CLONES
void palette_row_signs(const double *dot, bool flip, float *sign) { row_signs(dot, flip, sign); }

CB_TARGET_CLONES
void palette_store_rows(const float (*v)[B], uint32_t count, float *out, size_t stride) { store_rows(v, count, out, stride); }

/* A batch's rows in the making: what bone_lanes takes besides a joint's lanes. */
typedef struct rows_in_making {
    bake_state *st;
    worker *w;
    uint32_t f, count;
    float *rows;
    lane_extent x;
    double *keep; /* where each joint's lanes are kept (palette_row_lanes_keep), or NULL */
    double *local; /* a local bake's: each joint's global qpos lanes (q, pivot, s) for local_rows_from_lanes, or NULL */
} rows_in_making;

/* A local bake's joint: its pivots and reach grow the bounds as bone_lanes grows them, and its
 * global qpos (q, the pivots, s) waits for local_rows_from_lanes, which writes the rows. */
static CB_CLONE_INLINE void joint_into_local(rows_in_making *r, uint32_t j, const double (*lanes)[B])
{
    double e[4][B], *g = r->local + (size_t)j * 8 * B;
    bone_pivots(r->st, j, lanes, e);
    grow_lane_bounds(r->st->radius[j], (const double(*)[B])e, &r->x);
    memcpy(g, lanes, 4 * B * sizeof(double));
    memcpy(g + 4 * B, e, 3 * B * sizeof(double));
    memcpy(g + 7 * B, lanes[7], B * sizeof(double));
}

/* The sampler's sink (cb_clip_frame_lanes_each): each joint into the rows as it is sampled,
 * its lanes still in cache, in joint order as before. */
CB_TARGET_CLONES
static void joint_into_rows(void *ctx, uint32_t j, double (*lanes)[B])
{
    rows_in_making *r = ctx;
    if (r->local) joint_into_local(r, j, (const double(*)[B])lanes);
    else bone_lanes(r->st, r->w, j, r->f, r->count, (const double(*)[B])lanes, r->rows, &r->x);
    if (r->keep) memcpy(r->keep + (size_t)j * 8 * B, lanes, 8 * B * sizeof(double));
}

CB_TARGET_CLONES
void palette_similarity_rows(bake_state *st, worker *w, uint32_t c, uint32_t f, uint32_t count, float *rows,
                             extent *clip_bounds)
{
    /* The joints' similarities as lanes (the sampler's layout: no transposing on either side),
     * each joint into the rows as soon as it is sampled (joint_into_rows). */
    uint32_t frames[B];
    for (uint32_t i = 0; i < count; ++i) frames[i] = f + i;
    rows_in_making r = {.st = st, .w = w, .f = f, .count = count, .rows = rows, .keep = palette_row_lanes_keep(st, c, f),
                        .local = st->local && st->local->sampled[c] ? w->local_lanes : NULL};
    lane_extent_reset(&r.x);
    cb_clip_frame_lanes_each(w->sampler, &st->infos[c], frames, count, st->opt->root_motion, joint_into_rows, &r);
    if (r.keep) palette_row_lanes_kept(st, f, count, r.keep);
    if (r.local) local_rows_from_lanes(st, w, c, f, count, rows);
    /* Bounds and ranges in frame order, as one row at a time grows them (of +0 and -0, the
     * minimum is the one met first). Locals, kept in registers. */
    extent bounds = *clip_bounds;
    value_range range = st->ranges[c];
    fold_lanes(&r.x, count, &bounds, &range);
    *clip_bounds = bounds;
    st->ranges[c] = range;
}

/* ---- a probe's rows' lanes, for its baked rows' measurement (palette_bake.h) ---- */

/* The lanes kept of a search thread's rows, at most this much (Fox's Run at 120 fps: 221 KB). */
#define ROW_LANES_BYTES ((size_t)4 << 20)

struct row_lanes {
    cb_clip_info framing;       /* the rows' clip framing (framed_alike) */
    cb_root_motion root_motion;
    uint32_t bones, batches;    /* the framing's batches of CB_SAMPLE_BATCH rows */
    size_t room;                /* the doubles `lanes` holds (and `count` a batch's worth of them) */
    uint32_t *count;            /* per batch: its rows kept (0: none yet) */
    double *lanes;              /* per batch, bones x 8 x CB_SAMPLE_BATCH: each joint's lanes */
};

void palette_row_lanes_free(struct row_lanes *l)
{
    if (l) free(l->count), free(l->lanes);
    free(l);
}

static bool lanes_match(const struct row_lanes *l, const bake_state *st, uint32_t c)
{
    return l->root_motion == st->opt->root_motion && l->bones == st->p->bone_count &&
           framed_alike(&l->framing, &st->infos[c]);
}

/* The thread's kept lanes made ready for clip c's framing: those of the same framing stay (the
 * same poses), another's are forgotten. NULL: not kept (no search, too large, out of memory). */
static struct row_lanes *row_lanes_for(bake_state *st, uint32_t c)
{
    struct row_lanes **slot = pose_batch_row_lanes(st->batch), *l = *slot;
    if (l && lanes_match(l, st, c)) return l;
    uint32_t bones = st->p->bone_count, batches = (st->infos[c].frames + B - 1) / B;
    size_t doubles = (size_t)batches * bones * 8 * B;
    if (doubles * sizeof(double) > ROW_LANES_BYTES) return NULL;
    if (!l || l->room < doubles || l->bones != bones) { /* room for these rows (a count for each batch it holds) */
        palette_row_lanes_free(l);
        *slot = l = calloc(1, sizeof *l);
        if (l) l->lanes = malloc(doubles * sizeof(double)), l->count = malloc(batches * sizeof *l->count), l->room = doubles;
        if (l && (!l->lanes || !l->count)) palette_row_lanes_free(l), *slot = l = NULL;
        if (!l) return NULL;
    }
    l->framing = st->infos[c], l->root_motion = st->opt->root_motion, l->bones = bones, l->batches = batches;
    memset(l->count, 0, batches * sizeof *l->count);
    return l;
}

double *palette_row_lanes_keep(bake_state *st, uint32_t c, uint32_t f)
{
    if (!st->batch || f % B) return NULL; /* only a search's probe keeps them */
    struct row_lanes *l = row_lanes_for(st, c);
    if (!l || f / B >= l->batches) return NULL;
    l->count[f / B] = 0; /* until the batch is sampled */
    return l->lanes + (size_t)(f / B) * l->bones * 8 * B;
}

void palette_row_lanes_kept(bake_state *st, uint32_t f, uint32_t count, const double *at)
{
    struct row_lanes *l = *pose_batch_row_lanes(st->batch);
    if (l && at == l->lanes + (size_t)(f / B) * l->bones * 8 * B) l->count[f / B] = count;
}

const double *palette_row_lanes_find(const bake_state *st, uint32_t c, const uint32_t *frames, uint32_t count)
{
    const struct row_lanes *l = st->batch ? *pose_batch_row_lanes(st->batch) : NULL;
    if (!l || count == 0 || frames[0] % B || !lanes_match(l, st, c)) return NULL;
    uint32_t b = frames[0] / B;
    if (b >= l->batches || l->count[b] != count) return NULL;
    for (uint32_t i = 1; i < count; ++i)
        if (frames[i] != frames[0] + i) return NULL;
    return l->lanes + (size_t)b * l->bones * 8 * B;
}
