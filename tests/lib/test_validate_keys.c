/* test_validate_keys.c - cb_model_validate's key pre-scan (src/core/key_scan.c) decides as the key-by-key
 * checks do: whole-channel scans against plain scalar references at every length and every
 * position of a bad key, and whole models whose clips are kept, normalized or skipped with the
 * same messages as before, on one thread and (from 256 K keys) on several. */
#include "testutil.h"

#include <float.h>
#include <math.h>

/* Library-private (src/core/key_scan.h): the pre-scan's whole-channel checks. */
bool cb_times_increasing(const float *times, uint64_t n);
bool cb_rotations_unit(const float *q, uint64_t count, uint32_t stride);

/* ---- scalar references: the key-by-key checks of validate_channel ---- */

static bool ref_times_increasing(const float *t, uint64_t n)
{
    for (uint64_t k = 0; k < n; ++k) {
        if (!isfinite(t[k])) return false;
        if (k > 0 && !(t[k] > t[k - 1])) return false;
    }
    return true;
}

static bool ref_rotations_unit(const float *q, uint64_t count, uint32_t stride)
{
    for (uint64_t i = 0; i < count; ++i) {
        const float *k = q + i * stride;
        double len2 = (double)k[0] * k[0] + (double)k[1] * k[1] + (double)k[2] * k[2] + (double)k[3] * k[3];
        if (!(fabs(len2 - 1) <= 0x1p-22)) return false;
    }
    return true;
}

/* w of (0, 0, 0, w): 1 + 2^-23 squares to 1 + 2^-22 + 2^-46, just outside the tolerance;
 * 1 - 2^-23 to 1 - 2^-22 + 2^-46, just inside; 1 - 3 * 2^-24 is outside below. */
#define W_OUTSIDE_ABOVE (1.0f + 0x1p-23f)
#define W_INSIDE_BELOW (1.0f - 0x1p-23f)
#define W_OUTSIDE_BELOW (1.0f - 0x3p-24f)

/* Lengths around every vector width and block (2, 4, 8, 16 lanes; odd tails). */
#define MAX_LEN 41

static void test_times_match_the_scalar_check_at_every_length_and_position(void **state)
{
    (void)state;
    const float bad_values[] = {NAN, INFINITY, -INFINITY};
    float t[MAX_LEN];
    for (uint64_t n = 1; n <= MAX_LEN; ++n) {
        for (uint64_t k = 0; k < n; ++k) t[k] = 0.25f * (float)k - 1;
        assert_true(cb_times_increasing(t, n));
        assert_true(ref_times_increasing(t, n));
        for (uint64_t at = 0; at < n; ++at) {
            float keep = t[at];
            for (size_t b = 0; b < COUNT_OF(bad_values); ++b) {
                t[at] = bad_values[b];
                assert_false(cb_times_increasing(t, n));
                assert_int_equal(cb_times_increasing(t, n), ref_times_increasing(t, n));
            }
            if (at > 0) {
                t[at] = t[at - 1]; /* equal: not increasing */
                assert_false(cb_times_increasing(t, n));
                t[at] = nextafterf(t[at - 1], -INFINITY); /* one ulp back */
                assert_false(cb_times_increasing(t, n));
                t[at] = nextafterf(t[at - 1], INFINITY); /* one ulp on: still increasing */
                bool ok = at + 1 == n || t[at] < t[at + 1];
                assert_int_equal(cb_times_increasing(t, n), ok);
                assert_int_equal(ref_times_increasing(t, n), ok);
            }
            t[at] = keep;
        }
    }
    float big[2] = {-FLT_MAX, FLT_MAX}; /* finite extremes pass */
    assert_true(cb_times_increasing(big, 2));
}

static void fill_unit(float *q, uint64_t count, uint32_t stride)
{
    for (uint64_t i = 0; i < count; ++i) {
        float *k = q + i * stride;
        for (uint32_t c = 0; c < stride; ++c) k[c] = 7; /* tangents of a cubic spline: not looked at */
        k[0] = 0, k[1] = 0.6f, k[2] = 0, k[3] = 0.8f;     /* 0.36 + 0.64 within float rounding of 1 */
        if (i % 3 == 1) k[0] = 1, k[1] = 0, k[3] = 0;
    }
}

