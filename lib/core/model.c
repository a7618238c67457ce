/* model.c - cb_model ownership (an arena per model), validation and lookups. */
#include "cb_math.h"
#include "crowdbake/core.h"
#include "pool.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

static void fail_v(cb_error *err, cb_status status, cb_setting setting, const char *fmt, va_list ap)
{
    if (err && err->status == CB_OK) {
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        err->status = status;
        err->setting = setting;
    }
}

cb_status cb_fail(cb_error *err, cb_status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fail_v(err, status, CB_SETTING_NONE, fmt, ap);
    va_end(ap);
    return status;
}

cb_status cb_fail_setting(cb_error *err, cb_status status, cb_setting setting, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fail_v(err, status, setting, fmt, ap);
    va_end(ap);
    return status;
}

cb_limits cb_default_limits(void)
{
    cb_limits l;
    l.max_joints = 4096;
    l.max_frames = 1u << 20;
    l.max_accessor_count = 1u << 24;
    l.max_file_bytes = (uint64_t)2 << 30;
    l.max_palette_bytes = (uint64_t)1 << 30;
    return l;
}

/* ---- arena: one owner for everything a model holds ---- */

typedef struct cb_arena_block {
    struct cb_arena_block *next;
    size_t used, size;
    max_align_t data[];
} cb_arena_block;

typedef struct cb_arena_adopted {
    struct cb_arena_adopted *next;
    void *ptr;
    void (*release)(void *);
} cb_arena_adopted;

struct cb_arena {
    cb_arena_block *head;
    cb_arena_adopted *adopted;
};

static void *arena_alloc(cb_arena *arena, size_t bytes)
{
    const size_t align = sizeof(max_align_t);
    bytes = (bytes + align - 1) / align * align;
    cb_arena_block *b = arena->head;
    if (!b || b->size - b->used < bytes) {
        size_t size = bytes > 65536 ? bytes : 65536;
        b = calloc(1, sizeof *b + size);
        if (!b) return NULL;
        b->size = size;
        b->next = arena->head;
        arena->head = b;
    }
    void *p = (char *)b->data + b->used;
    b->used += bytes;
    return p; /* calloc'd and never reused, so already zero */
}

cb_arena *cb_arena_create(void) { return calloc(1, sizeof(cb_arena)); }

bool cb_arena_adopt(cb_arena *arena, void *ptr, void (*release)(void *))
{
    cb_arena_adopted *a = cb_arena_alloc(arena, 1, sizeof *a);
    if (!a) return false;
    *a = (cb_arena_adopted){arena->adopted, ptr, release};
    arena->adopted = a;
    return true;
}

void cb_arena_free(cb_arena *arena)
{
    if (!arena) return;
    for (cb_arena_adopted *a = arena->adopted; a; a = a->next) a->release(a->ptr);
    cb_arena_block *b = arena->head;
    while (b) {
        cb_arena_block *next = b->next;
        free(b);
        b = next;
    }
    free(arena);
}

void *cb_arena_alloc(cb_arena *arena, size_t count, size_t size)
{
    if (size && count > SIZE_MAX / size) return NULL;
    size_t bytes = count * size;
    return arena_alloc(arena, bytes ? bytes : 1);
}

const char *cb_arena_strdup(cb_arena *arena, const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = cb_arena_alloc(arena, n, 1);
    if (p) memcpy(p, s, n);
    return p;
}

cb_model *cb_model_create(const char *source)
{
    cb_model *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    m->arena = cb_arena_create();
    if (!m->arena) {
        free(m);
        return NULL;
    }
    m->source = cb_model_strdup(m, source ? source : "<memory>");
    return m;
}

void cb_model_free(cb_model *model)
{
    if (!model) return;
    cb_arena_free(model->arena);
    free(model);
}

void *cb_model_alloc(cb_model *model, size_t count, size_t size) { return cb_arena_alloc(model->arena, count, size); }

const char *cb_model_strdup(cb_model *model, const char *s) { return cb_arena_strdup(model->arena, s); }

/* ---- validation ---- */

static const char *path_name(cb_path p)
{
    return p == CB_PATH_TRANSLATION ? "translation" : p == CB_PATH_ROTATION ? "rotation" : "scale";
}

