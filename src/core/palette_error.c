/* palette_error.c - a bake's error: every vertex skinned exactly (float64) from the glTF
 * against the palette as the runtime decodes it, at the baked rows and halfway between them. */
#include <stdlib.h>
#include <string.h>

#include "error_bound.h"
#include "measure_lanes.h"
#include "palette_bake.h"
#include "sampler.h"
#include "internal/plumbing.h"

/* Decoded palette rows a measurement keeps: a batch's rows and the rows after them, so that
 * the baked rows of a batch and the blends between them and their next decode each row once. */
enum { VALUE_SLOTS = 2 * CB_SAMPLE_BATCH };
/* Or every row of the clip in hand, where that takes at most this much (in a bake of many clips,
 * and in a search's probes, whose scratch the search thread keeps): the passes over a clip
 * (each quarter point of fitted rows, the baked rows, the rows sorted by bound) read its rows
 * about 7 times (Cow's final bake: 6,915 decodes of 1,014 rows), each decoded once instead. */
#define VALUE_TABLE_BYTES ((size_t)4 << 20)

/* A measurement's scratch: one row's differences, their bound terms and its group bounds. */
struct measure_scratch {
    double *diff;                      /* CB_SAMPLE_BATCH rows of bones * 16 */
    cb_joint_error *joints;            /* CB_SAMPLE_BATCH rows of bones: the differences' bound terms */
    double *group_bounds;              /* groups */
    cb_bounded_row *rows;              /* the clip's frames */
    cb_bounded_row *baked;             /* the clip's frames: the baked rows measured with the blends */
    double *exact;                     /* CB_SAMPLE_BATCH rows of bones * 16: exact matrices no pose cache kept */
    double *values;                    /* VALUE_SLOTS (or table_rows) * bones * 16: decoded palette rows */
    uint32_t table_rows, table_first;  /* > 0: values holds row table_first + k at k (the clip's), else slots */
    unsigned char *table_decoded;      /* table_rows flags: row k decoded */
    uint32_t bones, groups, frames;    /* what it has room for: bones, vertex groups, a clip's rows */
    uint32_t value_row[VALUE_SLOTS];   /* which row each slot holds (UINT32_MAX: none) */
    uint64_t value_read[VALUE_SLOTS];  /* when each slot was last read (0: never) */
    uint64_t reads;                    /* the reads so far: the clock of value_read */
    bool finite[CB_SAMPLE_BATCH];      /* per row: every difference finite (else no bound holds) */
    uint32_t worst_frame, worst_sub;   /* the blend that last raised a measurement's worst (sub 0: none) */
    double *note_caps;                 /* a probe's baked rows measured: each row's cap noted here by frame, or NULL */
    unsigned char *block;              /* what the arrays above lie in */
};
typedef struct measure_scratch measure_scratch;

/* Slot k's values, read now. */
static const double *read_slot(const cb_palette *p, measure_scratch *s, uint32_t k)
{
    s->value_read[k] = ++s->reads;
    return s->values + (size_t)k * p->bone_count * 16;
}

/* Palette row `row` decoded, from whichever slot holds it, else decoded into the slot read
 * least recently: never the other row of the blend in hand, read just before. */
static const double *row_values(const cb_palette *p, measure_scratch *s, uint32_t row)
{
    if (s->table_rows) { /* every row of the clip: decoded at its first read */
        uint32_t k = row - s->table_first;
        double *values = s->values + (size_t)k * p->bone_count * 16;
        if (!s->table_decoded[k]) palette_decode_row_values(p, row, values), s->table_decoded[k] = 1;
        return values;
    }
    uint32_t oldest = 0;
    for (uint32_t k = 0; k < VALUE_SLOTS; ++k) {
        if (s->value_row[k] == row) return read_slot(p, s, k);
        if (s->value_read[k] < s->value_read[oldest]) oldest = k;
    }
    palette_decode_row_values(p, row, s->values + (size_t)oldest * p->bone_count * 16);
    s->value_row[oldest] = row;
    return read_slot(p, s, oldest);
}

/* A row's cap on its group bounds (cb_row_error_cap): `known` where a caller has it already (NaN:
 * not known, worked out here; the cap itself NaN is worked out again, to the same NaN). */
static double row_cap(const bake_state *st, const cb_joint_error *joints, double known)
{
    return !isnan(known) ? known : cb_row_error_cap(joints, st->p->bone_count, st->facts->group_reach, st->facts->weight_sum);
}

/* A row's bound, from its differences' terms `joints`: its largest group bound (infinite when a
 * difference is not finite), or its cap on them all where that is within `worst` (the row
 * cannot exceed the worst either way, and the cap takes O(bones) where the groups take
 * O(their joints)). The cap into *cap (NaN where not finite), for skin_row. */
