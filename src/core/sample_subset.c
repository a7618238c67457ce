/* sample_subset.c - some of a skin's joints sampled alone, at a batch of times at once
 * (sampler.h: cb_joint_subset). The 4x4 matrix sampler's operations (sample.c's sample_nodes and
 * cb_sample_joint_matrices), in their order, each over the batch's times side by side: the same
 * bits, at a fraction of the work where the joints wanted hang from a few of the rig's nodes. */
#include "cb_math.h"
#include "lanes.h"
#include "sampler.h"

#include <stdlib.h>
#include <string.h>

#define B CB_SAMPLE_BATCH
/* Per node of the subset, its lanes: translation, rotation, scale (10), then its global matrix (16). */
enum { TRS_LANES = 10, NODE_LANES = 26 };

/* A channel's component of a node's TRS: 0 translation (lanes 0-2), 1 rotation (3-6), 2 scale (7-9). */
static int channel_component(const cb_channel *ch)
{
    return ch->path == CB_PATH_TRANSLATION ? 0 : ch->path == CB_PATH_ROTATION ? 1 : 2;
}
static int component_of_lane(int c) { return c < 3 ? 0 : c < 7 ? 1 : 2; }
static const int component_first_lane[3] = {0, 3, 7};

static double *node_lanes(const cb_joint_subset *sub, uint32_t slot, int c)
{
    return sub->node_lanes + ((size_t)slot * NODE_LANES + (size_t)c) * B;
}

cb_joint_subset *cb_joint_subset_create(const cb_sampler *s, const bool *wanted)
{
    const cb_model *m = s->model;
    const cb_skin *skin = &m->skins[s->skin];
    cb_joint_subset *sub = calloc(1, sizeof *sub);
    if (!sub) return NULL;
    uint32_t channels = 1;
    for (uint32_t a = 0; a < m->animation_count; ++a)
        if (m->animations[a].channel_count > channels) channels = m->animations[a].channel_count;
    sub->relevant = calloc(m->node_count + 1, sizeof *sub->relevant);
    sub->order = malloc((m->node_count + 1) * sizeof *sub->order);
    sub->slot = malloc((m->node_count + 1) * sizeof *sub->slot);
    sub->animated = malloc((m->node_count + 1) * sizeof *sub->animated);
    sub->paths = malloc((m->node_count + 1) * sizeof *sub->paths);
    sub->joints = malloc((skin->joint_count + 1) * sizeof *sub->joints);
    sub->joint_slot = malloc((skin->joint_count + 1) * sizeof *sub->joint_slot);
    sub->channel_lanes = malloc((size_t)channels * 4 * B * sizeof(double));
    if (!sub->relevant || !sub->order || !sub->slot || !sub->animated || !sub->paths || !sub->joints || !sub->joint_slot ||
        !sub->channel_lanes)
        return cb_joint_subset_free(sub), NULL;
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        sub->joint_slot[j] = wanted[j] ? sub->joint_count : UINT32_MAX;
        if (!wanted[j]) continue;
        sub->joints[sub->joint_count++] = j;
        for (int32_t n = skin->joints[j]; n >= 0 && !sub->relevant[n]; n = m->nodes[n].parent) sub->relevant[n] = true;
    }
    for (uint32_t k = 0; k < m->node_count; ++k) /* s->order: parents first */
        if (sub->relevant[s->order[k]]) sub->slot[s->order[k]] = sub->count, sub->order[sub->count++] = s->order[k];
    sub->node_lanes = malloc(((size_t)sub->count + 1) * NODE_LANES * B * sizeof(double));
    if (!sub->node_lanes) return cb_joint_subset_free(sub), NULL;
    return sub;
}

void cb_joint_subset_free(cb_joint_subset *sub)
{
    if (!sub) return;
    free(sub->relevant), free(sub->order), free(sub->slot), free(sub->animated), free(sub->paths), free(sub->joints), free(sub->joint_slot);
    free(sub->channel_lanes), free(sub->node_lanes);
    free(sub);
}

/* The TRS components (bit 0 translation, 1 rotation, 2 scale) a relevant channel of the clip
 * sets, per node of the subset, into sub->paths; and which nodes a channel animates. */