static int path_components(cb_path p) { return p == CB_PATH_ROTATION ? 4 : 3; }

/* Gives every node a TRS: matrix nodes are decomposed (an animation channel may replace
 * parts of it), rotations are normalized. */
static void normalize_node_transforms(cb_model *m)
{
    for (uint32_t i = 0; i < m->node_count; ++i) {
        cb_node *n = &m->nodes[i];
        if (n->has_matrix) {
            cb_vec3 t, s;
            cb_quat r;
            cb_mat4_decompose(n->matrix, &t, &r, &s, 1e-4);
            double trs[10] = {t.x, t.y, t.z, r.x, r.y, r.z, r.w, s.x, s.y, s.z};
            memcpy(n->translation, trs, sizeof n->translation);
            memcpy(n->rotation, trs + 3, sizeof n->rotation);
            memcpy(n->scale, trs + 7, sizeof n->scale);
        } else if (isfinite(n->rotation[0] + n->rotation[1] + n->rotation[2] + n->rotation[3])) {
            cb_quat q = cb_quat_normalize((cb_quat){n->rotation[0], n->rotation[1], n->rotation[2], n->rotation[3]});
            n->rotation[0] = q.x, n->rotation[1] = q.y, n->rotation[2] = q.z, n->rotation[3] = q.w;
        }
    }
}

static cb_status validate_nodes(cb_model *m, cb_error *err)
{
    for (uint32_t i = 0; i < m->node_count; ++i) {
        const cb_node *n = &m->nodes[i];
        if (n->parent < -1 || n->parent >= (int32_t)m->node_count)
            return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) has parent %d out of range", m->source, i, n->name,
                           n->parent);
        for (int k = 0; k < 3; ++k)
            if (!isfinite(n->translation[k]) || !isfinite(n->scale[k]))
                return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) has a NaN or infinite transform", m->source, i,
                               n->name);
        for (int k = 0; k < 4; ++k)
            if (!isfinite(n->rotation[k]))
                return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) has a NaN or infinite rotation", m->source, i,
                               n->name);
        for (int k = 0; k < 16 && n->has_matrix; ++k)
            if (!isfinite(n->matrix[k]))
                return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) has a NaN or infinite matrix", m->source, i, n->name);
        /* Walking up at most node_count steps finds a root unless there is a cycle. */
        int32_t p = n->parent;
        for (uint32_t steps = 0; p >= 0; ++steps) {
            if (steps >= m->node_count)
                return cb_fail(err, CB_ERR_INPUT, "%s: node %u (%s) is part of a cycle in the node hierarchy",
                               m->source, i, n->name);
            p = m->nodes[p].parent;
        }
    }
    return CB_OK;
}

static cb_status validate_skins(const cb_model *m, const cb_limits *limits, cb_error *err)
{
    for (uint32_t s = 0; s < m->skin_count; ++s) {
        const cb_skin *skin = &m->skins[s];
        if (skin->joint_count == 0)
            return cb_fail(err, CB_ERR_INPUT, "%s: skin %u (%s) has no joints", m->source, s, skin->name);
        if (skin->joint_count > limits->max_joints)
            return cb_fail_setting(err, CB_ERR_INPUT, CB_SETTING_MAX_JOINTS, "%s: skin %u (%s) has %u joints, over the limit of %u",
                           m->source, s, skin->name, skin->joint_count, limits->max_joints);
        int32_t common_root = -1;
        for (uint32_t j = 0; j < skin->joint_count; ++j) {
            if (skin->joints[j] < 0 || skin->joints[j] >= (int32_t)m->node_count)
                return cb_fail(err, CB_ERR_INPUT, "%s: skin %u (%s) joint %u names node %d, which does not exist",
                               m->source, s, skin->name, j, skin->joints[j]);
            for (int k = 0; k < 16; ++k)
                if (!isfinite(skin->inverse_bind[j * 16 + k]))
                    return cb_fail(err, CB_ERR_INPUT, "%s: skin %u (%s) inverse bind matrix %u is NaN or infinite",
                                   m->source, s, skin->name, j);
            int32_t root = skin->joints[j];
            while (m->nodes[root].parent >= 0) root = m->nodes[root].parent;
            if (common_root >= 0 && root != common_root)
                return cb_fail(err, CB_ERR_INPUT,
                               "%s: skin %u (%s) joints have no common root: joint %u (%s) is under node %d (%s), joint 0 "
                               "under node %d (%s); parent all joints to one armature",
                               m->source, s, skin->name, j, m->nodes[skin->joints[j]].name, root, m->nodes[root].name,
                               common_root, m->nodes[common_root].name);
            common_root = root;
        }
    }
    return CB_OK;
}