static double row_bound(const bake_state *st, const cb_joint_error *joints, bool finite, double worst, double *cap_out)
{
    *cap_out = NAN;
    if (!finite) return INFINITY;
    double cap = *cap_out = row_cap(st, joints, NAN);
    if (cap <= worst) return cap;
    double most = 0;
    for (uint32_t k = 0; k < st->groups->group_count; ++k) {
        double bound = cb_group_error_bound(st->groups, k, joints, most);
        most = bound > most ? bound : most; /* fmax(most, bound): most is never NaN */
    }
    return most;
}

/* The worst vertex error of one row, or `worst` when none exceeds it: the group with the
 * largest bound first (it most likely holds the row's worst), then each group whose bound
 * exceeds the worst so far. The groups skipped cannot change the maximum, which is the one
 * skinning every vertex gives, bit for bit. A row whose cap on all the group bounds is within
 * the worst skips them all (a baked row against the blends' worst: its encoding errs far less). */
static double skin_row(const bake_state *st, measure_scratch *s, const double *diff, const cb_joint_error *joints,
                       bool finite, double worst, double cap)
{
    const cb_vertex_groups *g = st->groups;
    if (finite && row_cap(st, joints, cap) <= worst) return worst;
    uint32_t top = 0;
    for (uint32_t k = 0; k < g->group_count; ++k) {
        s->group_bounds[k] = finite ? cb_group_error_bound(g, k, joints, worst) : INFINITY;
        if (s->group_bounds[k] > s->group_bounds[top]) top = k;
    }
    for (uint32_t n = 0; n <= g->group_count; ++n) {
        uint32_t k = n ? n - 1 : top;
        if ((n && k == top) || s->group_bounds[k] <= worst) continue;
        const cb_vertex_group *grp = &g->groups[k];
        const cb_primitive *prim = &st->model->primitives[grp->primitive];
        /* fmax's result without its call: worst is never NaN, and a NaN error leaves it as fmax does */
        double error = sqrt(cb_skin_group_worst(prim, g->vertices + grp->first, grp->count, diff));
        worst = error > worst ? error : worst;
    }
    return worst;
}

/* `now`, the worst after a blend's row `frame` at `sub` was skinned against `was`: where it
 * rose, that blend is noted (a probe's worst point, pose_cache_note_worst). */
static double note_worst(measure_scratch *s, uint32_t frame, uint32_t sub, double was, double now)
{
    if (sub && now > was) s->worst_frame = frame, s->worst_sub = sub;
    return now;
}

#define B CB_SAMPLE_BATCH

/* What palette_bone_differences takes besides the joint and its lanes, for a batch of rows. */
typedef struct differences {
    const cb_palette *p;
    const double *const *mats, *const *a, *const *b;
    uint32_t count;
    double fr;
    measure_scratch *s;
} differences;

/* Joint j's differences from its similarities' lanes, or from the matrices where lanes is NULL;
 * the sampler's sink (cb_clip_frame_lanes_each) for rigs of similarities. */
static void joint_differences(void *ctx, uint32_t j, double (*lanes)[B])
{
    const differences *d = ctx;
    palette_bone_differences(d->p, j, (const double(*)[B])lanes, d->mats, d->a, d->b, d->count, d->fr, d->s->diff,
                             d->s->joints, d->s->finite);
}

/* The order a batch's rows are skinned in, into order: with `by_cap` (their differences in hand),
 * the largest cap on a row's error first (cb_row_error_cap; a row with a difference not finite
 * before all), so that the worst rises early and the rows after skip more groups; else as they
 * come. The maximum is the same in any order: a row or group skipped cannot exceed it. */
static void rows_by_cap(const bake_state *st, const measure_scratch *s, uint32_t count, bool by_cap, uint32_t *order,
                        double *caps)
{
    double cap[B];
    for (uint32_t i = 0; i < count; ++i) {
        const cb_joint_error *joints = s->joints + (size_t)i * st->p->bone_count;
        cap[i] = !by_cap ? 0 : !s->finite[i] ? INFINITY : row_cap(st, joints, NAN);
        caps[i] = by_cap && s->finite[i] ? cap[i] : NAN; /* skin_row's, not worked out twice */
        uint32_t k = i;
        for (; k > 0 && cap[order[k - 1]] < cap[i]; --k) order[k] = order[k - 1];
        order[k] = i;
    }
}

/* Clip c's joint matrices at `frame` of framing (palette_frame_matrices), where they stay until
 * the measurement's next batch: a pose cache's, or copied into `room` (the worker's matrices
 * are sampled over at its next call). */
static const double *exact_matrices(bake_state *st, worker *w, uint32_t c, const cb_clip_info *framing, uint32_t frame,
                                    double *room)
{
    const double *mats = palette_frame_matrices(st, w, c, framing, frame, NULL);
    if (mats != w->mats) return mats;
    memcpy(room, mats, (size_t)st->p->bone_count * 16 * sizeof(double));
    return room;
}

