/* test_foot_cache.c - one bake's foot analyses measured once (src/core/foot_cache.h) give what
 * each analysis measured on its own before: on real quadrupeds whose gallops stride (Cow, Husky,
 * Fox) and the robot, every clip's stride asked of the cache (framed at 30 fps, then at another
 * rate) equals cb_stride_measure's, field for field; the per-row travel with the cache the speed
 * reference filled equals the uncached one; the joints a sole reads, sampled alone, have the bits
 * of the whole skin's (also on the 200-joint bench rig); strides measured side by side on
 * threads equal those measured one by one; and the speed reference that skips one-shots and action-named clips picks
 * what measuring every clip picks. */
#include "testutil.h"

#include <string.h>

#include "crowdbake/locomotion.h"
#include "crowdbake/row_travel.h"
#include "crowdbake/stride.h"
#include "../../src/core/foot_cache.h"
#include "../../src/core/sampler.h"
#include "../../src/core/stride_feet.h"

static const char *const models[] = {"assets/quaternius-cow/Cow.glb", "assets/quaternius-husky/Husky.glb", "assets/fox-bevy/Fox.glb",
                                     "assets/robot-quaternius-raylib/robot.glb"};

static void assert_same_stride(const cb_stride *a, const cb_stride *b, const char *clip)
{
    if (memcmp(a, b, sizeof *a)) fail_msg("clip '%s': the cached stride differs (%s / %s)", clip, a->why, b->why);
}

/* Each clip framed at 30 fps, then at 60 (twice the rows: only slide_mean_varying reads them),
 * then at 30 again: the cache measures once and answers the rest, each as cb_stride_measure. */
static void test_cached_strides_are_measured_ones(void **state)
{
    (void)state;
    uint32_t striding = 0;
    for (size_t mi = 0; mi < sizeof models / sizeof *models; ++mi) {
        cb_model *m = load_shared(models[mi]);
        cb_error err = {0};
        cb_sampler *s = cb_sampler_create(m, 0, &err);
        assert_non_null(s);
        foot_cache *cache = foot_cache_create();
        assert_non_null(cache);
        static const double rates[] = {30, 60, 30};
        for (uint32_t a = 0; a < m->animation_count; ++a)
            for (int r = 0; r < 3; ++r) {
                cb_clip_info info;
                cb_stride alone, cached;
                assert_int_equal(cb_clip_analyze(s, (int32_t)a, rates[r], -1, NULL, &info, &err), CB_OK);
                cb_stride_measure(s, &info, &alone);
                foot_cache_stride(cache, s, &info, &cached);
                assert_same_stride(&alone, &cached, m->animations[a].name);
                striding += r == 0 && alone.stride;
            }
        uint32_t measured, reused;
        foot_cache_counts(cache, &measured, &reused);
        printf("  %s: %u clips measured, %u answers reused\n", models[mi], measured, reused);
        assert_int_equal(measured, m->animation_count);
        assert_int_equal(reused, 2 * m->animation_count);
        foot_cache_free(cache);
        cb_sampler_free(s);
        cb_model_free(m);
    }
    printf("  %u striding clips among them\n", striding);
    assert_true(striding >= 4); /* the gallops and walks of Cow, Husky and Fox */
}

/* The per-row travel of every clip in place at its 30 fps rows: after the speed reference has
 * filled the cache (as cb_bake_job_run orders them), the same offsets and words as alone. */
static void test_row_travel_from_the_cache_is_the_same(void **state)
{
    (void)state;
    uint32_t applied = 0;
    for (size_t mi = 0; mi < 2; ++mi) {
        cb_model *m = load_shared(models[mi]);
        cb_error err = {0};
        cb_sampler *s = cb_sampler_create(m, 0, &err);
        foot_cache *cache = foot_cache_create();
        char why[256];
        double ref = speed_reference_cached(cache, NULL, m, 0, NULL, 0, 1, why, sizeof why);
        assert_true(ref > 0);
        for (uint32_t a = 0; a < m->animation_count; ++a) {
            cb_clip_info info;
            cb_row_travel alone, shared;
            assert_int_equal(cb_clip_analyze(s, (int32_t)a, 30, -1, NULL, &info, &err), CB_OK);
            float *o1 = calloc(info.frames + 1, sizeof *o1), *o2 = calloc(info.frames + 1, sizeof *o2);
            cb_row_travel_measure(s, &info, true, info.frames, o1, &alone);
            row_travel_measure_cached(cache, s, &info, true, info.frames, o2, &shared);
            assert_memory_equal(&alone, &shared, sizeof alone);
            assert_memory_equal(o1, o2, info.frames * sizeof *o1);
            applied += alone.applied;
            free(o1), free(o2);
        }
        foot_cache_free(cache);
        cb_sampler_free(s);
        cb_model_free(m);
    }
    assert_true(applied >= 2); /* Cow's and Husky's gallops */
}

