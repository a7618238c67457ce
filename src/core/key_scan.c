/* key_scan.c - see key_scan.h: animation keys checked a whole channel at a time. */
#include "key_scan.h"
#include "pool.h"

#include <float.h>
#include <math.h>
#include <string.h>
#include <unistd.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* True when no value is a NaN or an infinity (all exponent bits set). Branch-free, so the
 * compiler vectorizes it: animation data is most of a large file. */
bool cb_floats_finite(const float *v, uint64_t n)
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
 * Library-private; tests/lib/test_validate_keys.c checks them against scalar references. */

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
    uint32_t per_key = (uint32_t)cb_path_components(ch->path) * (ch->interp == CB_INTERP_CUBICSPLINE ? 3 : 1);
    if (!times_checked && !cb_times_increasing(ch->times, ch->key_count)) return false;
    if (ch->path == CB_PATH_ROTATION && per_key == 4) /* unit keys are finite: one pass */
        return cb_rotations_unit(ch->values, ch->key_count, 4);
    if (!cb_floats_finite(ch->values, (uint64_t)ch->key_count * per_key)) return false;
    return ch->path != CB_PATH_ROTATION || cb_rotations_unit(ch->values + 4, ch->key_count, per_key);
}

bool cb_same_key_times(const cb_channel *a, const cb_channel *b)
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
        s->good[s->first[a] + c] = channel_keys_good(ch, c > 0 && cb_same_key_times(&anim->channels[c - 1], ch));
    }
}

static void scan_share(void *ctx, uint32_t thread, uint32_t threads)
{
    const key_scan *s = ctx;
    for (uint32_t a = thread; a < s->model->animation_count; a += threads) scan_clip(s, a);
}

/* From this many keys on, the clips are scanned on several threads: a key costs about 3 ns
 * (12 instructions), so 256 K keys are some 0.7 ms of scanning, over ten times what starting a
 * thread costs; below it, starting them costs more than they save. (It was 2 M keys: the
 * 200-joint, 30-clip benchmark rig's 1.8 M keys were scanned on one thread, 5 ms of its load.) */
#define SCAN_THREADED_KEYS 262144u
#define SCAN_MAX_THREADS 8u

/* Fills good (one flag per channel over all clips, see key_scan) for validate_animations.
 * Each flag depends on its channel alone, so neither the thread count nor timing changes any. */
void cb_scan_channel_keys(const cb_model *m, const uint32_t *first, bool *good)
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