/* Whether fraction sub / parts of a row interval is a fitted probe's quarter point (1/4, 3/4).
 * Such a pose is read by its probe's measurement and seldom again: the probe's mid-rows and
 * every sampled probe's rows and blends lie on the halves, and a quarter point is a row only of
 * a probe at 4 times the rate. Kept, they were the search's largest share of fresh memory, which
 * the kernel clears before its first use (Cow: 1,450 of the 4,751 poses its search kept, 1,290
 * of them read once; Husky 1,026 of 3,359, 785): they are sampled into the measurement's scratch
 * instead, and sampled again where read again (the same bits). */
static bool quarter_point(uint32_t sub, uint32_t parts)
{
    return parts == 4 && sub % 2 == 1;
}

/* The worst vertex error of the given rows of clip c (parts = 1), or between each of them and
 * the next at fraction sub / parts, blended as the runtime does, or `worst` when none exceeds
 * it; with `bounds`, each row's bound, and the worst of the row with the largest where that is
 * cheap (see the end; the others are left for later). Skinning is linear in the matrices, so
 * one skinning with (exact - decoded) gives each vertex's error directly: half the work of
 * skinning twice, and no cancellation. Rows baked from similarities are measured against those, sampled
 * together like the bake did, every row's differences at once (palette_bone_differences). */
CB_TARGET_CLONES
static double measure_rows(bake_state *st, worker *w, uint32_t c, const uint32_t *frames, uint32_t count,
                           uint32_t sub, uint32_t parts, measure_scratch *s, double *bounds, double worst)
{
    cb_palette *p = st->p;
    const cb_palette_clip *clip = &p->clips[c];
    /* Fraction sub / parts between rows f and f + 1 is row parts * f + sub of the clip framed at
     * `parts` times the steps. */
    cb_clip_info framing = st->infos[c];
    uint32_t times[B];
    for (uint32_t i = 0; i < count; ++i) times[i] = parts * frames[i] + sub;
    framing.steps *= parts;
    bool similar = p->layout == CB_LAYOUT_QPOS && cb_sampler_is_similarity(w->sampler);
    /* qpos rows: every row's differences at once, over the lanes (palette_bone_differences) */
    bool lanes = p->layout == CB_LAYOUT_QPOS;
    bool blend = sub && !clip->step; /* a stepped clip's runtime holds row f until row f + 1 */
    if (lanes) {
        const double *mats[B] = {NULL};
        bool unkept = !similar && quarter_point(sub, parts); /* read once: sampled into the scratch, not kept */
        if (unkept) palette_unkept_poses(st, w, c, &framing, times, count, s->exact, mats);
        else if (!similar) palette_prefetch_poses(st, w, c, &framing, times, count); /* the rows' poses at once, where kept */
        for (uint32_t i = 0; !similar && !unkept && i < count; ++i)
            mats[i] = exact_matrices(st, w, c, &framing, times[i], s->exact + (size_t)i * p->bone_count * 16);
        for (uint32_t i = count; !similar && i < B; ++i) mats[i] = mats[count - 1];
        const double *a[B], *b[B]; /* at most 2 B rows: all in the slots at once */
        for (uint32_t i = 0; i < count; ++i) {
            a[i] = row_values(p, s, clip->first_row + frames[i]);
            b[i] = blend ? row_values(p, s, clip->first_row + (frames[i] + 1) % clip->frames) : NULL;
        }
        for (uint32_t i = count; i < B; ++i) a[i] = a[count - 1], b[i] = b[count - 1]; /* lanes past count repeat the last */
        for (uint32_t i = 0; i < count; ++i) s->finite[i] = true;
        differences d = {p, mats, a, blend ? b : NULL, count, (double)sub / parts, s};
        /* Baked rows whose lanes their probe kept: the poses the rows were made from, in joint order */
        const double *kept = similar && !sub && parts == 1 ? palette_row_lanes_find(st, c, frames, count) : NULL;
        for (uint32_t j = 0; kept && j < p->bone_count; ++j)
            palette_bone_differences(p, j, (const double(*)[B])(kept + (size_t)j * 8 * B), d.mats, d.a, d.b, d.count,
                                     d.fr, s->diff, s->joints, s->finite);
        if (similar && !kept) /* each joint measured as soon as the sampler has it, as the bake's rows are made */
            cb_clip_frame_lanes_each(w->sampler, &framing, times, count, st->opt->root_motion, joint_differences, &d);
        for (uint32_t j = 0; !similar && j < p->bone_count; ++j) joint_differences(&d, j, NULL);
    }
    uint32_t order[B];
    double caps[B]; /* each row's cap where in hand (NaN: not) */
    rows_by_cap(st, s, count, lanes && !bounds, order, caps);
    for (uint32_t i = 0; !sub && s->note_caps && i < count; ++i) s->note_caps[frames[i]] = caps[i]; /* NaN: none */
    for (uint32_t n = 0; n < count; ++n) {
        uint32_t i = order[n];
        double *diff = lanes ? s->diff + (size_t)i * p->bone_count * 16 : s->diff;
        const cb_joint_error *joints = lanes ? s->joints + (size_t)i * p->bone_count : s->joints;
        if (!lanes) {
            const double *mats = palette_frame_matrices(st, w, c, &framing, times[i], NULL);
            uint32_t row = clip->first_row + frames[i], next = clip->first_row + (frames[i] + 1) % clip->frames;
            const double *a = row_values(p, s, row), *b = blend ? row_values(p, s, next) : NULL;
            for (uint32_t j = 0; j < p->bone_count; ++j) {
                double decoded[16], *d = diff + (size_t)j * 16;
                const double *exact = mats + (size_t)j * 16;
                if (blend) palette_blend_values(p, j, a + (size_t)j * 16, b + (size_t)j * 16, (double)sub / parts, decoded);
                else cb_palette_values_to_matrix(p, j, a + (size_t)j * 16, decoded);
                for (int k = 0; k < 16; ++k) d[k] = exact[k] - decoded[k];
            }
        }
        bool finite = lanes ? s->finite[i] : cb_joint_errors(diff, p->bone_count, p->bind_positions, s->joints);
        if (bounds) bounds[i] = row_bound(st, joints, finite, worst, &caps[i]);
        else worst = note_worst(s, frames[i], sub, worst, skin_row(st, s, diff, joints, finite, worst, caps[i]));
    }
    /* The rows' likeliest worst skinned at once where that costs no sampling (qpos rows: every
     * row's differences are in hand), and with a goal (a row above it ends
     * the clip; rows of other layouts sampled again). Its bound becomes the worst after it, which
     * holds its error, so it is not measured again. Without a goal the order rows are skinned in
     * does not change the maximum (a row skipped cannot exceed the worst). */
    uint32_t top = 0;
    for (uint32_t i = 1; bounds && i < count; ++i) top = bounds[i] > bounds[top] ? i : top;
    if (bounds && bounds[top] > worst && (lanes || st->opt->error_goal > 0)) {
        size_t at = (size_t)top * p->bone_count;
        if (lanes) {
            double skinned = skin_row(st, s, s->diff + at * 16, s->joints + at, s->finite[top], worst, caps[top]);
            worst = note_worst(s, frames[top], sub, worst, skinned);
        } else {
            worst = measure_rows(st, w, c, frames + top, 1, sub, parts, s, NULL, worst);
        }
        bounds[top] = worst;
    }
    return worst;
}