/* The old rule, every clip measured: the slowest clip that follows the speed. */
static double speed_reference_measuring_all(const cb_model *m)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_ground_speed *gs = malloc(sizeof *gs);
    double best = 0;
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_clip_info info;
        char word[64], words[160] = "", reason[512];
        if (cb_clip_analyze(s, (int32_t)a, 30, -1, NULL, &info, &err)) continue;
        cb_measure_ground_speed(s, &info, gs);
        int kind = cb_name_says_locomotion(m->animations[a].name, word, sizeof word);
        if (kind) snprintf(words, sizeof words, "the clip's name says '%s'", word);
        if (cb_decide_locomotion(kind, words, info.loops, gs, false, reason, sizeof reason) && gs->speed > 0 &&
            (best == 0 || gs->speed < best))
            best = gs->speed;
    }
    free(gs);
    cb_sampler_free(s);
    return best;
}

static void test_speed_reference_skips_only_what_cannot_matter(void **state)
{
    (void)state;
    for (size_t mi = 0; mi < sizeof models / sizeof *models; ++mi) {
        cb_model *m = load_shared(models[mi]);
        char why[256];
        double now = cb_speed_reference(m, 0, NULL, 0, why, sizeof why), before = speed_reference_measuring_all(m);
        printf("  %s: %.9g units/s (%s)\n", models[mi], now, why);
        assert_true(now == before);
        cb_model_free(m);
    }
}

/* The sole joints alone, sampled at every 30 fps row of every clip, one time at a time and in
 * batches of CB_SAMPLE_BATCH (the channels evaluated over the batch's times together, the
 * matrices composed side by side): each one's 16 doubles are cb_sample_joint_matrices' bits,
 * and so is where each sole stands (foot_sole_at_lanes against foot_sole_at). */
static void check_batch(cb_sampler *s, int32_t a, const stride_feet *feet, const double *times, uint32_t count,
                        double *lanes, double *all, size_t *checked)
{
    const cb_joint_subset *sub = feet->joints;
    cb_sample_joint_subset_batch(s, a, times, count, feet->joints, lanes);
    double h[4][CB_SAMPLE_BATCH], x[4][CB_SAMPLE_BATCH], z[4][CB_SAMPLE_BATCH];
    for (uint32_t k = 0; k < feet->count && k < 4; ++k) foot_sole_at_lanes(&feet->soles[k], sub, lanes, h[k], x[k], z[k]);
    for (uint32_t i = 0; i < count; ++i) {
        cb_sample_joint_matrices(s, a, times[i], all);
        for (uint32_t k = 0; k < sub->joint_count; ++k, ++*checked)
            for (int c = 0; c < 16; ++c) {
                double want = all[(size_t)sub->joints[k] * 16 + c], got = lanes[((size_t)k * 16 + c) * CB_SAMPLE_BATCH + i];
                if (memcmp(&want, &got, sizeof want)) fail_msg("joint %u, value %d at %g: %.17g, not %.17g", sub->joints[k], c, times[i], got, want);
            }
        for (uint32_t k = 0; k < feet->count && k < 4; ++k) {
            double want_h, want_xz[2];
            foot_sole_at(&feet->soles[k], all, &want_h, want_xz);
            assert_memory_equal(&want_h, &h[k][i], sizeof want_h);
            assert_memory_equal(&want_xz[0], &x[k][i], sizeof want_h);
            assert_memory_equal(&want_xz[1], &z[k][i], sizeof want_h);
        }
    }
}

/* The 200-joint rig `make bench` measures (gen_samples --bench, 4 clips of 2 s): its soles hang
 * from 20-joint limbs, so their joints are sampled over most of its nodes. */
static cb_model *bench_rig(void)
{
    char gen[1100], cmd[2400];
    snprintf(gen, sizeof gen, "%s", crowdbake_exe());
    *strrchr(gen, '/') = 0;
    snprintf(cmd, sizeof cmd, "mkdir -p " TEST_TMP "/foot_cache && %s/gen_samples --bench " TEST_TMP "/foot_cache 200 4 2 >/dev/null", gen);
    assert_int_equal(system(cmd), 0);
    cb_error err = {0};
    cb_model *m = cb_gltf_load(TEST_TMP "/foot_cache/bench_j200_c4_s2.glb", NULL, &err);
    if (!m) fail_msg("%s", err.message);
    return m;
}

