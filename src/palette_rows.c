/* palette_rows.c - qpos rows from joint similarities: what qpos stores (quaternion, position,
 * scale), with no matrix to build, check or decompose, for a batch of frames at a time.
 *
 * Bone by bone, the batch's frames are lanes (structure of arrays, like the sampler's), so the
 * rotation of the bind position, the position and the conversions to float vectorize. Each
 * lane runs cb_quat_rotate's operations in their order: the same bits as one row at a time.
 * What depends on the rows before - the quaternion's hemisphere, the clip's bounds and value
 * ranges - is settled after, in frame order, so it comes out as before too. */

#include "palette_bake.h"
#include "sampler.h"

#define B CB_SAMPLE_BATCH

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

/* One bone at frames f .. f + count - 1, its similarities' lanes `sim` (lanes past count repeat
 * the last frame): its position and reach grow the lanes' bounds, its values their range, its 8
 * values go into the rows and its last quaternion into w->prev. */
static CB_CLONE_INLINE void bone_lanes(bake_state *st, worker *w, uint32_t j, uint32_t f, uint32_t count,
                                       const double (*sim)[B], float *rows, lane_extent *x)
{
    const cb_palette *p = st->p;
    uint32_t bones = p->bone_count;
    const double(*q)[B] = sim, (*t)[B] = sim + 4, *s = sim[7];
    double dot[B], e[4][B];
    float fq[4][B + 1], fp[4][B]; /* fq: lane i's quaternion as stored at i + 1 (0 at 0) */
    const float *b = p->bind_positions + (size_t)j * 3;
    double bx = b[0], by = b[1], bz = b[2], radius = st->radius[j];
    fq[0][0] = fq[1][0] = fq[2][0] = fq[3][0] = 0;
    for (int i = 0; i < B; ++i) {
        /* cb_quat_rotate(q, b), written out over the lanes */
        double uvx = q[1][i] * bz - q[2][i] * by, uvy = q[2][i] * bx - q[0][i] * bz, uvz = q[0][i] * by - q[1][i] * bx;
        double uuvx = q[1][i] * uvz - q[2][i] * uvy, uuvy = q[2][i] * uvx - q[0][i] * uvz,
               uuvz = q[0][i] * uvy - q[1][i] * uvx;
        double rx = bx + 2 * (q[3][i] * uvx + uuvx), ry = by + 2 * (q[3][i] * uvy + uuvy),
               rz = bz + 2 * (q[3][i] * uvz + uuvz);
        e[0][i] = t[0][i] + s[i] * rx, e[1][i] = t[1][i] + s[i] * ry, e[2][i] = t[2][i] + s[i] * rz;
        e[3][i] = radius * s[i] * sqrt(3.0); /* |s R| = sqrt(3) s */
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
    float sign[B], sq[4][B]; /* each row's hemisphere; then the rows' quaternions */
    row_signs(dot, flip, sign);
    for (int c = 0; c < 4; ++c)
        for (int i = 0; i < B; ++i) sq[c][i] = sign[i] * fq[c][i + 1];
    for (uint32_t i = 0; i < count; ++i) { /* lanes to rows: field by field, no staging copy */
        float *o = rows + (size_t)i * bones * 8 + (size_t)j * 8;
        o[0] = sq[0][i], o[1] = sq[1][i], o[2] = sq[2][i], o[3] = sq[3][i];
        o[4] = fp[0][i], o[5] = fp[1][i], o[6] = fp[2][i], o[7] = fp[3][i];
    }
    /* Every lane grown (those past count repeat the last frame, and fold_lanes reads count). */
    for (int k = 0; radius >= 0 && k < 3; ++k) /* a joint that moves no vertex bounds nothing */
        for (int i = 0; i < B; ++i) {
            double lo = e[k][i] - e[3][i], hi = e[k][i] + e[3][i];
            x->lo[k][i] = lo < x->lo[k][i] ? lo : x->lo[k][i];
            x->hi[k][i] = hi > x->hi[k][i] ? hi : x->hi[k][i];
        }
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
void palette_similarity_rows(bake_state *st, worker *w, uint32_t c, uint32_t f, uint32_t count, float *rows,
                             extent *clip_bounds)
{
    uint32_t bones = st->p->bone_count;
    /* The joints' similarities as lanes (the sampler's layout: no transposing on either side). */
    double *lanes = w->lanes;
    uint32_t frames[B];
    for (uint32_t i = 0; i < count; ++i) frames[i] = f + i;
    cb_clip_frame_lanes(w->sampler, &st->infos[c], frames, count, st->opt->root_motion, lanes);
    lane_extent x;
    lane_extent_reset(&x);
    for (uint32_t j = 0; j < bones; ++j)
        bone_lanes(st, w, j, f, count, (const double(*)[B])(lanes + (size_t)j * 8 * B), rows, &x);
    /* Bounds and ranges in frame order, as one row at a time grows them (of +0 and -0, the
     * minimum is the one met first). Locals, kept in registers. */
    extent bounds = *clip_bounds;
    value_range range = st->ranges[c];
    fold_lanes(&x, count, &bounds, &range);
    *clip_bounds = bounds;
    st->ranges[c] = range;
}
