/* sample_lanes.c - the similarity sampler: CB_SAMPLE_BATCH times at once, every step a loop
 * over the times (lanes, structure of arrays) that the compiler vectorizes. Every lane gives
 * the bits sample.c's one-time path gives (tests/lib/test_similarity.c checks it on real models).
 *
 * Exporters write one key-time accessor for many channels (all of a clip's, often), so the
 * search for each time's keys runs once per batch for every distinct times array (a span
 * group), and the channels then only gather their key values and interpolate. */
#include "cb_math.h"
#include "lanes.h"
#include "sampler.h"

#include <stdlib.h>
#include <string.h>

/* The lanes of a batch: a node's 8 components (rotation x y z w, translation x y z, scale),
 * each CB_SAMPLE_BATCH times. Loops run over every lane, used or not: a constant trip count
 * is what lets the compiler vectorize them at -O2. */
#define B CB_SAMPLE_BATCH
typedef double lane_set[8][B];

/* ---- span groups ---- */

/* Channels whose keys the lanes interpolate: LINEAR with two keys or more (a spline or STEP
 * channel, or a single key, runs time by time through sample.c). */
static bool lane_channel(const cb_channel *ch) { return ch->interp == CB_INTERP_LINEAR && ch->key_count > 1; }

/* The group of the clip's groups (from `first` on) with these key times, or a new one. */
static int32_t span_group_of(cb_sampler *s, uint32_t first, const cb_channel *ch)
{
    for (uint32_t g = first; g < s->span_group_count; ++g)
        if (s->group_times[g] == ch->times && s->group_keys[g] == ch->key_count) return (int32_t)g;
    uint32_t g = s->span_group_count++;
    s->group_times[g] = ch->times;
    s->group_keys[g] = ch->key_count;
    s->group_cursor[g] = 0;
    return (int32_t)g;
}

bool cb_sampler_prepare_spans(cb_sampler *s)
{
    const cb_model *m = s->model;
    uint32_t channels = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a) channels += m->animations[a].channel_count;
    size_t n = channels ? channels : 1;
    s->span_group = malloc(n * sizeof *s->span_group);
    s->group_base = calloc(m->animation_count + 1, sizeof *s->group_base);
    s->clip_paths = calloc((size_t)m->animation_count * s->relevant_count + 1, 1);
    s->group_times = malloc(n * sizeof *s->group_times);
    s->group_keys = malloc(n * sizeof *s->group_keys);
    s->group_cursor = malloc(n * sizeof *s->group_cursor);
    if (!s->span_group || !s->group_base || !s->group_times || !s->group_keys || !s->group_cursor || !s->clip_paths)
        return false;
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        const cb_animation *anim = &m->animations[a];
        s->group_base[a] = s->span_group_count;
        for (uint32_t c = 0; c < anim->channel_count; ++c) {
            const cb_channel *ch = &anim->channels[c];
            bool lanes = s->relevant[ch->node] && lane_channel(ch);
            if (s->relevant[ch->node]) s->clip_paths[(size_t)a * s->relevant_count + s->slot[ch->node]] |= 1u << ch->path;
            s->span_group[s->cursor_base[a] + c] = lanes ? span_group_of(s, s->group_base[a], ch) : -1;
        }
    }
    s->group_base[m->animation_count] = s->span_group_count;
    uint32_t most = 1; /* spans for one clip's groups at a time */
    for (uint32_t a = 0; a < m->animation_count; ++a)
        if (s->group_base[a + 1] - s->group_base[a] > most) most = s->group_base[a + 1] - s->group_base[a];
    s->spans = malloc(most * sizeof *s->spans);
    return s->spans != NULL;
}

/* Where each of the batch's times falls among the keys: the operations of sample.c's
 * channel_eval, so the same key and the same fraction. */
static CB_CLONE_INLINE void find_spans(const float *times, uint32_t key_count, const double *t, uint32_t *hint,
                                       cb_key_spans *out)
{
    uint32_t last = key_count - 1;
    bool any_edge = false;
    for (int i = 0; i < B; ++i) {
        double time = t[i];
        bool edge = time <= times[0] || time >= times[last];
        uint32_t k = edge ? 0 : cb_find_key(times, key_count, time, hint);
        double t_k = times[k], dt = (double)times[k + 1] - t_k;
        out->key[i] = k;
        out->s[i] = (time - t_k) / dt;
        out->edge[i] = edge ? 1.0 : 0.0;
        any_edge |= edge;
    }
    out->any_edge = any_edge;
}