static void animated_paths(const cb_animation *anim, cb_joint_subset *sub)
{
    for (uint32_t k = 0; k < sub->count; ++k) sub->paths[k] = 0, sub->animated[sub->order[k]] = false;
    for (uint32_t c = 0; anim && c < anim->channel_count; ++c) {
        const cb_channel *ch = &anim->channels[c];
        if (!sub->relevant[ch->node]) continue;
        sub->paths[sub->slot[ch->node]] |= (uint8_t)(1u << channel_component(ch));
        sub->animated[ch->node] = true;
    }
}

/* Each node's rest TRS in every lane of the components no channel sets (the others are the
 * channels' values, written over them before as after). */
static void rest_lanes(const cb_sampler *s, cb_joint_subset *sub)
{
    const cb_model *m = s->model;
    for (uint32_t k = 0; k < sub->count; ++k) {
        const cb_node *n = &m->nodes[sub->order[k]];
        const double rest[TRS_LANES] = {n->translation[0], n->translation[1], n->translation[2], n->rotation[0],
                                        n->rotation[1],    n->rotation[2],    n->rotation[3],    n->scale[0],
                                        n->scale[1],       n->scale[2]};
        for (int c = 0; c < TRS_LANES; ++c) {
            if (sub->paths[k] >> component_of_lane(c) & 1u) continue;
            double *lane = node_lanes(sub, k, c);
            for (int i = 0; i < B; ++i) lane[i] = rest[c];
        }
    }
}

/* cb_mat4_from_trs lane by lane, the same operations in the same order. */
static CB_CLONE_INLINE void matrix_from_trs_lanes(const double *t, double (*m)[B])
{
    const double *tx = t, *ty = t + B, *tz = t + 2 * B, *qx = t + 3 * B, *qy = t + 4 * B, *qz = t + 5 * B,
                 *qw = t + 6 * B, *sx = t + 7 * B, *sy = t + 8 * B, *sz = t + 9 * B;
    for (int i = 0; i < B; ++i) {
        double x = qx[i], y = qy[i], z = qz[i], w = qw[i];
        double xx = x * x, yy = y * y, zz = z * z;
        double xy = x * y, xz = x * z, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
        m[0][i] = (1 - 2 * (yy + zz)) * sx[i], m[1][i] = (2 * (xy + wz)) * sx[i], m[2][i] = (2 * (xz - wy)) * sx[i];
        m[4][i] = (2 * (xy - wz)) * sy[i], m[5][i] = (1 - 2 * (xx + zz)) * sy[i], m[6][i] = (2 * (yz + wx)) * sy[i];
        m[8][i] = (2 * (xz + wy)) * sz[i], m[9][i] = (2 * (yz - wx)) * sz[i], m[10][i] = (1 - 2 * (xx + yy)) * sz[i];
        m[12][i] = tx[i], m[13][i] = ty[i], m[14][i] = tz[i];
        m[3][i] = m[7][i] = m[11][i] = 0, m[15][i] = 1;
    }
}

/* cb_mat4_mul_affine lane by lane, the same operations in the same order. */
static CB_CLONE_INLINE void mul_affine_lanes(double (*restrict out)[B], const double (*restrict a)[B],
                                             const double (*restrict b)[B])
{
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 3; ++r)
            for (int i = 0; i < B; ++i)
                out[c * 4 + r][i] = a[r][i] * b[c * 4][i] + a[4 + r][i] * b[c * 4 + 1][i] + a[8 + r][i] * b[c * 4 + 2][i];
        for (int i = 0; i < B; ++i) out[c * 4 + 3][i] = 0.0;
    }
    for (int r = 12; r < 15; ++r)
        for (int i = 0; i < B; ++i) out[r][i] += a[r][i];
    for (int i = 0; i < B; ++i) out[15][i] = 1.0;
}

#if defined(__GNUC__)
/* Row r of one column of mul_affine_lanes' product at lanes i .. i + 3, the column's three
 * values given (b0, b1, b2), then the parent's translation added for the fourth column (`add`). */
static CB_CLONE_INLINE void product_row(const double (*restrict a)[B], int r, int i, const v4df *b0, const v4df *b1,
                                        const v4df *b2, const double *add, double *dst)
{
    v4df ar, ar4, ar8;
    memcpy(&ar, &a[r][i], sizeof ar), memcpy(&ar4, &a[4 + r][i], sizeof ar4), memcpy(&ar8, &a[8 + r][i], sizeof ar8);
    v4df o = ar * *b0 + ar4 * *b1 + ar8 * *b2;
    if (add) {
        v4df t;
        memcpy(&t, add, sizeof t);
        o += t;
    }
    memcpy(dst, &o, sizeof o);
}