static cb_status validate_primitives(const cb_model *m, cb_error *err)
{
    for (uint32_t p = 0; p < m->primitive_count; ++p) {
        const cb_primitive *prim = &m->primitives[p];
        if (prim->skin < 0 || prim->skin >= (int32_t)m->skin_count)
            return cb_fail(err, CB_ERR_INPUT, "%s: skinned primitive %u uses skin %d, which does not exist",
                           m->source, p, prim->skin);
        uint32_t joint_count = m->skins[prim->skin].joint_count;
        for (uint64_t i = 0; i < (uint64_t)prim->vertex_count * 4; ++i) {
            if (prim->weights[i] != 0 && prim->joints[i] >= joint_count)
                return cb_fail(err, CB_ERR_INPUT,
                               "%s: vertex %llu of mesh node %d uses joint %u, but its skin has %u joints",
                               m->source, (unsigned long long)(i / 4), prim->node, prim->joints[i], joint_count);
            if (!isfinite(prim->weights[i]))
                return cb_fail(err, CB_ERR_INPUT, "%s: vertex %llu of mesh node %d has a NaN or infinite weight",
                               m->source, (unsigned long long)(i / 4), prim->node);
        }
        for (uint64_t i = 0; i < (uint64_t)prim->vertex_count * 3; ++i)
            if (!isfinite(prim->positions[i]))
                return cb_fail(err, CB_ERR_INPUT, "%s: vertex %llu of mesh node %d has a NaN or infinite position",
                               m->source, (unsigned long long)(i / 3), prim->node);
        for (uint32_t i = 0; i < prim->index_count; ++i)
            if (prim->indices[i] >= prim->vertex_count)
                return cb_fail(err, CB_ERR_INPUT, "%s: index %u of mesh node %d is %u, past its %u vertices",
                               m->source, i, prim->node, prim->indices[i], prim->vertex_count);
    }
    return CB_OK;
}

/* True when no value is a NaN or an infinity (all exponent bits set). Branch-free, so the
 * compiler vectorizes it: animation data is most of a large file. */
static bool all_finite(const float *v, uint64_t n)
{
    /* NaN and infinity have every exponent bit set. Four lanes at a time, branch-free, so the
     * compiler keeps them in one vector register: this reads every key of every clip. */
    const uint32_t exponent = 0x7f800000u;
    uint32_t bad[4] = {0, 0, 0, 0};
    uint64_t i = 0;
    for (; i + 4 <= n; i += 4) {
        uint32_t bits[4];
        memcpy(bits, v + i, sizeof bits);
        for (int k = 0; k < 4; ++k) bad[k] |= (bits[k] & exponent) == exponent ? ~0u : 0u;
    }
    for (; i < n; ++i) {
        uint32_t bits;
        memcpy(&bits, v + i, sizeof bits);
        bad[0] |= (bits & exponent) == exponent;
    }
    return !(bad[0] | bad[1] | bad[2] | bad[3]);
}

/* ---- the key pre-scan: a channel's keys checked whole ----
 *
 * Most channels of a real file are clean: finite, increasing times and rotations of unit length
 * to float precision. Checking them one key at a time, with a branch and a message ready at each,
 * was a third of a big rig's load. These loops only answer "is the whole channel clean?": they
 * accumulate a flag without branching, so the compiler vectorizes them. A clean channel needs
 * nothing more; any other is checked key by key as before (validate_channel), which finds the
 * same first bad key, message and normalized copy as ever: the pre-scan decides nothing itself.
 * Library-private; tests/test_validate_keys.c checks them against scalar references. */