/* Whether any lane is an edge or marked in `redo` (1.0 or +0.0 each): an OR of their bits,
 * which vectorizes (a sum of doubles does not: it must add in order); most batches have none,
 * and then no lane is looked at one by one. */
static CB_CLONE_INLINE bool any_lane(const double *edge, const double *redo)
{
    uint64_t any = 0;
    for (int i = 0; i < B; ++i) {
        uint64_t e, r;
        memcpy(&e, &edge[i], sizeof e), memcpy(&r, &redo[i], sizeof r);
        any |= e | r;
    }
    return any != 0;
}

/* ---- channels ---- */

/* Whether lane i's time is lane i - 1's, bit for bit: a batch's lanes past its count repeat its
 * last time. A channel's value depends on the time alone (the hint speeds the key search but
 * never changes its answer), so such a lane takes the lane before's value, however that was
 * made, instead of evaluating it again time by time (the last time of a clip is at or past its
 * last key: every padded lane would be an edge). */
static CB_CLONE_INLINE bool time_repeats(const double *times, int i)
{
    return i > 0 && memcmp(&times[i], &times[i - 1], sizeof times[i]) == 0;
}

/* Spherical interpolation of key pairs, lane by lane: cb_quat_slerp's small-angle branch
 * (half chord below 0.1) with the same operations in the same order, so the same bits. Lanes
 * needing its other branches are marked in `redo`. */
static CB_CLONE_INLINE void slerp_lanes(const double (*restrict a)[B], const double (*restrict b)[B],
                                        const double *restrict t, double (*restrict out)[B], double *restrict redo)
{
    for (int i = 0; i < B; ++i) {
        double d = a[0][i] * b[0][i] + a[1][i] * b[1][i] + a[2][i] * b[2][i] + a[3][i] * b[3][i];
        double sign = copysign(1.0, d);
        double bx = b[0][i] * sign, by = b[1][i] * sign, bz = b[2][i] * sign, bw = b[3][i] * sign;
        double dx = a[0][i] - bx, dy = a[1][i] - by, dz = a[2][i] - bz, dw = a[3][i] - bw;
        double half_chord = 0.5 * sqrt(dx * dx + dy * dy + dz * dz + dw * dw);
        double angle = 2 * cb_small_asin(half_chord);
        /* Below 1e-6 rad the weights are lerp's: a blend by 1 or 0, not a branch, so that the
         * loop vectorizes. For these finite, non-negative weights it is exact. */
        double tiny = angle < 1e-6 ? 1.0 : 0.0;
        double wa = tiny * (1 - t[i]) + (1 - tiny) * cb_small_sin((1 - t[i]) * angle);
        double wb = tiny * t[i] + (1 - tiny) * cb_small_sin(t[i] * angle);
        double rx = wa * a[0][i] + wb * bx, ry = wa * a[1][i] + wb * by, rz = wa * a[2][i] + wb * bz,
               rw = wa * a[3][i] + wb * bw;
        double len2 = rx * rx + ry * ry + rz * rz + rw * rw, inv = 1 / sqrt(len2);
        out[0][i] = rx * inv, out[1][i] = ry * inv, out[2][i] = rz * inv, out[3][i] = rw * inv;
        redo[i] = half_chord >= 0.1 || len2 == 0 ? 1.0 : 0.0;
    }
}

#if defined(__GNUC__)
/* A rotation key (4 floats) as doubles, written element-wise: GCC 12 makes this one
 * converting load (vcvtps2pd), where __builtin_convertvector converts two halves and joins
 * them. A macro, as a function returning a 32-byte vector warns of the non-AVX clone's ABI. */
#define KEY_OF(k) ((v4df){(k)[0], (k)[1], (k)[2], (k)[3]})

/* Each lane's rotation keys k and k + 1 (adjacent) into a[c][i] and b[c][i], as doubles.
 * Element by element this was 16 scalar conversions and stores a lane; as vectors, each key is
 * one converting load and four lanes share a transpose. */