static void test_rotations_match_the_scalar_check_at_every_length_and_position(void **state)
{
    (void)state;
    const float bad_w[] = {W_OUTSIDE_ABOVE, W_OUTSIDE_BELOW, NAN, INFINITY, 0};
    const float good_w[] = {1, W_INSIDE_BELOW, nextafterf(1, 0)};
    static float q[MAX_LEN * 12];
    for (uint32_t stride = 4; stride <= 12; stride += 8) {
        for (uint64_t n = 0; n <= MAX_LEN; ++n) {
            fill_unit(q, n, stride);
            assert_true(cb_rotations_unit(q, n, stride));
            assert_true(ref_rotations_unit(q, n, stride));
            for (uint64_t at = 0; at < n; ++at) {
                float *k = q + at * stride, keep[4];
                memcpy(keep, k, sizeof keep);
                k[0] = k[1] = k[2] = 0;
                for (size_t b = 0; b < COUNT_OF(bad_w); ++b) {
                    k[3] = bad_w[b];
                    assert_false(ref_rotations_unit(q, n, stride));
                    assert_false(cb_rotations_unit(q, n, stride));
                }
                for (size_t g = 0; g < COUNT_OF(good_w); ++g) {
                    k[3] = good_w[g];
                    assert_true(ref_rotations_unit(q, n, stride));
                    assert_true(cb_rotations_unit(q, n, stride));
                }
                k[3] = 1, k[1] = NAN; /* a NaN in another lane */
                assert_false(cb_rotations_unit(q, n, stride));
                memcpy(k, keep, sizeof keep);
                if (stride == 12) { /* a NaN tangent is all_finite's to find, not this scan's */
                    k[5] = NAN;
                    assert_true(cb_rotations_unit(q, n, stride));
                    k[5] = 7;
                }
            }
        }
    }
}

/* ---- whole models: the clips kept, normalized or skipped as before ---- */

/* One root node, no skin (validation needs none) and `clips` clips, each of one rotation
 * channel of n keys (LINEAR) and a translation channel sharing its times, all on the same keys. */
static cb_model *keys_model(float *times, float *rotations, float *moves, uint32_t n, uint32_t clips)
{
    cb_model *m = cb_model_create("keys-test");
    m->node_count = 1;
    m->nodes = cb_model_alloc(m, 1, sizeof(cb_node));
    m->nodes[0].name = "root";
    m->nodes[0].parent = -1;
    m->nodes[0].rotation[3] = 1;
    m->nodes[0].scale[0] = m->nodes[0].scale[1] = m->nodes[0].scale[2] = 1;
    m->animation_count = clips;
    m->animations = cb_model_alloc(m, clips, sizeof(cb_animation));
    for (uint32_t c = 0; c < clips; ++c) {
        cb_animation *a = &m->animations[c];
        a->name = c ? "clip2" : "clip";
        a->channel_count = 2;
        a->channels = cb_model_alloc(m, 2, sizeof(cb_channel));
        a->channels[0] = (cb_channel){0, CB_PATH_ROTATION, CB_INTERP_LINEAR, n, times, rotations};
        a->channels[1] = (cb_channel){0, CB_PATH_TRANSLATION, CB_INTERP_LINEAR, n, times, moves};
    }
    return m;
}

typedef struct keys {
    float *times, *rotations, *moves;
    uint32_t n, clips;
} keys;

static keys clean_keys(uint32_t n, uint32_t clips)
{
    keys k = {malloc(n * sizeof(float)), malloc(n * 4 * sizeof(float)), malloc(n * 3 * sizeof(float)), n, clips};
    assert_non_null(k.times), assert_non_null(k.rotations), assert_non_null(k.moves);
    for (uint32_t i = 0; i < n; ++i) k.times[i] = (float)i / 30;
    fill_unit(k.rotations, n, 4);
    for (uint32_t i = 0; i < n * 3; ++i) k.moves[i] = (float)(i % 7);
    return k;
}