/* True when all n times (n >= 1) are finite and each is greater than the one before. */
bool cb_times_increasing(const float *times, uint64_t n)
{
    uint32_t bad = !(fabsf(times[0]) <= FLT_MAX); /* NaN compares false */
    for (uint64_t k = 1; k < n; ++k) bad |= !(fabsf(times[k]) <= FLT_MAX) | !(times[k] > times[k - 1]);
    return !bad;
}

/* The test validate_channel leaves a rotation key alone with: its squared length, in double,
 * within float rounding of 1. A NaN or an infinity is never unit. */
static inline uint32_t quat_not_unit(const float *q)
{
    double len2 = (double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3];
    return !(fabs(len2 - 1) <= 0x1p-22);
}

#if defined(__SSE2__)
/* Packed quaternions, two at a time in SSE2's two double lanes: the same conversions, products
 * and sums, in the same order, as quat_not_unit (so the same bits), with the components of the
 * two keys side by side. gcc leaves the plain loop scalar: it does not vectorize float-to-double
 * conversions of interleaved groups. */
static uint32_t packed_not_unit(const float *q, uint64_t count)
{
    const __m128d one = _mm_set1_pd(1), tolerance = _mm_set1_pd(0x1p-22), sign = _mm_set1_pd(-0.0);
    __m128d ok = _mm_castsi128_pd(_mm_set1_epi32(-1));
    uint64_t i = 0;
    for (; i + 2 <= count; i += 2) {
        __m128 k0 = _mm_loadu_ps(q + 4 * i), k1 = _mm_loadu_ps(q + 4 * i + 4);
        __m128d xy0 = _mm_cvtps_pd(k0), zw0 = _mm_cvtps_pd(_mm_movehl_ps(k0, k0));
        __m128d xy1 = _mm_cvtps_pd(k1), zw1 = _mm_cvtps_pd(_mm_movehl_ps(k1, k1));
        xy0 = _mm_mul_pd(xy0, xy0), zw0 = _mm_mul_pd(zw0, zw0), xy1 = _mm_mul_pd(xy1, xy1), zw1 = _mm_mul_pd(zw1, zw1);
        __m128d len2 = _mm_add_pd(_mm_add_pd(_mm_unpacklo_pd(xy0, xy1), _mm_unpackhi_pd(xy0, xy1)), _mm_unpacklo_pd(zw0, zw1));
        len2 = _mm_add_pd(len2, _mm_unpackhi_pd(zw0, zw1));
        __m128d off = _mm_andnot_pd(sign, _mm_sub_pd(len2, one)); /* fabs; a NaN stays NaN and fails <= */
        ok = _mm_and_pd(ok, _mm_cmple_pd(off, tolerance));
    }
    uint32_t bad = _mm_movemask_pd(ok) != 3;
    for (; i < count; ++i) bad |= quat_not_unit(q + 4 * i);
    return bad;
}
#else
static uint32_t packed_not_unit(const float *q, uint64_t count)
{
    uint32_t bad = 0;
    for (uint64_t i = 0; i < count; ++i) bad |= quat_not_unit(q + 4 * i);
    return bad;
}
#endif

/* True when the `count` quaternions at q, `stride` floats apart (4: LINEAR and STEP keys; 12: a
 * CUBICSPLINE key's value between its tangents), are all unit length within float rounding,
 * so validate_channel would neither copy nor normalize any of them. */
bool cb_rotations_unit(const float *q, uint64_t count, uint32_t stride)
{
    if (stride == 4) return !packed_not_unit(q, count);
    uint32_t bad = 0;
    for (uint64_t i = 0; i < count; ++i) bad |= quat_not_unit(q + (uint64_t)stride * i);
    return !bad;
}

/* True when validate_channel has nothing to check key by key: times finite and increasing
 * (or `times_checked`: the same times as the channel before, which passed), every value finite,
 * rotations unit. Node and key-count checks stay in validate_channel. */