enum { SCOUT_ROWS = 8 }; /* rows a measurement with a goal tries first */

/* The frames of clip c measured at fraction sub (every error_stride-th and the last; at sub > 0
 * a one-shot's last row has no next), into rows; returns how many. */
static uint32_t measured_frames(const bake_state *st, uint32_t c, uint32_t sub, cb_bounded_row *rows)
{
    const cb_palette_clip *clip = &st->p->clips[c];
    uint32_t frames = sub && !clip->loops ? clip->frames - 1 : clip->frames, n = 0;
    for (uint32_t f = 0; f < frames; ++f)
        if (f % st->error_stride == 0 || f + 1 == frames) rows[n++].frame = f;
    return n;
}

/* measure_rows over the frames of rows[i ..], a batch of them (fewer at the end of n). */
static double measure_batch(bake_state *st, worker *w, uint32_t c, const cb_bounded_row *rows, uint32_t i, uint32_t n,
                            uint32_t sub, uint32_t parts, measure_scratch *s, double *bounds, double worst)
{
    uint32_t batch[CB_SAMPLE_BATCH], count = n - i < CB_SAMPLE_BATCH ? n - i : CB_SAMPLE_BATCH;
    for (uint32_t k = 0; k < count; ++k) batch[k] = rows[i + k].frame;
    return measure_rows(st, w, c, batch, count, sub, parts, s, bounds, worst);
}

/* The rows that could exceed `worst` (bound above it) moved to the front, in order of bound
 * (cb_sort_bounded_rows' order); returns how many. The walk over them (measure_clip_rows) stops
 * at the first row whose bound is within the worst, which only rises: sorting every row put
 * these first in this same order (bounds ordered, ties by frame, and each frame once: one order
 * whatever the sort), and the rest are never read. Cow's search sorted every row of its probes
 * for a handful it measured. A NaN bound orders nothing: every row sorted, as before. */
static uint32_t sort_rows_over(cb_bounded_row *rows, uint32_t n, double worst)
{
    for (uint32_t i = 0; i < n; ++i)
        if (isnan(rows[i].bound)) return cb_sort_bounded_rows(rows, n), n;
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i)
        if (rows[i].bound > worst) {
            cb_bounded_row r = rows[i];
            rows[i] = rows[m], rows[m++] = r;
        }
    if (m > 32) return cb_sort_bounded_rows(rows, m), m;
    for (uint32_t x = 1; x < m; ++x) /* by_bound's order: larger bound first, then lower frame */
        for (uint32_t y = x; y > 0 && (rows[y - 1].bound < rows[y].bound ||
                                       (rows[y - 1].bound == rows[y].bound && rows[y - 1].frame > rows[y].frame)); --y) {
            cb_bounded_row r = rows[y];
            rows[y] = rows[y - 1], rows[y - 1] = r;
        }
    return m;
}