/* matrix_from_trs_lanes, then mul_affine_lanes with the parent's global `a`, four lanes at a
 * time without storing the local matrix: each lane the same operations in the same order (no
 * contraction: -ffp-contract=off), so the same bits. */
static CB_CLONE_INLINE void trs_global_lanes(const double *t, const double (*restrict a)[B], double (*restrict out)[B])
{
    const v4df one = {1, 1, 1, 1}, two = {2, 2, 2, 2}, zero = {0, 0, 0, 0};
    for (int i = 0; i < B; i += 4) { /* unrolled within: the values stay in registers */
        v4df v[TRS_LANES];
#pragma GCC unroll 10
        for (int c = 0; c < TRS_LANES; ++c) memcpy(&v[c], t + (size_t)c * B + i, sizeof v[c]);
        v4df x = v[3], y = v[4], z = v[5], w = v[6];
        v4df xx = x * x, yy = y * y, zz = z * z;
        v4df xy = x * y, xz = x * z, yz = y * z, wx = w * x, wy = w * y, wz = w * z;
        const v4df m[12] = {(one - two * (yy + zz)) * v[7], (two * (xy + wz)) * v[7], (two * (xz - wy)) * v[7],
                            (two * (xy - wz)) * v[8], (one - two * (xx + zz)) * v[8], (two * (yz + wx)) * v[8],
                            (two * (xz + wy)) * v[9], (two * (yz - wx)) * v[9], (one - two * (xx + yy)) * v[9],
                            v[0], v[1], v[2]};
#pragma GCC unroll 4
        for (int c = 0; c < 4; ++c)
#pragma GCC unroll 3
            for (int r = 0; r < 3; ++r)
                product_row(a, r, i, &m[c * 3], &m[c * 3 + 1], &m[c * 3 + 2], c == 3 ? &a[12 + r][i] : NULL,
                            &out[c * 4 + r][i]);
        memcpy(&out[3][i], &zero, sizeof zero), memcpy(&out[7][i], &zero, sizeof zero);
        memcpy(&out[11][i], &zero, sizeof zero), memcpy(&out[15][i], &one, sizeof one);
    }
}
#endif

/* Each node's global matrix, parents first: sample_nodes' local_matrix and product per lane. */
CB_TARGET_CLONES
static void global_lanes(const cb_sampler *s, cb_joint_subset *sub)
{
    const cb_model *m = s->model;
    double local[16][B];
    for (uint32_t k = 0; k < sub->count; ++k) {
        uint32_t node = sub->order[k];
        const cb_node *n = &m->nodes[node];
#if defined(__GNUC__)
        if (n->parent >= 0 && !(n->has_matrix && !sub->animated[node])) {
            trs_global_lanes(node_lanes(sub, k, 0), (const double(*)[B])node_lanes(sub, sub->slot[n->parent], TRS_LANES),
                             (double(*)[B])node_lanes(sub, k, TRS_LANES));
            continue;
        }
#endif
        if (n->has_matrix && !sub->animated[node])
            for (int c = 0; c < 16; ++c)
                for (int i = 0; i < B; ++i) local[c][i] = n->matrix[c];
        else
            matrix_from_trs_lanes(node_lanes(sub, k, 0), local);
        double(*global)[B] = (double(*)[B])node_lanes(sub, k, TRS_LANES);
        if (n->parent < 0)
            memcpy(global, local, sizeof local);
        else
            mul_affine_lanes(global, (const double(*)[B])node_lanes(sub, sub->slot[n->parent], TRS_LANES),
                             (const double(*)[B])local);
    }
}

/* Each wanted joint's matrix, its global times its inverse bind matrix: cb_mat4_mul_affine's
 * operations lane by lane, or cb_mat4_mul time by time where an inverse bind matrix is not affine. */