static void free_keys(keys *k) { free(k->times), free(k->rotations), free(k->moves); }

/* Validates a model of k; returns it (NULL when no clip passed, *err says why). */
static cb_model *validate(const keys *k, cb_error *err)
{
    cb_model *m = keys_model(k->times, k->rotations, k->moves, k->n, k->clips);
    if (cb_model_validate(m, NULL, err) == CB_OK) return m;
    cb_model_free(m);
    return NULL;
}

static void expect_skipped(const keys *k, const char *why)
{
    cb_error err = {0};
    assert_null(validate(k, &err));
    assert_int_equal(err.status, CB_ERR_INPUT);
    if (!strstr(err.message, why)) fail_msg("expected \"%s\" in: %s", why, err.message);
}

static void check_models(uint32_t n, uint32_t clips)
{
    uint32_t at = n - 2; /* near the end: past every full vector block of a long channel */
    keys k = clean_keys(n, clips);
    cb_error err = {0};
    cb_model *m = validate(&k, &err);
    assert_non_null(m);
    assert_int_equal(m->animation_count, clips);
    for (uint32_t c = 0; c < clips; ++c) {
        assert_ptr_equal(m->animations[c].channels[0].values, k.rotations); /* clean keys stay where they lie */
        assert_true(m->animations[c].t1 == k.times[n - 1]);
    }
    cb_model_free(m);

    /* A key just outside the tolerance: a normalized copy, the file's keys untouched. */
    float *q = k.rotations + 4 * (size_t)at;
    q[0] = q[1] = q[2] = 0, q[3] = W_OUTSIDE_ABOVE;
    m = validate(&k, &err);
    assert_non_null(m);
    assert_int_equal(m->animation_count, clips);
    for (uint32_t c = 0; c < clips; ++c) {
        const float *own = m->animations[c].channels[0].values;
        assert_ptr_not_equal(own, k.rotations);
        assert_true(own[4 * (size_t)at + 3] == 1.0f);
        assert_memory_equal(own, k.rotations, 4 * (size_t)at * sizeof(float)); /* the others copied as they are */
    }
    assert_true(q[3] == W_OUTSIDE_ABOVE);
    cb_model_free(m);
    q[3] = W_INSIDE_BELOW; /* just inside: left alone */
    m = validate(&k, &err);
    assert_non_null(m);
    assert_ptr_equal(m->animations[0].channels[0].values, k.rotations);
    cb_model_free(m);
    q[3] = 0;
    expect_skipped(&k, "is a zero quaternion");
    q[3] = NAN;
    expect_skipped(&k, "has a NaN or infinite value");
    q[3] = 1;

    char why[128];
    k.times[at] = NAN;
    snprintf(why, sizeof why, "key %u has a NaN or infinite time", at);
    expect_skipped(&k, why);
    k.times[at] = k.times[at - 1];
    snprintf(why, sizeof why, "key times are not increasing at key %u", at);
    expect_skipped(&k, why);
    k.times[at] = (float)at / 30;
    k.moves[3 * (size_t)at + 1] = INFINITY; /* the translation channel (shared times) */
    expect_skipped(&k, "channel 1 (translation of root)");
    free_keys(&k);
}

static void test_models_decide_as_before(void **state)
{
    (void)state;
    for (uint32_t n = 3; n <= 19; ++n) check_models(n, 1);
}

/* 256 K keys and more are scanned on several threads (scan_keys): the same decisions. */
static void test_models_decide_as_before_when_scanned_on_threads(void **state)
{
    (void)state;
    check_models(550001, 2); /* two clips of two channels: 2.2 M keys, a clip a thread */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_times_match_the_scalar_check_at_every_length_and_position),
        cmocka_unit_test(test_rotations_match_the_scalar_check_at_every_length_and_position),
        cmocka_unit_test(test_models_decide_as_before),
        cmocka_unit_test(test_models_decide_as_before_when_scanned_on_threads),
    };
    return cmocka_run_group_tests_name("validate keys", tests, NULL, NULL);
}