static bool channel_keys_good(const cb_channel *ch, bool times_checked)
{
    if (ch->key_count == 0 || !ch->times || !ch->values) return false;
    uint32_t per_key = (uint32_t)path_components(ch->path) * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
    if (!times_checked && !cb_times_increasing(ch->times, ch->key_count)) return false;
    if (ch->path == CB_PATH_ROTATION && per_key == 4) /* unit keys are finite: one pass */
        return cb_rotations_unit(ch->values, ch->key_count, 4);
    if (!all_finite(ch->values, (uint64_t)ch->key_count * per_key)) return false;
    return ch->path != CB_PATH_ROTATION || cb_rotations_unit(ch->values + 4, ch->key_count, per_key);
}

static bool same_times(const cb_channel *a, const cb_channel *b)
{
    return a->times == b->times && a->key_count == b->key_count;
}

/* good[i] for the i-th channel over all clips, in order. */
typedef struct key_scan {
    const cb_model *model;
    const uint32_t *first; /* each clip's first channel's index in good */
    bool *good;
} key_scan;

static void scan_clip(const key_scan *s, uint32_t a)
{
    const cb_animation *anim = &s->model->animations[a];
    for (uint32_t c = 0; c < anim->channel_count; ++c) {
        const cb_channel *ch = &anim->channels[c];
        s->good[s->first[a] + c] = channel_keys_good(ch, c > 0 && same_times(&anim->channels[c - 1], ch));
    }
}

static void scan_share(void *ctx, uint32_t thread, uint32_t threads)
{
    const key_scan *s = ctx;
    for (uint32_t a = thread; a < s->model->animation_count; a += threads) scan_clip(s, a);
}

/* From this many keys on, the clips are scanned on several threads: below it, starting them
 * costs more than they save. */
#define SCAN_THREADED_KEYS 2000000u
#define SCAN_MAX_THREADS 8u

/* Fills good (one flag per channel over all clips, see key_scan) for validate_animations.
 * Each flag depends on its channel alone, so neither the thread count nor timing changes any. */
static void scan_keys(const cb_model *m, const uint32_t *first, bool *good)
{
    key_scan s = {m, first, good};
    uint64_t keys = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a)
        for (uint32_t c = 0; c < m->animations[a].channel_count; ++c) keys += m->animations[a].channels[c].key_count;
    long cores = keys >= SCAN_THREADED_KEYS ? sysconf(_SC_NPROCESSORS_ONLN) : 1;
    uint32_t threads = cores < 1 ? 1 : cores > (long)SCAN_MAX_THREADS ? SCAN_MAX_THREADS : (uint32_t)cores;
    if (threads > m->animation_count) threads = m->animation_count;
    if (threads > 1) cb_pool_run(threads, scan_share, &s);
    else
        for (uint32_t a = 0; a < m->animation_count; ++a) scan_clip(&s, a);
}

/* `checked`: key times an earlier channel of the clip passed (they are often shared). `good`:
 * the pre-scan found its keys clean (channel_keys_good), so only node and count are checked. */