CB_TARGET_CLONES
static void joint_matrix_lanes(const cb_sampler *s, const cb_joint_subset *sub, double *out)
{
    const cb_skin *skin = &s->model->skins[s->skin];
    for (uint32_t k = 0; k < sub->joint_count; ++k) {
        uint32_t j = sub->joints[k];
        const double *ibm = skin->inverse_bind + (size_t)j * 16;
        const double(*g)[B] = (const double(*)[B])node_lanes(sub, sub->slot[skin->joints[j]], TRS_LANES);
        double(*m)[B] = (double(*)[B])(out + (size_t)k * 16 * B);
        if (s->affine_ibm) {
            double b[16][B];
            for (int c = 0; c < 16; ++c)
                for (int i = 0; i < B; ++i) b[c][i] = ibm[c];
            mul_affine_lanes(m, g, (const double(*)[B])b);
            continue;
        }
        for (int i = 0; i < B; ++i) {
            double gi[16], mi[16];
            for (int c = 0; c < 16; ++c) gi[c] = g[c][i];
            cb_mat4_mul(mi, gi, ibm);
            for (int c = 0; c < 16; ++c) m[c][i] = mi[c];
        }
    }
}

/* How many channels ahead of the one interpolated its keys are asked for (as sample_lanes.c's). */
#define KEYS_AHEAD 2

/* Every node of the subset at the batch's times: its channels, then each global matrix. */
static void subset_globals(cb_sampler *s, int32_t animation, const double *times, uint32_t count, cb_joint_subset *sub)
{
    const cb_model *m = s->model;
    const cb_animation *anim = animation >= 0 && animation < (int32_t)m->animation_count ? cb_sampler_clip(s, animation) : NULL;
    double padded[B]; /* the unused lanes repeat the last time */
    for (uint32_t i = 0; i < B; ++i) padded[i] = times[i < count ? i : count - 1];
    /* The rest lanes no channel sets stay as filled from one batch of a clip to the next. */
    if (!sub->filled || sub->filled_animation != animation || sub->filled_clip != anim) {
        animated_paths(anim, sub);
        rest_lanes(s, sub);
        sub->filled = true, sub->filled_animation = animation, sub->filled_clip = anim;
    }
    /* Channels that share their key times (one input accessor for many, as exporters write
     * them) share one key search: the spans are the same whatever the channel. A channel the
     * lanes interpolate writes its rows (3, or 4 for a rotation) straight into its node's; one
     * evaluated time by time writes 4, so through channel_lanes. Either way in channel order:
     * of two channels of one component, the last one's values stay. */
    cb_key_spans spans;
    const float *spans_of = NULL;
    uint32_t spans_keys = 0;
    for (uint32_t c = 0; anim && c < anim->channel_count; ++c) {
        const cb_channel *ch = &anim->channels[c];
        if (!sub->relevant[ch->node]) continue;
        uint32_t *cursor = &s->cursor[s->cursor_base[animation] + c];
        bool lanes = cb_channel_in_lanes(ch);
        if (lanes && (ch->times != spans_of || ch->key_count != spans_keys))
            cb_find_spans(ch->times, ch->key_count, padded, cursor, &spans), spans_of = ch->times, spans_keys = ch->key_count;
        const cb_channel *ahead = c + KEYS_AHEAD < anim->channel_count ? &anim->channels[c + KEYS_AHEAD] : NULL;
        if (lanes && ahead && sub->relevant[ahead->node] && ahead->times == spans_of && ahead->key_count == spans_keys &&
            cb_channel_in_lanes(ahead))
            cb_prefetch_keys(ahead, &spans); /* its keys, while this channel is interpolated */
        int component = channel_component(ch);
        double *node = node_lanes(sub, sub->slot[ch->node], component_first_lane[component]);
        double *scratch = sub->channel_lanes + (size_t)c * 4 * B;
        cb_channel_lanes_at(ch, padded, cursor, &s->wraps[animation], lanes ? &spans : NULL,
                            (double(*)[B])(lanes ? node : scratch));
        if (!lanes) memcpy(node, scratch, (component == 1 ? 4 : 3) * B * sizeof(double));
    }
    global_lanes(s, sub);
}

void cb_sample_joint_subset_batch(cb_sampler *s, int32_t animation, const double *times, uint32_t count,
                                  cb_joint_subset *sub, double *out)
{
    subset_globals(s, animation, times, count, sub);
    joint_matrix_lanes(s, sub, out);
}

#if defined(__GNUC__)
/* Four lanes of four components (v[c]: component c at lanes i .. i + 3) stored as each lane's
 * four values at dst[l] + at: the 4x4 transpose of cb_rows_to_lanes4. */