/* A measurement's blends bounded before (kept, with the shift any blend's error may have moved by
 * since: palette_taken_point_bounds), or to bound for the bake after (note: a probe's,
 * palette_pending_point_bounds): one fraction's bound per row interval, each NULL for none. */
typedef struct point_bounds {
    const double *kept;
    double shift;
    double *note;
} point_bounds;

/* Whether a point's kept bound, moved by the shift, is within `floor`: its error in this palette
 * cannot exceed it (it is at most the probe's plus the shift). A NaN bound is never within. */
static bool bounded_within(double kept, double shift, double floor) { return kept + shift <= floor; }

/* The rows bounded within `floor` left out of rows[0 .. n), the others in their order; returns
 * how many are left. */
static uint32_t drop_bounded(cb_bounded_row *rows, uint32_t n, const double *kept, double shift, double floor)
{
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i)
        if (!bounded_within(kept[rows[i].frame], shift, floor)) rows[m++] = rows[i];
    return m;
}

/* The worst vertex error of clip c over every error_stride-th row and the last (sub > 0: at
 * fraction sub / parts from each of those rows to the next, as the runtime blends them; a
 * one-shot's last row has no next). Rows that cannot exceed `floor` are not measured (0 when
 * none may be skipped): the result is exact when above it. With an error goal, measuring also
 * stops once the worst exceeds it. With `baked` (sub > 0, no goal), the baked rows' worst error
 * too, into *baked: their batches measured along the blends' bounds, which decode the same rows.
 * With pb (sub > 0), the blends' bounds noted once every row has one, and the blends whose kept
 * bound cannot reach `floor` left out before any is sampled (drop_bounded).
 *
 * Blends err most where the motion is fastest, so their rows' bounds differ widely: branch and
 * bound - every row's bound first, then the rows in order of bound, largest first, until no row
 * left can exceed the worst found - samples few rows twice. The baked rows' encoding error is
 * much the same on every row, and so are their bounds: those rows are measured in one pass in
 * frame order, each skinning only its groups that could exceed the worst so far. */
static double measure_clip_rows(bake_state *st, worker *w, uint32_t c, uint32_t sub, uint32_t parts, double floor,
                                measure_scratch *s, double *baked, const point_bounds *pb)
{
    cb_bounded_row *rows = s->rows;
    uint32_t n = measured_frames(st, c, sub, rows), batch[CB_SAMPLE_BATCH];
    if (sub && pb && pb->kept) n = drop_bounded(rows, n, pb->kept, pb->shift, floor);
    double bounds[CB_SAMPLE_BATCH], worst = floor, goal = st->opt->error_goal;
    for (uint32_t i = 0; i < n && !sub && !(goal > 0 && worst > goal); i += CB_SAMPLE_BATCH)
        worst = measure_batch(st, w, c, rows, i, n, 0, 1, s, NULL, worst);
    if (!sub) return worst;
    /* With a goal, a few rows spread over the clip first: a rate that misses its goal mostly
     * misses it over much of the clip, and one row above the goal decides - every row's bound,
     * an exact sample each, is then not needed (Cow --fps auto: most probes fail). What the
     * scouts find is measured, so as the floor it leaves the maximum exact. */
    if (goal > 0 && n > SCOUT_ROWS) {
        for (uint32_t k = 0; k < SCOUT_ROWS; ++k) batch[k] = rows[(size_t)k * n / SCOUT_ROWS].frame;
        worst = measure_rows(st, w, c, batch, SCOUT_ROWS, sub, parts, s, NULL, worst);
        if (worst > goal) return worst;
    }
    uint32_t nb = baked ? measured_frames(st, c, 0, s->baked) : 0;
    for (uint32_t i = 0; i < n || i < nb; i += CB_SAMPLE_BATCH) {
        if (i < nb) *baked = measure_batch(st, w, c, s->baked, i, nb, 0, 1, s, NULL, *baked);
        if (i >= n) continue;
        uint32_t count = n - i < CB_SAMPLE_BATCH ? n - i : CB_SAMPLE_BATCH;
        worst = measure_batch(st, w, c, rows, i, n, sub, parts, s, bounds, worst);
        for (uint32_t k = 0; k < count; ++k) rows[i + k].bound = bounds[k];
        if (goal > 0 && worst > goal) return worst;
    }
    for (uint32_t k = 0; pb && pb->note && k < n; ++k) pb->note[rows[k].frame] = rows[k].bound; /* every row bounded */
    n = sort_rows_over(rows, n, worst);
    /* Batches of 1, 2, 4, ... rows: often the first few rows settle it. */
    for (uint32_t i = 0, size = 1; i < n && rows[i].bound > worst && !(goal > 0 && worst > goal); size *= 2) {
        uint32_t count = 0;
        for (; i < n && count < size && count < CB_SAMPLE_BATCH && rows[i].bound > worst; ++i) batch[count++] = rows[i].frame;
        for (uint32_t x = 1; x < count; ++x) /* increasing frames, as the batched sampler wants them */
            for (uint32_t y = x; y > 0 && batch[y - 1] > batch[y]; --y) {
                uint32_t swap = batch[y];
                batch[y] = batch[y - 1], batch[y - 1] = swap;
            }
        worst = measure_rows(st, w, c, batch, count, sub, parts, s, NULL, worst);
    }
    return worst;
}