static cb_status validate_channel(const cb_model *m, uint32_t a, uint32_t c, const cb_channel *checked, bool good,
                                  cb_error *err)
{
    const cb_animation *anim = &m->animations[a];
    cb_channel *ch = &anim->channels[c];
    if (ch->node < 0 || ch->node >= (int32_t)m->node_count)
        return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u targets node %d, which does not exist", m->source,
                       anim->name, c, ch->node);
    if (ch->key_count == 0)
        return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u (%s of %s) has no keys", m->source, anim->name, c,
                       path_name(ch->path), m->nodes[ch->node].name);
    if (good) return CB_OK;
    bool times_checked = checked && same_times(checked, ch);
    for (uint32_t k = 0; k < ch->key_count && !times_checked; ++k) {
        if (!isfinite(ch->times[k]))
            return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u key %u has a NaN or infinite time", m->source,
                           anim->name, c, k);
        if (k > 0 && !(ch->times[k] > ch->times[k - 1]))
            return cb_fail(err, CB_ERR_INPUT,
                           "%s: clip '%s' channel %u (%s of %s): key times are not increasing at key %u (%g after %g)",
                           m->source, anim->name, c, path_name(ch->path), m->nodes[ch->node].name, k,
                           (double)ch->times[k], (double)ch->times[k - 1]);
    }
    int comps = path_components(ch->path);
    int per_key = comps * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
    uint64_t value_count = (uint64_t)ch->key_count * per_key;
    for (uint64_t i = all_finite(ch->values, value_count) ? value_count : 0; i < value_count; ++i)
        if (!isfinite(ch->values[i]))
            return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u (%s of %s) key %llu has a NaN or infinite value",
                           m->source, anim->name, c, path_name(ch->path), m->nodes[ch->node].name,
                           (unsigned long long)(i / per_key));
    if (ch->path == CB_PATH_ROTATION) {
        /* Real exporters write keys of length 0.9998; glTF wants unit quaternions. Keys that
         * are unit to float precision are left as they are (most are). The first key that is
         * not gives the channel a copy of its values in the model's arena, which is normalized:
         * the keys may lie in the loader's read-only mapping of the file, which is never
         * written (cb_model.release drops its pages, and reading them again gives the file's
         * bytes). Tangents of cubic splines are not rotations and stay too. */
        int value_slot = ch->interp == CB_INTERP_CUBICSPLINE ? 1 : 0;
        const float *keys = ch->values; /* as loaded; `own` is the copy, once made */
        float *own = NULL;
        for (const float *q = keys + value_slot * 4; q < keys + value_count; q += per_key) {
            double len2 = (double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] + (double)q[3] * q[3];
            if (fabs(len2 - 1) <= 0x1p-22) continue; /* float rounding of a unit quaternion */
            if (len2 < 1e-24)
                return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' channel %u (rotation of %s) key %u is a zero quaternion",
                               m->source, anim->name, c, m->nodes[ch->node].name, (uint32_t)((q - keys) / per_key));
            if (!own && !(own = cb_arena_alloc(m->arena, value_count, sizeof(float))))
                return cb_fail(err, CB_ERR_INTERNAL, "%s: out of memory", m->source);
            if (ch->values != own) ch->values = memcpy(own, keys, value_count * sizeof(float));
            double inv = 1 / sqrt(len2);
            for (int i = 0; i < 4; ++i) own[q - keys + i] = (float)(q[i] * inv);
        }
    }
    return CB_OK;
}

static cb_status validate_animation(cb_model *m, uint32_t a, const bool *good, cb_error *err)
{
    cb_animation *anim = &m->animations[a];
    if (anim->channel_count == 0)
        return cb_fail(err, CB_ERR_INPUT, "%s: clip '%s' has no channels (remove it or give it keys)", m->source,
                       anim->name);
    anim->t0 = INFINITY;
    anim->t1 = -INFINITY;
    for (uint32_t c = 0; c < anim->channel_count; ++c) {
        if (validate_channel(m, a, c, c ? &anim->channels[c - 1] : NULL, good[c], err)) return err->status;
        const cb_channel *ch = &anim->channels[c];
        if (ch->times[0] < anim->t0) anim->t0 = ch->times[0];
        if (ch->times[ch->key_count - 1] > anim->t1) anim->t1 = ch->times[ch->key_count - 1];
    }
    return CB_OK;
}

/* Keeps the clips that pass; the others go to skipped_clips, in file order. good: the
 * pre-scan's flags, from first[a] on for clip a. */
static cb_status validate_clips(cb_model *m, const uint32_t *first, const bool *good, cb_error *err)
{
    m->skipped_clips = cb_model_alloc(m, m->animation_count, sizeof *m->skipped_clips);
    if (!m->skipped_clips) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    uint32_t kept = 0;
    cb_error first_error = {0};
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_error why = {0};
        if (!validate_animation(m, a, good + first[a], &why)) {
            m->animations[kept++] = m->animations[a];
            continue;
        }
        if (why.status != CB_ERR_INPUT) return *err = why, err->status;
        if (!first_error.status) first_error = why;
        struct cb_skipped_clip *skip = &m->skipped_clips[m->skipped_clip_count++];
        skip->name = m->animations[a].name;
        if (!(skip->reason = cb_model_strdup(m, why.message))) return cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    }
    m->animation_count = kept;
    if (kept == 0) return *err = first_error, err->status;
    return CB_OK;
}