static void check_sole_bits(cb_model *m, const char *name)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    stride_feet feet;
    assert_true(stride_feet_find(s, &feet));
    size_t bones = m->skins[0].joint_count, checked = 0;
    assert_true(feet.joints->joint_count >= 2 && feet.joints->joint_count < bones);
    double *all = malloc(bones * 16 * sizeof(double));
    double *lanes = malloc(feet.joints->joint_count * 16 * CB_SAMPLE_BATCH * sizeof(double)), times[CB_SAMPLE_BATCH];
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, (int32_t)a, 30, -1, NULL, &info, &err), CB_OK); /* its wrap */
        uint32_t count = 0;
        for (uint32_t f = 0; f <= info.frames; ++f) {
            double t = info.t0 + f * info.duration / info.frames;
            check_batch(s, (int32_t)a, &feet, &t, 1, lanes, all, &checked);
            times[count++] = t;
            if (count < CB_SAMPLE_BATCH && f < info.frames) continue;
            check_batch(s, (int32_t)a, &feet, times, count, lanes, all, &checked);
            count = 0;
        }
    }
    printf("  %s: %u of %zu joints sampled for %u soles, over %u nodes; %zu matrices checked\n", name,
           feet.joints->joint_count, bones, feet.count, feet.joints->count, checked);
    free(all), free(lanes);
    stride_feet_free(&feet);
    cb_sampler_free(s);
}

/* Batches of one clip after another, of a single time between them: the rest lanes kept from
 * one batch of a clip to the next, the channels written into their nodes' lanes and the local
 * and global matrices composed four lanes at a time give cb_sample_joint_matrices' bits. */
static void test_sole_joints_alone_have_the_same_bits(void **state)
{
    (void)state;
    for (size_t mi = 0; mi < sizeof models / sizeof *models; ++mi) {
        cb_model *m = load_shared(models[mi]);
        check_sole_bits(m, models[mi]);
        cb_model_free(m);
    }
    cb_model *rig = bench_rig();
    check_sole_bits(rig, "the 200-joint bench rig");
    cb_model_free(rig);
}

/* Every clip's stride measured side by side on 4 threads (foot_cache_measure_clips), each on a
 * sampler of its own, is cb_stride_measure's field for field, answered from the cache without
 * measuring again; and the speed reference on 4 threads is the one on 1, with the same words. */
static void check_threaded_strides(cb_model *m, const char *name)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info *infos = calloc(m->animation_count, sizeof *infos);
    for (uint32_t a = 0; a < m->animation_count; ++a)
        assert_int_equal(cb_clip_analyze(s, (int32_t)a, 30, -1, NULL, &infos[a], &err), CB_OK);
    foot_cache *cache = foot_cache_create();
    foot_cache_measure_clips(cache, s, infos, m->animation_count, 4);
    uint32_t measured, reused;
    foot_cache_counts(cache, &measured, &reused);
    assert_int_equal(measured, m->animation_count); /* every clip, before any is asked */
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_stride alone, cached;
        cb_stride_measure(s, &infos[a], &alone);
        foot_cache_stride(cache, s, &infos[a], &cached);
        assert_same_stride(&alone, &cached, m->animations[a].name);
    }
    foot_cache_counts(cache, &measured, &reused);
    assert_int_equal(measured, m->animation_count);
    assert_int_equal(reused, m->animation_count);
    foot_cache_free(cache);
    char why1[256], why4[256];
    foot_cache *c1 = foot_cache_create(), *c4 = foot_cache_create();
    double one = speed_reference_cached(c1, NULL, m, 0, NULL, 0, 1, why1, sizeof why1);
    double four = speed_reference_cached(c4, NULL, m, 0, NULL, 0, 4, why4, sizeof why4);
    printf("  %s: %u strides on 4 threads; speed reference %.9g (%s)\n", name, m->animation_count, four, why4);
    assert_memory_equal(&one, &four, sizeof one);
    assert_string_equal(why1, why4);
    foot_cache_free(c1), foot_cache_free(c4);
    free(infos);
    cb_sampler_free(s);
}

static void test_strides_on_threads_are_measured_ones(void **state)
{
    (void)state;
    for (size_t mi = 0; mi < sizeof models / sizeof *models; ++mi) {
        cb_model *m = load_shared(models[mi]);
        check_threaded_strides(m, models[mi]);
        cb_model_free(m);
    }
    cb_model *rig = bench_rig();
    check_threaded_strides(rig, "the 200-joint bench rig");
    cb_model_free(rig);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cached_strides_are_measured_ones),
        cmocka_unit_test(test_row_travel_from_the_cache_is_the_same),
        cmocka_unit_test(test_speed_reference_skips_only_what_cannot_matter),
        cmocka_unit_test(test_sole_joints_alone_have_the_same_bits),
        cmocka_unit_test(test_strides_on_threads_are_measured_ones),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