/* Without a goal, a clip's blends and its baked rows are two jobs while clips are few for the
 * threads (fewer than 2 each), so that the threads share the work more evenly; else one job,
 * which decodes each measured row once for both. The results are the same either way. */
static bool measure_split(const bake_state *st)
{
    uint32_t threads = st->opt->threads ? st->opt->threads : 1; /* a clip's kept poses are one worker's */
    return !(st->opt->error_goal > 0) && !st->clip_poses && st->p->clip_count < 2 * threads;
}

uint32_t palette_measure_jobs(const bake_state *st)
{
    return measure_split(st) ? 2 * st->p->clip_count : st->p->clip_count;
}

void palette_measure_scratch_free(measure_scratch *s)
{
    if (s) free(s->block);
    free(s);
}

/* `bytes` more of the scratch block, 64-byte aligned, at *at. */
static void *carve(unsigned char *block, size_t *at, size_t bytes)
{
    void *p = block + *at;
    *at += (bytes + 63) / 64 * 64;
    return p;
}

/* The values a scratch holds forgotten: a job's rows (clip c's) are not the last job's. */
static measure_scratch *begin_job(const bake_state *st, measure_scratch *s, uint32_t c)
{
    for (uint32_t i = 0; i < VALUE_SLOTS; ++i) s->value_row[i] = UINT32_MAX, s->value_read[i] = 0;
    if (s->table_rows) memset(s->table_decoded, 0, s->table_rows);
    s->table_first = st->p->clips[c].first_row;
    s->reads = 0;
    s->worst_sub = 0;
    return s;
}

/* Whether scratch s has room for st's measurement: a search thread's is kept across its probes,
 * whose clips and rates differ. */
static bool scratch_fits(const bake_state *st, const measure_scratch *s)
{
    return s->bones == st->p->bone_count && s->groups == st->groups->group_count && s->frames >= st->max_clip_frames;
}

/* The worker's scratch for a job, made by its first job for the longest clip; in a search's probe
 * (st->batch, one worker), the search thread's, kept across its probes with its batches of poses
 * and made again only for more rows (room for twice as many: its later probes bake higher rates).
 * NULL when out of memory. One block for all of it (cb_alloc_large: 1.4 MB for 200 bones is a
 * whole huge page, where six blocks of 4 KB pages took 350 page faults of fresh memory a thread). */
static measure_scratch *worker_scratch(const bake_state *st, worker *w, uint32_t c)
{
    measure_scratch **kept = st->batch ? pose_batch_measure(st->batch) : &w->measure;
    if (*kept && scratch_fits(st, *kept)) return begin_job(st, *kept, c);
    palette_measure_scratch_free(*kept), *kept = NULL;
    const cb_palette *p = st->p;
    size_t matrices = (size_t)p->bone_count * 16 * sizeof(double);
    uint32_t frames = st->batch ? 2 * st->max_clip_frames : st->max_clip_frames;
    bool table = (st->batch || !st->poses) && frames > VALUE_SLOTS && frames * matrices <= VALUE_TABLE_BYTES;
    uint32_t slots = table ? frames : VALUE_SLOTS;
    size_t sizes[8] = {
        CB_SAMPLE_BATCH * matrices, slots * matrices, CB_SAMPLE_BATCH * p->bone_count * sizeof(cb_joint_error),
        (st->groups->group_count + 1) * sizeof(double), frames * sizeof(cb_bounded_row),
        frames * sizeof(cb_bounded_row), CB_SAMPLE_BATCH * matrices, table ? slots : 0};
    size_t total = 0;
    for (int i = 0; i < 8; ++i) total += (sizes[i] + 63) / 64 * 64;
    measure_scratch *s = calloc(1, sizeof *s);
    if (s) s->block = cb_alloc_large(total);
    if (!s || !s->block) {
        palette_measure_scratch_free(s);
        return NULL;
    }
    size_t at = 0;
    s->diff = carve(s->block, &at, sizes[0]), s->values = carve(s->block, &at, sizes[1]);
    s->joints = carve(s->block, &at, sizes[2]), s->group_bounds = carve(s->block, &at, sizes[3]);
    s->rows = carve(s->block, &at, sizes[4]), s->baked = carve(s->block, &at, sizes[5]);
    s->exact = carve(s->block, &at, sizes[6]), s->table_decoded = carve(s->block, &at, sizes[7]);
    s->table_rows = table ? slots : 0;
    s->bones = p->bone_count, s->groups = st->groups->group_count, s->frames = frames;
    return begin_job(st, *kept = s, c);
}