static CB_CLONE_INLINE void lanes_to_poses4(const v4df *v, double *const *dst, size_t at)
{
    v4df t0 = __builtin_shufflevector(v[0], v[1], 0, 4, 2, 6), t1 = __builtin_shufflevector(v[0], v[1], 1, 5, 3, 7);
    v4df t2 = __builtin_shufflevector(v[2], v[3], 0, 4, 2, 6), t3 = __builtin_shufflevector(v[2], v[3], 1, 5, 3, 7);
    const v4df r0 = __builtin_shufflevector(t0, t2, 0, 1, 4, 5), r1 = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    const v4df r2 = __builtin_shufflevector(t0, t2, 2, 3, 6, 7), r3 = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
    memcpy(dst[0] + at, &r0, sizeof r0), memcpy(dst[1] + at, &r1, sizeof r1);
    memcpy(dst[2] + at, &r2, sizeof r2), memcpy(dst[3] + at, &r3, sizeof r3);
}

/* joint_matrix_lanes' affine product (mul_affine_lanes with the inverse bind matrix in every
 * lane: each lane the same operations in the same order, no contraction) four lanes at a time,
 * each lane's matrix stored straight into its pose: no lanes written and read back. A lane not
 * wanted (past count, or its pose NULL) is stored into `dump` (room for a pose), so that every
 * store is made. */
CB_TARGET_CLONES
static void joint_matrix_poses(const cb_sampler *s, const cb_joint_subset *sub, uint32_t count, double *const *pose,
                               double *dump)
{
    const cb_skin *skin = &s->model->skins[s->skin];
    const v4df zero = {0, 0, 0, 0}, one = {1, 1, 1, 1};
    double *base[B], *dst[B];
    for (uint32_t i = 0; i < B; ++i) base[i] = i < count && pose[i] ? pose[i] : dump;
    for (uint32_t k = 0; k < sub->joint_count; ++k) {
        uint32_t j = sub->joints[k];
        const double *ibm = skin->inverse_bind + (size_t)j * 16;
        const double(*g)[B] = (const double(*)[B])node_lanes(sub, sub->slot[skin->joints[j]], TRS_LANES);
        for (uint32_t i = 0; i < B; ++i) dst[i] = base[i] + (size_t)j * 16;
        for (uint32_t i = 0; i < count; i += 4) {
            v4df a[12];
#pragma GCC unroll 3
            for (int r = 0; r < 3; ++r)
                memcpy(&a[r], &g[r][i], 32), memcpy(&a[3 + r], &g[4 + r][i], 32), memcpy(&a[6 + r], &g[8 + r][i], 32),
                    memcpy(&a[9 + r], &g[12 + r][i], 32);
#pragma GCC unroll 4
            for (int c = 0; c < 4; ++c) {
                const v4df b0 = CB_SPLAT4(ibm[c * 4]), b1 = CB_SPLAT4(ibm[c * 4 + 1]), b2 = CB_SPLAT4(ibm[c * 4 + 2]);
                v4df col[4];
#pragma GCC unroll 3
                for (int r = 0; r < 3; ++r) {
                    col[r] = a[r] * b0 + a[3 + r] * b1 + a[6 + r] * b2;
                    if (c == 3) col[r] += a[9 + r];
                }
                col[3] = c == 3 ? one : zero;
                lanes_to_poses4(col, dst + i, (size_t)c * 4);
            }
        }
    }
}
#endif

void cb_sample_joint_subset_poses(cb_sampler *s, int32_t animation, const double *times, uint32_t count,
                                  cb_joint_subset *sub, double *lanes, double *const *pose)
{
    subset_globals(s, animation, times, count, sub);
#if defined(__GNUC__)
    if (s->affine_ibm) {
        joint_matrix_poses(s, sub, count, pose, lanes); /* the lanes' room, unused here, as the dump */
        return;
    }
#endif
    joint_matrix_lanes(s, sub, lanes);
    for (uint32_t i = 0; i < count; ++i) {
        if (!pose[i]) continue;
        for (uint32_t k = 0; k < sub->joint_count; ++k) {
            double *to = pose[i] + (size_t)sub->joints[k] * 16;
            const double *from = lanes + (size_t)k * 16 * B + i;
#pragma GCC unroll 16 /* -O2 leaves it a loop of six instructions a value */
            for (int c = 0; c < 16; ++c) to[c] = from[c * B];
        }
    }
}
#undef B
