/* test_clip_memo.c - one bake run's clip analyses made once (src/core/clip_memo.h) stand in for
 * analyzing again, bit for bit: on real models (Cow and Husky, whose loops close over a slightly
 * off last key and are corrected; Fox; the robot, whose punch is a one-shot), every clip analyzed
 * through the memo at 30 fps and then asked at 24, 60 and 30 fps with each loop override gives
 * cb_clip_analyze's cb_clip_info on a fresh sampler, byte for byte, and leaves its sampler as
 * analyzing does (the joint matrices sampled after, inside the clip and across a loop's wrap,
 * have the same bits); analyses made side by side on threads (clip_memo_prefetch) are the ones
 * made one by one, and each is made once. */
#include "testutil.h"

#include <string.h>

#include "../../src/core/clip_memo.h"
#include "../../src/core/palette_bake.h" /* palette_choose_rates, palette_memo_keep_search */
#include "crowdbake/runtime.h"

static const char *const models[] = {"assets/quaternius-cow/Cow.glb", "assets/quaternius-husky/Husky.glb",
                                     "assets/fox-bevy/Fox.glb", "assets/robot-quaternius-raylib/robot.glb"};

/* The joint matrices of both samplers at times inside clip a and past its last key (a loop's
 * wrap): the same bits. */
static void assert_same_samples(const cb_model *m, cb_sampler *x, cb_sampler *y, const cb_clip_info *info)
{
    uint32_t n = m->skins[0].joint_count * 16;
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
    assert_non_null(a), assert_non_null(b);
    double span = info->t1 - info->t0, times[] = {info->t0 + 0.37 * span, info->t1 + 0.5 * info->key_interval,
                                                  info->t0 + 0.999 * info->duration};
    for (int k = 0; k < 3; ++k) {
        cb_sample_joint_matrices(x, info->animation, times[k], a);
        cb_sample_joint_matrices(y, info->animation, times[k], b);
        if (memcmp(a, b, n * sizeof *a)) fail_msg("clip '%s': sampled differently at %g", m->animations[info->animation].name, times[k]);
    }
    free(a), free(b);
}

/* Every clip analyzed through the memo at 30 fps with each loop override, then asked again at
 * each rate with the overrides taken in turn, so that the sampler holds another loop of the clip
 * each time it is asked (a stand-in must set its own). */
static void test_memo_answers_are_analyses(void **state)
{
    (void)state;
    static const double rates[] = {24, 60, 30};
    static const int loops[] = {-1, 1, 0};
    uint32_t corrected = 0;
    for (size_t mi = 0; mi < sizeof models / sizeof *models; ++mi) {
        cb_model *m = load_shared(models[mi]);
        cb_error err = {0};
        cb_sampler *s = cb_sampler_create(m, 0, &err);
        clip_memo *memo = clip_memo_create();
        assert_non_null(s), assert_non_null(memo);
        cb_clip_info kept, fresh;
        for (uint32_t a = 0; a < m->animation_count; ++a)
            for (int l = 0; l < 3; ++l) assert_int_equal(clip_memo_analyze(memo, s, (int32_t)a, 30, loops[l], NULL, &kept, &err), CB_OK);
        for (int r = 0; r < 3; ++r)
            for (int l = 0; l < 3; ++l)
                for (uint32_t a = 0; a < m->animation_count; ++a) {
                    memset(&kept, 0, sizeof kept);
                    cb_sampler *alone = cb_sampler_create(m, 0, &err);
                    assert_non_null(alone);
                    assert_int_equal(clip_memo_analyze(memo, s, (int32_t)a, rates[r], loops[l], NULL, &kept, &err), CB_OK);
                    assert_int_equal(cb_clip_analyze(alone, (int32_t)a, rates[r], loops[l], NULL, &fresh, &err), CB_OK);
                    if (memcmp(&kept, &fresh, sizeof kept))
                        fail_msg("%s clip '%s' at %g fps, loop %d: the memo's analysis differs", models[mi],
                                 m->animations[a].name, rates[r], loops[l]);
                    assert_same_samples(m, s, alone, &fresh);
                    corrected += l == 0 && fresh.loop_reason == CB_LOOP_CLOSED_CORRECTED;
                    cb_sampler_free(alone);
                }
        printf("  %s: %u clips, %u analyses kept\n", models[mi], m->animation_count, clip_memo_count(memo));
        assert_int_equal(clip_memo_count(memo), 3 * m->animation_count); /* once per loop override */
        clip_memo_free(memo);
        cb_sampler_free(s);
        cb_model_free(m);
    }
    assert_true(corrected > 0); /* the corrected loops were among them */
}