/* A probe of clip c (a search's bake of it alone) measured its blends: where their worst was, for
 * the bake after the search (blend_floor), where the value is exact (no goal, or within it). */
static void keep_worst_point(bake_state *st, uint32_t c, uint32_t parts, const measure_scratch *s, double blend)
{
    double goal = st->opt->error_goal;
    if (st->poses && s->worst_sub && (!(goal > 0) || blend <= goal))
        pose_cache_note_worst(st->poses, (pose_worst){st->p->clips[c].frames, parts, s->worst_frame, s->worst_sub});
}

/* A floor for clip c's blends: the worst of the one blend where its rate search's probe of the
 * same rows found its worst, measured in this palette (0 when none). u16 quantizes every clip
 * in the file's box, so the bake's errors are not the probe's; but the probe's worst point
 * mostly stays the worst, and measured first it lets the bounds skip nearly every other row.
 * Exact: the point is one of those the measurement takes (measured_frames), measured by the
 * same code (a row's lanes are its own, whatever the batch), so the maximum is the same bits. */
static double blend_floor(bake_state *st, worker *w, uint32_t c, uint32_t parts, measure_scratch *s)
{
    const cb_palette_clip *clip = &st->p->clips[c];
    const pose_cache *poses = st->clip_poses && !st->poses ? st->clip_poses[c] : NULL;
    pose_worst at;
    if (!poses || !pose_cache_worst(poses, clip->frames, parts, &at)) return 0;
    uint32_t frames = clip->loops ? clip->frames : clip->frames - 1; /* a one-shot's last row has no next */
    bool measured = at.frame % st->error_stride == 0 || at.frame + 1 == frames;
    if (!at.sub || at.sub >= parts || at.frame >= frames || !measured) return 0;
    return measure_rows(st, w, c, &at.frame, 1, at.sub, parts, s, NULL, 0);
}

/* Clip c's baked rows whose kept caps (moved by the shift) are not within `within` but are within
 * `taken` (INFINITY: every one), measured from `worst`: the rows left out cannot exceed `within`.
 * The bake after a search leaves out those within the clip's blends, which cannot raise its
 * visible error, then measures those of them that could still exceed every baked row measured
 * (palette_measure_rest), which could raise the palette's max_error. */
static double measure_baked_rows(bake_state *st, worker *w, uint32_t c, measure_scratch *s, const double *caps,
                                 double shift, double within, double taken, double worst)
{
    cb_bounded_row *rows = s->baked;
    uint32_t n = measured_frames(st, c, 0, rows), m = 0;
    for (uint32_t i = 0; i < n; ++i) {
        double cap = caps[rows[i].frame];
        if (!bounded_within(cap, shift, within) && (taken == INFINITY || bounded_within(cap, shift, taken)))
            rows[m++] = rows[i];
    }
    for (uint32_t i = 0; i < m; i += CB_SAMPLE_BATCH) worst = measure_batch(st, w, c, rows, i, m, 0, 1, s, NULL, worst);
    return worst;
}

/* Clip c's baked rows' caps kept by its probe, and their shift; NULL when none (or measured apart
 * from the blends: a probe's, or a bake that splits its jobs). */
static const double *kept_caps(const bake_state *st, uint32_t c, double *shift)
{
    uint32_t parts = st->p->clips[c].fitted ? 4 : 2;
    if (st->opt->error_goal > 0 || measure_split(st) || st->pending) return NULL;
    const double *kept = palette_taken_point_bounds(st, c, parts, shift);
    return kept ? kept + (size_t)3 * st->p->clips[c].frames : NULL;
}

bool palette_measure_rest(bake_state *st)
{
    const cb_palette *p = st->p;
    bool rest = false;
    st->baked_worst = 0;
    for (uint32_t c = 0; c < p->clip_count; ++c) st->baked_worst = fmax(st->baked_worst, st->clip_error[c]);
    for (uint32_t c = 0; c < p->clip_count && !rest; ++c) {
        double shift;
        const double *caps = kept_caps(st, c, &shift);
        for (uint32_t f = 0; caps && f < p->clips[c].frames && !rest; ++f)
            rest = bounded_within(caps[f], shift, st->clip_blend_error[c]) &&
                   !bounded_within(caps[f], shift, st->baked_worst);
    }
    return rest;
}