static CB_CLONE_INLINE void gather_key_pairs(const float *values, const uint32_t *key, double (*a)[B],
                                             double (*b)[B])
{
    for (int i = 0; i < B; i += 4) {
        const float *k0 = values + (size_t)key[i] * 4, *k1 = values + (size_t)key[i + 1] * 4,
                    *k2 = values + (size_t)key[i + 2] * 4, *k3 = values + (size_t)key[i + 3] * 4;
        const v4df ka[4] = {KEY_OF(k0), KEY_OF(k1), KEY_OF(k2), KEY_OF(k3)};
        const v4df kb[4] = {KEY_OF(k0 + 4), KEY_OF(k1 + 4), KEY_OF(k2 + 4), KEY_OF(k3 + 4)};
        cb_rows_to_lanes4(ka, a, i), cb_rows_to_lanes4(kb, b, i); /* each lane's quaternions as components */
    }
}
#else
static CB_CLONE_INLINE void gather_key_pairs(const float *values, const uint32_t *key, double (*a)[B],
                                             double (*b)[B])
{
    for (int i = 0; i < B; ++i) {
        const float *ka = values + (size_t)key[i] * 4, *kb = ka + 4;
        for (int c = 0; c < 4; ++c) a[c][i] = ka[c], b[c][i] = kb[c];
    }
}
#endif

/* The keys channel c of the clip reads in this batch (when its lanes come from its group's
 * spans, `base` the clip's first group), asked for ahead of it (cb_prefetch_keys). A batch reads
 * the keys of each of a clip's channels in turn (about 200 on the big rig): more streams than the
 * hardware prefetcher follows. Asking a batch ahead for the keys after its last pair (as was done)
 * fetched them too early: the clip's other keys and the lanes pushed them out again. */
static CB_CLONE_INLINE void prefetch_channel_keys(const cb_sampler *s, const cb_animation *anim, int32_t animation,
                                                  uint32_t c, uint32_t base)
{
    if (c >= anim->channel_count) return;
    const cb_channel *ch = &anim->channels[c];
    int32_t g = s->span_group[s->cursor_base[animation] + c];
    if (g >= 0 && s->group_times[g] == ch->times && s->group_keys[g] == ch->key_count)
        cb_prefetch_keys(ch, &s->spans[g - base]);
}

/* A linear rotation channel at the batch's times into out[4][B]. */
static CB_CLONE_INLINE void rotation_lanes(const cb_channel *ch, const cb_key_spans *sp, const double *times,
                                           uint32_t *hint, const cb_wrap *wrap, double (*out)[B])
{
    double a[4][B], b[4][B];
    double redo[B]; /* 1 or 0; a double, as SSE2 has no 64-bit integer compares to vectorize */
    gather_key_pairs(ch->values, sp->key, a, b);
    slerp_lanes((const double(*)[B])a, (const double(*)[B])b, sp->s, out, redo);
    if (!any_lane(sp->edge, redo)) return;
    for (int i = 0; i < B; ++i) {
        if (!sp->edge[i] && !redo[i]) continue;
        if (time_repeats(times, i)) {
            for (int c = 0; c < 4; ++c) out[c][i] = out[c][i - 1];
            continue;
        }
        double v[4];
        cb_channel_eval_at(ch, times[i], v, hint, wrap); /* before or after the keys, or a wide angle */
        for (int c = 0; c < 4; ++c) out[c][i] = v[c];
    }
}

/* A linear translation or scale channel at the batch's times into out[3][B]: a + (b - a) s,
 * channel_eval's lerp (from float keys, in double). */
static CB_CLONE_INLINE void lerp_lanes(const cb_channel *ch, const cb_key_spans *sp, const double *times,
                                       uint32_t *hint, const cb_wrap *wrap, double (*out)[B])
{
    double a[3][B], b[3][B];
    for (int i = 0; i < B; ++i) {
        const float *ka = ch->values + (size_t)sp->key[i] * 3, *kb = ka + 3;
        for (int c = 0; c < 3; ++c) a[c][i] = ka[c], b[c][i] = kb[c];
    }
    for (int c = 0; c < 3; ++c)
        for (int i = 0; i < B; ++i) out[c][i] = a[c][i] + (b[c][i] - a[c][i]) * sp->s[i];
    for (int i = 0; sp->any_edge && i < B; ++i) {
        if (!sp->edge[i]) continue;
        if (time_repeats(times, i)) {
            for (int c = 0; c < 3; ++c) out[c][i] = out[c][i - 1];
            continue;
        }
        double v[4];
        cb_channel_eval_at(ch, times[i], v, hint, wrap); /* before or after the keys */
        for (int c = 0; c < 3; ++c) out[c][i] = v[c];
    }
}