/* Prefetched on 2 and 4 threads: the analyses one made one by one, made once each. */
static void test_prefetched_analyses_are_analyses(void **state)
{
    (void)state;
    for (size_t mi = 0; mi < sizeof models / sizeof *models; ++mi) {
        cb_model *m = load_shared(models[mi]);
        cb_error err = {0};
        cb_sampler *s = cb_sampler_create(m, 0, &err), *alone = cb_sampler_create(m, 0, &err);
        assert_non_null(s), assert_non_null(alone);
        clip_ask *asks = malloc(m->animation_count * sizeof *asks);
        assert_non_null(asks);
        for (uint32_t a = 0; a < m->animation_count; ++a) asks[a] = (clip_ask){(int32_t)a, 30, -1};
        for (uint32_t threads = 2; threads <= 4; threads += 2) {
            clip_memo *memo = clip_memo_create();
            assert_non_null(memo);
            clip_memo_prefetch(memo, s, asks, m->animation_count, NULL, threads);
            assert_int_equal(clip_memo_count(memo), m->animation_count > 1 ? m->animation_count : 0);
            for (uint32_t a = 0; a < m->animation_count; ++a) {
                cb_clip_info kept, fresh;
                assert_int_equal(clip_memo_analyze(memo, s, (int32_t)a, 30, -1, NULL, &kept, &err), CB_OK);
                assert_int_equal(cb_clip_analyze(alone, (int32_t)a, 30, -1, NULL, &fresh, &err), CB_OK);
                if (memcmp(&kept, &fresh, sizeof kept)) fail_msg("%s clip %u: prefetched differently", models[mi], a);
            }
            assert_int_equal(clip_memo_count(memo), m->animation_count); /* none analyzed again */
            clip_memo_free(memo);
        }
        free(asks);
        cb_sampler_free(alone), cb_sampler_free(s);
        cb_model_free(m);
    }
}

/* What a bake run's memo takes from its rate searches (palette_memo_keep_search: each clip's
 * analysis kept with its poses) stands in for analyzing the clip at 30 fps, as the speed
 * reference asks, bit for bit, and nothing is analyzed again (Cow: the loops corrected too). */
static void test_search_analyses_stand_in(void **state)
{
    (void)state;
    static const char *const searched[] = {"assets/quaternius-cow/Cow.glb", "assets/fox-bevy/Fox.glb"};
    for (size_t mi = 0; mi < 2; ++mi) {
        cb_model *m = load_shared(searched[mi]);
        cb_error err = {0};
        cb_sampler *s = cb_sampler_create(m, 0, &err);
        uint32_t n = m->animation_count;
        assert_true(n <= 32);
        cb_clip_plan plan[32];
        cb_rate_goal goals[32];
        search_keep *keep = search_keep_create(n);
        clip_memo *memo = clip_memo_create();
        assert_non_null(s), assert_non_null(keep), assert_non_null(memo);
        cb_bake_options o = cb_default_bake_options();
        for (uint32_t i = 0; i < n; ++i)
            plan[i] = (cb_clip_plan){(int32_t)i, NULL, -1, 0, false, false, 0, NULL}, goals[i] = (cb_rate_goal){1, 120, CB_ROWS_BEST};
        assert_int_equal(palette_choose_rates(s, &o, plan, n, goals, NULL, keep, NULL, &err), CB_OK);
        for (uint32_t i = 0; i < n; ++i) palette_memo_keep_search(memo, s, keep->poses[i], &o.limits);
        assert_int_equal(clip_memo_count(memo), n);
        for (uint32_t a = 0; a < n; ++a) {
            cb_clip_info kept, fresh;
            memset(&kept, 0, sizeof kept);
            cb_sampler *alone = cb_sampler_create(m, 0, &err);
            assert_non_null(alone);
            assert_int_equal(clip_memo_analyze(memo, s, (int32_t)a, 30, -1, &o.limits, &kept, &err), CB_OK);
            assert_int_equal(cb_clip_analyze(alone, (int32_t)a, 30, -1, &o.limits, &fresh, &err), CB_OK);
            if (memcmp(&kept, &fresh, sizeof kept)) fail_msg("%s clip '%s': the search's analysis differs", searched[mi], m->animations[a].name);
            assert_same_samples(m, s, alone, &fresh);
            cb_sampler_free(alone);
        }
        assert_int_equal(clip_memo_count(memo), n); /* every one taken, none analyzed */
        clip_memo_free(memo);
        search_keep_free(keep);
        cb_sampler_free(s);
        cb_model_free(m);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_memo_answers_are_analyses),
        cmocka_unit_test(test_prefetched_analyses_are_analyses),
        cmocka_unit_test(test_search_analyses_stand_in),
    };
    return cmocka_run_group_tests_name("clip memo", tests, NULL, NULL);
}