void palette_measure_rest_job(bake_state *st, worker *w, uint32_t c)
{
    double shift;
    const double *caps = kept_caps(st, c, &shift);
    measure_scratch *s = caps ? worker_scratch(st, w, c) : NULL;
    if (caps && !s)
        cb_fail(&st->errors[st->p->clip_count + c], CB_ERR_INTERNAL, "out of memory measuring %s", st->model->source);
    if (s)
        st->clip_error[c] =
            measure_baked_rows(st, w, c, s, caps, shift, st->baked_worst, st->clip_blend_error[c], st->clip_error[c]);
}

void palette_measure_job(bake_state *st, worker *w, uint32_t k)
{
    const cb_palette *p = st->p;
    double goal = st->opt->error_goal, blend = 0, baked = 0;
    bool split = measure_split(st);
    uint32_t c = split ? k / 2 : k;
    bool blends = !split || k % 2 == 0, rows = !split || k % 2 == 1; /* what this job measures */
    if (palette_clip_timed(st, c)) return; /* measured once laid out (global_timed.c) */
    measure_scratch *s = worker_scratch(st, w, c);
    /* A sampled row interval errs most halfway (a chord under an arc); fitted rows err both
     * ways, so their quarter points are measured too. */
    uint32_t parts = p->clips[c].fitted ? 4 : 2;
    if (!s) {
        cb_fail(&st->errors[blends ? c : p->clip_count + c], CB_ERR_INTERNAL, "out of memory measuring %s", st->model->source);
    } else if (goal > 0) { /* the blends, then only the baked rows that could exceed them */
        double *note = palette_pending_point_bounds(st, parts); /* a probe's, for the bake after */
        for (uint32_t sub = 1; sub < parts && !(blend > goal); ++sub) {
            point_bounds pb = {NULL, 0, note ? note + (size_t)(sub - 1) * p->clips[c].frames : NULL};
            blend = measure_clip_rows(st, w, c, sub, parts, blend, s, NULL, &pb);
        }
        keep_worst_point(st, c, parts, s, blend);
        st->clip_blend_error[c] = blend;
        s->note_caps = note ? note + (size_t)3 * p->clips[c].frames : NULL;
        double both = blend > goal ? blend : measure_clip_rows(st, w, c, 0, 1, blend, s, NULL, NULL);
        s->note_caps = NULL;
        st->clip_error[c] = both > blend ? both : 0; /* exact when above the blend; else only <= it */
    } else if (blends) { /* each fraction's rows only count where they exceed the worst blend so far */
        double *note = palette_pending_point_bounds(st, parts), shift = 0;
        const double *kept = note ? NULL : palette_taken_point_bounds(st, c, parts, &shift);
        blend = blend_floor(st, w, c, parts, s);
        /* Baked rows whose caps are kept: measured after the blends, those within them left out */
        bool later = rows && kept;
        for (uint32_t sub = 1; sub < parts; ++sub) {
            size_t at = (size_t)(sub - 1) * p->clips[c].frames;
            point_bounds pb = {kept ? kept + at : NULL, shift, note ? note + at : NULL};
            blend = measure_clip_rows(st, w, c, sub, parts, blend, s, rows && !later && sub == 1 ? &baked : NULL, &pb);
        }
        keep_worst_point(st, c, parts, s, blend);
        st->clip_blend_error[c] = blend;
        if (later)
            baked = measure_baked_rows(st, w, c, s, kept + (size_t)3 * p->clips[c].frames, shift, blend, INFINITY, 0);
        if (rows) st->clip_error[c] = baked;
    } else {
        s->note_caps = palette_pending_point_bounds(st, parts);
        if (s->note_caps) s->note_caps += (size_t)3 * p->clips[c].frames;
        st->clip_error[c] = measure_clip_rows(st, w, c, 0, 1, 0, s, NULL, NULL);
        s->note_caps = NULL;
    }
    cb_model_release_clip(st->model, st->infos[c].animation); /* measured: the keys are not read again */
}

bool palette_joint_reach(const float *bind, uint32_t bones, const cb_model *m, int32_t skin, double *radius)
{
    bool any = false;
    for (uint32_t j = 0; j < bones; ++j) radius[j] = -1;
    for (uint32_t pi = 0; pi < m->primitive_count; ++pi) {
        const cb_primitive *prim = &m->primitives[pi];
        if (prim->skin != skin) continue;
        for (uint32_t v = 0; v < prim->vertex_count; ++v)
            for (int i = 0; i < 4; ++i) {
                if (prim->weights[(size_t)v * 4 + i] == 0) continue;
                uint16_t j = prim->joints[(size_t)v * 4 + i];
                const float *b = bind + (size_t)j * 3, *x = prim->positions + (size_t)v * 3;
                double d = sqrt((double)(x[0] - b[0]) * (x[0] - b[0]) + (double)(x[1] - b[1]) * (x[1] - b[1]) +
                                (double)(x[2] - b[2]) * (x[2] - b[2]));
                if (d > radius[j]) radius[j] = d;
                any = true;
            }
    }
    return any;
}
