/* test_stride_screen.c - a bake's strides screened on a quarter of their samples
 * (foot_cache_screen_strides, stride_feet.h): on every real model with feet (Cow, Husky and Fox,
 * whose walks and gallops stride; the robot, the spider, the rigged figure) and the sample
 * quadruped, every clip that strides is passed on and measured to cb_stride_measure's bits, and
 * a clip the screen answers does not stride by cb_stride_measure either; strides screened on
 * threads equal those screened one by one; and on the 200-joint rig `make bench` bakes, whose
 * dangling limbs touch down for 0-2.5% of the cycle, most clips are answered by the screen. */
#include "testutil.h"

#include <string.h>

#include "crowdbake/stride.h"
#include "../../src/core/foot_cache.h"

static const char *const models[] = {"assets/quaternius-cow/Cow.glb", "assets/quaternius-husky/Husky.glb",
                                     "assets/fox-bevy/Fox.glb", "assets/robot-quaternius-raylib/robot.glb",
                                     "assets/spider-animated-luanti/gltf_spider_animated.gltf",
                                     "assets/riggedfigure-raylib/rigged_figure.glb"};

/* Clips screened, passed on, and striding (by cb_stride_measure) over one model. */
typedef struct tally {
    uint32_t screened, passed, striding;
} tally;

/* The screened answer against the full one: equal, bit for bit, where the screen passed the
 * clip on; where it answered, no stride by either, and the same feet. */
static void check_clip(const cb_stride *full, const cb_stride *got, bool screened, const char *name)
{
    if (!screened) {
        if (memcmp(full, got, sizeof *full)) fail_msg("clip '%s': passed on, but not measured as alone (%s)", name, got->why);
        return;
    }
    if (full->stride) fail_msg("clip '%s' strides (%s), but the screen ruled it out", name, full->why);
    assert_false(got->stride);
    assert_true(got->speed == 0 && got->slide_mean == 0);
    assert_int_equal(got->foot_count, full->foot_count);
    for (uint32_t k = 0; k < full->foot_count; ++k) {
        assert_int_equal(got->feet[k].joint, full->feet[k].joint);
        assert_string_equal(got->feet[k].name, full->feet[k].name);
        assert_false(got->feet[k].strides);
    }
    assert_non_null(strstr(got->why, "no stride"));
}

/* Every clip of m framed at 30 fps: screened one by one (against cb_stride_measure), then on
 * two threads (against the ones screened one by one). */
static tally check_model(cb_model *m, const char *name)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    cb_clip_info *infos = calloc(m->animation_count ? m->animation_count : 1, sizeof *infos);
    cb_stride *one = calloc(m->animation_count ? m->animation_count : 1, sizeof *one);
    foot_cache *cache = foot_cache_create();
    foot_cache_screen_strides(cache);
    tally t = {0, 0, 0};
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_stride full;
        assert_int_equal(cb_clip_analyze(s, (int32_t)a, 30, -1, NULL, &infos[a], &err), CB_OK);
        cb_stride_measure(s, &infos[a], &full);
        uint32_t before = foot_cache_screened(cache);
        foot_cache_stride(cache, s, &infos[a], &one[a]);
        bool screened = foot_cache_screened(cache) > before;
        check_clip(&full, &one[a], screened, m->animations[a].name);
        t.screened += screened, t.passed += !screened && full.foot_count, t.striding += full.stride;
    }
    foot_cache_free(cache);
    cache = foot_cache_create();
    foot_cache_screen_strides(cache);
    foot_cache_measure_clips(cache, s, infos, m->animation_count, 2);
    for (uint32_t a = 0; a < m->animation_count; ++a) {
        cb_sampler_set_loop(s, &infos[a]);
        cb_stride threaded;
        foot_cache_stride(cache, s, &infos[a], &threaded);
        if (memcmp(&threaded, &one[a], sizeof threaded)) fail_msg("clip '%s': screened on threads, not as alone", m->animations[a].name);
    }
    if (m->animation_count >= 2) assert_int_equal(foot_cache_screened(cache), t.screened);
    printf("  %s: %u clips, %u striding, %u passed on by the screen, %u answered by it\n", name, m->animation_count,
           t.striding, t.passed, t.screened);
    foot_cache_free(cache);
    free(infos), free(one);
    cb_sampler_free(s);
    return t;
}

static void test_screen_passes_every_stride_on(void **state)
{
    (void)state;
    uint32_t striding = 0;
    for (size_t i = 0; i < COUNT_OF(models); ++i) {
        cb_model *m = load_shared(models[i]);
        striding += check_model(m, models[i]).striding;
        cb_model_free(m);
    }
    char path[1024];
    sample_path(path, sizeof path, "quadruped");
    cb_model *q = load_or_fail(path);
    striding += check_model(q, "the sample quadruped").striding;
    cb_model_free(q);
    assert_true(striding >= 6); /* walks and gallops: the screen was asked about real strides */
}

/* The bench rig, 200 joints, 6 clips of 10 s as `make bench` makes them (it bakes 30). */
static void test_screen_answers_the_bench_rig(void **state)
{
    (void)state;
    char gen[1100], cmd[2400];
    snprintf(gen, sizeof gen, "%s", crowdbake_exe());
    *strrchr(gen, '/') = 0;
    snprintf(cmd, sizeof cmd, "mkdir -p " TEST_TMP "/stride_screen && %s/gen_samples --bench " TEST_TMP
             "/stride_screen 200 6 10 >/dev/null", gen);
    assert_int_equal(system(cmd), 0);
    cb_model *m = load_or_fail(TEST_TMP "/stride_screen/bench_j200_c6_s10.glb");
    tally t = check_model(m, "the 200-joint bench rig");
    assert_int_equal(t.striding, 0);
    assert_true(t.screened * 2 >= m->animation_count); /* its limbs touch down for 0-2.5% of each cycle */
    cb_model_free(m);
}

/* The screen's arithmetic (stride.c): a foot planted for 20 of the 240 intervals in R stretches
 * of r samples each (r - 1 intervals) is planted on at least floor(r / 4) of every 4th sample in
 * each, however the stretches fall; over every such foot of up to five stretches, at least 3 in
 * all, and six stretches can leave it 2 (7, 7, 3, 3, 3, 3). Stretches in non-decreasing length. */
static uint32_t fewest_seen(uint32_t stretches, uint32_t from, uint32_t intervals, uint32_t seen)
{
    if (intervals >= 20) return seen;
    if (!stretches) return UINT32_MAX; /* not planted for long enough: not such a foot */
    uint32_t best = UINT32_MAX;
    for (uint32_t r = from; r <= 21; ++r) {
        uint32_t got = fewest_seen(stretches - 1, r, intervals + r - 1, seen + r / 4);
        best = got < best ? got : best;
    }
    return best;
}

static void test_screen_arithmetic(void **state)
{
    (void)state;
    for (uint32_t stretches = 1; stretches <= 5; ++stretches) assert_true(fewest_seen(stretches, 1, 0, 0) >= 3);
    assert_int_equal(fewest_seen(6, 1, 0, 0), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_screen_passes_every_stride_on),
        cmocka_unit_test(test_screen_answers_the_bench_rig),
        cmocka_unit_test(test_screen_arithmetic),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