/* A lane channel (lane_channel) at the batch's times, its keys found in `sp`, into `node`. */
static CB_CLONE_INLINE void interpolate_lanes(const cb_channel *ch, const cb_key_spans *sp, const double *times,
                                              uint32_t *hint, const cb_wrap *wrap, lane_set *node)
{
    if (ch->path == CB_PATH_ROTATION) {
        rotation_lanes(ch, sp, times, hint, wrap, *node);
    } else if (ch->path == CB_PATH_TRANSLATION) {
        lerp_lanes(ch, sp, times, hint, wrap, *node + 4);
    } else {
        double v[3][B];
        lerp_lanes(ch, sp, times, hint, wrap, v);
        for (int i = 0; i < B; ++i) (*node)[7][i] = (v[0][i] + v[1][i] + v[2][i]) / 3;
    }
}

/* Any other channel, time by time. */
static void scalar_lanes(const cb_channel *ch, const double *times, uint32_t *hint, const cb_wrap *wrap,
                         lane_set *node)
{
    for (int i = 0; i < B; ++i) {
        if (time_repeats(times, i)) { /* the lane before's value of this channel's components, as stored */
            int first = ch->path == CB_PATH_ROTATION ? 0 : ch->path == CB_PATH_TRANSLATION ? 4 : 7;
            int last = ch->path == CB_PATH_ROTATION ? 3 : ch->path == CB_PATH_TRANSLATION ? 6 : 7;
            for (int c = first; c <= last; ++c) (*node)[c][i] = (*node)[c][i - 1];
            continue;
        }
        double v[4];
        cb_channel_eval_at(ch, times[i], v, hint, wrap);
        if (ch->path == CB_PATH_ROTATION)
            for (int c = 0; c < 4; ++c) (*node)[c][i] = v[c];
        else if (ch->path == CB_PATH_TRANSLATION)
            for (int c = 0; c < 3; ++c) (*node)[4 + c][i] = v[c];
        else
            (*node)[7][i] = (v[0] + v[1] + v[2]) / 3;
    }
}

/* One channel at the batch's times into its node's lanes; `sp` its group's spans, or NULL. */
static CB_CLONE_INLINE void channel_lanes(const cb_channel *ch, const cb_key_spans *sp, const double *times,
                                          uint32_t *hint, const cb_wrap *wrap, lane_set *node)
{
    if (!lane_channel(ch)) {
        scalar_lanes(ch, times, hint, wrap, node);
        return;
    }
    cb_key_spans own;
    if (!sp) { /* keys unlike its group's (not seen when the sampler was made) */
        find_spans(ch->times, ch->key_count, times, hint, &own);
        sp = &own;
    }
    interpolate_lanes(ch, sp, times, hint, wrap, node);
}

/* ---- the hierarchy ---- */

/* x -> a(b(x)) for similarities as 8 values (rotation, translation, scale): the rotation
 * qa qb, the translation ta + sa rotate(qa, tb), the scale sa sb; the operations of
 * cb_quat_mul and cb_quat_rotate, in their order. */
static CB_CLONE_INLINE void compose8(const double a[8], const double b[8], double out[8])
{
    double uvx = a[1] * b[6] - a[2] * b[5], uvy = a[2] * b[4] - a[0] * b[6], uvz = a[0] * b[5] - a[1] * b[4];
    double uuvx = a[1] * uvz - a[2] * uvy, uuvy = a[2] * uvx - a[0] * uvz, uuvz = a[0] * uvy - a[1] * uvx;
    out[0] = a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1];
    out[1] = a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0];
    out[2] = a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3];
    out[3] = a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2];
    out[4] = a[4] + a[7] * (b[4] + 2 * (a[3] * uvx + uuvx));
    out[5] = a[5] + a[7] * (b[5] + 2 * (a[3] * uvy + uuvy));
    out[6] = a[6] + a[7] * (b[6] + 2 * (a[3] * uvz + uuvz));
    out[7] = a[7] * b[7];
}

/* node = parent after node, in every lane. */
static CB_CLONE_INLINE void compose_lanes(const lane_set *restrict parent, lane_set *restrict node)
{
    const double(*p)[B] = *parent;
    double(*n)[B] = *node;
    for (int i = 0; i < B; ++i) {
        double a[8] = {p[0][i], p[1][i], p[2][i], p[3][i], p[4][i], p[5][i], p[6][i], p[7][i]};
        double b[8] = {n[0][i], n[1][i], n[2][i], n[3][i], n[4][i], n[5][i], n[6][i], n[7][i]}, r[8];
        compose8(a, b, r);
        n[0][i] = r[0], n[1][i] = r[1], n[2][i] = r[2], n[3][i] = r[3];
        n[4][i] = r[4], n[5][i] = r[5], n[6][i] = r[6], n[7][i] = r[7];
    }
}