/* The pre-scan (scan_keys) over every clip, then each clip checked (validate_clips). */
static cb_status validate_animations(cb_model *m, cb_error *err)
{
    if (m->animation_count == 0) return CB_OK;
    uint64_t channels = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a) channels += m->animations[a].channel_count;
    uint32_t *first = malloc(m->animation_count * sizeof *first);
    bool *good = channels < UINT32_MAX ? malloc(channels ? channels : 1) : NULL;
    cb_status rc = first && good ? CB_OK : cb_fail(err, CB_ERR_INTERNAL, "out of memory");
    for (uint32_t a = 0, at = 0; !rc && a < m->animation_count; at += m->animations[a++].channel_count) first[a] = at;
    if (!rc) scan_keys(m, first, good);
    if (!rc) rc = validate_clips(m, first, good, err);
    free(first);
    free(good);
    return rc;
}

cb_status cb_model_validate(cb_model *model, const cb_limits *limits, cb_error *err)
{
    cb_limits defaults = cb_default_limits();
    if (!limits) limits = &defaults;
    if (validate_nodes(model, err)) return err->status;
    normalize_node_transforms(model);
    if (validate_skins(model, limits, err) || validate_primitives(model, err) ||
        validate_animations(model, err))
        return err->status;
    return CB_OK;
}

int32_t cb_model_find_skin(const cb_model *model, const char *name)
{
    for (uint32_t i = 0; i < model->skin_count; ++i)
        if (strcmp(model->skins[i].name, name) == 0) return (int32_t)i;
    char *end;
    long idx = strtol(name, &end, 10);
    if (*name && !*end && idx >= 0 && idx < (long)model->skin_count) return (int32_t)idx;
    return -1;
}

int32_t cb_model_find_animation(const cb_model *model, const char *name)
{
    for (uint32_t i = 0; i < model->animation_count; ++i)
        if (strcmp(model->animations[i].name, name) == 0) return (int32_t)i;
    return -1;
}

const struct cb_skipped_clip *cb_model_find_skipped_clip(const cb_model *model, const char *name)
{
    for (uint32_t i = 0; i < model->skipped_clip_count; ++i)
        if (strcmp(model->skipped_clips[i].name, name) == 0) return &model->skipped_clips[i];
    return NULL;
}

void cb_model_release_clip(const cb_model *model, int32_t animation)
{
    if (!model->release || animation < 0 || (uint32_t)animation >= model->animation_count) return;
    const cb_animation *anim = &model->animations[animation];
    cb_byte_range *ranges = malloc(2 * (size_t)anim->channel_count * sizeof *ranges);
    if (!ranges) return; /* a hint: nothing lost */
    size_t n = 0;
    const float *times = NULL;
    for (uint32_t c = 0; c < anim->channel_count; ++c) {
        const cb_channel *ch = &anim->channels[c];
        size_t per_key = (ch->path == CB_PATH_ROTATION ? 4 : 3) * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
        if (ch->times != times) /* channels often share their times */
            ranges[n++] = (cb_byte_range){times = ch->times, (size_t)ch->key_count * sizeof(float)};
        ranges[n++] = (cb_byte_range){ch->values, (size_t)ch->key_count * per_key * sizeof(float)};
    }
    model->release(model->release_ctx, ranges, n);
    free(ranges);
}

uint64_t cb_model_skin_vertex_count(const cb_model *model, int32_t skin)
{
    uint64_t n = 0;
    for (uint32_t p = 0; p < model->primitive_count; ++p)
        if (model->primitives[p].skin == skin) n += model->primitives[p].vertex_count;
    return n;
}

uint64_t cb_model_skin_mesh_bytes(const cb_model *model, int32_t skin)
{
    uint64_t bytes = 0;
    for (uint32_t p = 0; p < model->primitive_count; ++p) {
        const cb_primitive *prim = &model->primitives[p];
        if (prim->skin == skin)
            bytes += (uint64_t)prim->vertex_count * prim->vertex_bytes + (uint64_t)prim->index_count * prim->index_bytes;
    }
    return bytes;
}