/* out = node after ibm, in every lane. */
static CB_CLONE_INLINE void joint_lanes(const lane_set *restrict node, const cb_similarity *ibm, lane_set *restrict out)
{
    const double(*n)[B] = *node;
    double(*r)[B] = *out;
    const double b[8] = {ibm->rotation[0],    ibm->rotation[1],    ibm->rotation[2],    ibm->rotation[3],
                         ibm->translation[0], ibm->translation[1], ibm->translation[2], ibm->scale};
    for (int i = 0; i < B; ++i) {
        double a[8] = {n[0][i], n[1][i], n[2][i], n[3][i], n[4][i], n[5][i], n[6][i], n[7][i]}, ri[8];
        compose8(a, b, ri);
        r[0][i] = ri[0], r[1][i] = ri[1], r[2][i] = ri[2], r[3][i] = ri[3];
        r[4][i] = ri[4], r[5][i] = ri[5], r[6][i] = ri[6], r[7][i] = ri[7];
    }
}

/* ---- batches ---- */

/* A node's rest pose in every lane of the components no channel of the clip sets (`paths`:
 * bit 1 << path for those that one does). */
static CB_CLONE_INLINE void rest_lanes(const cb_similarity *rest, unsigned paths, lane_set *node)
{
    double(*n)[B] = *node;
    /* copied first: the lanes' stores could alias `rest`, and would reload it each time */
    double v[8] = {rest->rotation[0],    rest->rotation[1],    rest->rotation[2],    rest->rotation[3],
                   rest->translation[0], rest->translation[1], rest->translation[2], rest->scale};
    if (!(paths & 1u << CB_PATH_ROTATION))
        for (int c = 0; c < 4; ++c)
            for (int i = 0; i < B; ++i) n[c][i] = v[c];
    if (!(paths & 1u << CB_PATH_TRANSLATION))
        for (int c = 4; c < 7; ++c)
            for (int i = 0; i < B; ++i) n[c][i] = v[c];
    if (!(paths & 1u << CB_PATH_SCALE))
        for (int i = 0; i < B; ++i) n[7][i] = v[7];
}

/* Where a batch's joints go: each joint's lanes into joints[j]; or, with `out`, as rows of
 * similarities, out[i * joint_count + j] for the first `count`; or, with `sink`, handed to it.
 * The last two through one set of lanes (joints[0]). */
typedef struct batch_out {
    lane_set *joints;
    cb_similarity *out;
    cb_joint_lanes_sink sink;
    void *ctx;
} batch_out;

/* How many channels ahead of the one interpolated its keys are asked for (prefetch_channel_keys):
 * one channel's lanes take a few hundred cycles, a miss to L3 or memory about as long. */
#define KEYS_AHEAD 2

/* One batch: 1..B times, its joints to `to`. */
CB_TARGET_CLONES
static void sample_batch(cb_sampler *s, int32_t animation, const double *times, uint32_t count, const batch_out *to)
{
    lane_set *joints = to->joints;
    cb_similarity *out = to->out;
    const cb_model *m = s->model;
    lane_set *lanes = (lane_set *)s->lanes;
    double padded[B]; /* the unused lanes repeat the last time */
    for (uint32_t i = 0; i < B; ++i) padded[i] = times[i < count ? i : count - 1];
    bool animated = animation >= 0 && animation < (int32_t)m->animation_count;
    const uint8_t *paths = animated ? s->clip_paths + (size_t)animation * s->relevant_count : NULL;
    for (uint32_t k = 0; k < s->relevant_count; ++k)
        rest_lanes(&s->sim_rest[s->relevant_order[k]], paths ? paths[k] : 0, &lanes[k]);
    if (animated) {
        const cb_animation *anim = cb_sampler_clip(s, animation);
        uint32_t base = s->group_base[animation];
        for (uint32_t g = base; g < s->group_base[animation + 1]; ++g)
            find_spans(s->group_times[g], s->group_keys[g], padded, &s->group_cursor[g], &s->spans[g - base]);
        for (uint32_t c = 0; c < KEYS_AHEAD; ++c) prefetch_channel_keys(s, anim, animation, c, base);
        for (uint32_t c = 0; c < anim->channel_count; ++c) {
            const cb_channel *ch = &anim->channels[c];
            prefetch_channel_keys(s, anim, animation, c + KEYS_AHEAD, base);
            if (!s->relevant[ch->node]) continue;
            uint32_t at = s->cursor_base[animation] + c;
            int32_t g = s->span_group[at];
            bool grouped = g >= 0 && s->group_times[g] == ch->times && s->group_keys[g] == ch->key_count;
            channel_lanes(ch, grouped ? &s->spans[g - base] : NULL, padded, &s->cursor[at], &s->wraps[animation],
                          &lanes[s->slot[ch->node]]);
        }
    }
    for (uint32_t k = 0; k < s->relevant_count; ++k) {
        int32_t p = s->parent_slot[k];
        if (p >= 0) compose_lanes(&lanes[p], &lanes[k]);
    }
    const cb_skin *skin = &m->skins[s->skin];
    for (uint32_t j = 0; j < skin->joint_count; ++j) {
        lane_set *joint = out || to->sink ? joints : &joints[j];
        joint_lanes(&lanes[s->slot[skin->joints[j]]], &s->sim_ibm[j], joint);
        if (to->sink) to->sink(to->ctx, j, *joint);
        const double(*r)[B] = *joint;
        for (uint32_t i = 0; out && i < count; ++i)
            out[i * skin->joint_count + j] =
                (cb_similarity){{r[0][i], r[1][i], r[2][i], r[3][i]}, {r[4][i], r[5][i], r[6][i]}, r[7][i]};
    }
}

void cb_sample_joint_similarities_batch(cb_sampler *s, int32_t animation, const double *times, uint32_t count,
                                        cb_similarity *out)
{
    size_t joints = s->model->skins[s->skin].joint_count;
    lane_set one; /* each joint's lanes in turn: its rows are all that is kept */
    for (uint32_t first = 0; first < count; first += B)
        sample_batch(s, animation, times + first, count - first < B ? count - first : B,
                     &(batch_out){&one, out + first * joints, NULL, NULL});
}

void cb_sample_joint_lanes(cb_sampler *s, int32_t animation, const double *times, uint32_t count, double *out)
{
    sample_batch(s, animation, times, count, &(batch_out){(lane_set *)out, NULL, NULL, NULL});
}

void cb_sample_joint_lanes_each(cb_sampler *s, int32_t animation, const double *times, uint32_t count,
                                cb_joint_lanes_sink sink, void *ctx)
{
    lane_set one; /* each joint's lanes in turn */
    sample_batch(s, animation, times, count, &(batch_out){&one, NULL, sink, ctx});
}

void cb_channel_eval_lanes(const cb_channel *ch, const double *times, double (*out)[B])
{
    uint32_t hint = 0;
    cb_key_spans sp;
    find_spans(ch->times, ch->key_count, times, &hint, &sp);
    if (ch->path == CB_PATH_ROTATION)
        rotation_lanes(ch, &sp, times, &hint, NULL, out);
    else
        lerp_lanes(ch, &sp, times, &hint, NULL, out);
}
bool cb_channel_in_lanes(const cb_channel *ch) { return lane_channel(ch); }

void cb_find_spans(const float *key_times, uint32_t key_count, const double *times, uint32_t *hint, cb_key_spans *out)
{
    find_spans(key_times, key_count, times, hint, out);
}

CB_TARGET_CLONES
void cb_channel_lanes_at(const cb_channel *ch, const double *times, uint32_t *hint, const cb_wrap *wrap,
                         const cb_key_spans *spans, double (*out)[B])
{
    if (!lane_channel(ch)) { /* STEP, CUBICSPLINE, a single key: time by time */
        for (int i = 0; i < B; ++i) {
            double v[4] = {0, 0, 0, 0};
            if (time_repeats(times, i))
                for (int c = 0; c < 4; ++c) v[c] = out[c][i - 1];
            else
                cb_channel_eval_at(ch, times[i], v, hint, wrap);
            for (int c = 0; c < 4; ++c) out[c][i] = v[c];
        }
        return;
    }
    cb_key_spans own;
    if (!spans) find_spans(ch->times, ch->key_count, times, hint, &own), spans = &own;
    if (ch->path == CB_PATH_ROTATION)
        rotation_lanes(ch, spans, times, hint, wrap, out);
    else
        lerp_lanes(ch, spans, times, hint, wrap, out);
}
#undef B
