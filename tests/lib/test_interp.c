/* test_interp.c - glTF interpolation against hand-computed values. */
#include "testutil.h"

#define _USE_MATH_DEFINES
#include <math.h>
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#include "../../src/core/cb_math.h"

static cb_channel make_channel(cb_path path, cb_interp interp, float *times, float *values, uint32_t keys)
{
    cb_channel ch = {0};
    ch.node = 0;
    ch.path = path;
    ch.interp = interp;
    ch.key_count = keys;
    ch.times = times;
    ch.values = values;
    return ch;
}

static void test_linear_translation_and_clamping(void **state)
{
    (void)state;
    float times[] = {1.0f, 3.0f};
    float values[] = {0, 0, 0, 10, -20, 4};
    cb_channel ch = make_channel(CB_PATH_TRANSLATION, CB_INTERP_LINEAR, times, values, 2);
    double v[4];
    cb_channel_eval(&ch, 1.5, v); /* a quarter of the way */
    assert_float_equal(v[0], 2.5, 1e-12);
    assert_float_equal(v[1], -5.0, 1e-12);
    assert_float_equal(v[2], 1.0, 1e-12);
    cb_channel_eval(&ch, 0.0, v); /* before the first key: clamp */
    assert_float_equal(v[0], 0.0, 0);
    cb_channel_eval(&ch, 99.0, v); /* after the last key: clamp */
    assert_float_equal(v[0], 10.0, 0);
    assert_float_equal(v[1], -20.0, 0);
}

static void test_slerp_halfway_is_45_degrees(void **state)
{
    (void)state;
    /* identity to 90 degrees about Z: halfway is 45 degrees, (0, 0, sin 22.5, cos 22.5). */
    float s = (float)sqrt(0.5);
    float times[] = {0, 1};
    float values[] = {0, 0, 0, 1, 0, 0, s, s};
    cb_channel ch = make_channel(CB_PATH_ROTATION, CB_INTERP_LINEAR, times, values, 2);
    double v[4];
    cb_channel_eval(&ch, 0.5, v);
    assert_float_equal(v[2], sin(M_PI / 8), 1e-7);
    assert_float_equal(v[3], cos(M_PI / 8), 1e-7);
    /* A nlerp would give the same halfway point; at a quarter slerp differs from nlerp. */
    cb_channel_eval(&ch, 0.25, v);
    assert_float_equal(v[2], sin(M_PI / 16), 1e-7);
    assert_float_equal(v[3], cos(M_PI / 16), 1e-7);
}

static void test_slerp_takes_the_short_way_across_the_hemisphere_flip(void **state)
{
    (void)state;
    /* Key 1 is the 20-degree rotation written as its negative (-q): the same rotation. The
     * short arc from identity passes 10 degrees; the long arc would pass 190. */
    double half = 20.0 * M_PI / 180 / 2;
    float times[] = {0, 1};
    float values[] = {0, 0, 0, 1, 0, (float)-sin(half), 0, (float)-cos(half)};
    cb_channel ch = make_channel(CB_PATH_ROTATION, CB_INTERP_LINEAR, times, values, 2);
    double v[4];
    cb_channel_eval(&ch, 0.5, v);
    double angle = 2 * acos(fabs(v[3]));
    assert_float_equal(angle, 10.0 * M_PI / 180, 1e-6);
    assert_true(v[1] * (v[3] < 0 ? -1 : 1) > 0); /* about +Y */
}

static void test_step_holds_and_reaches_keys_within_a_microsecond(void **state)
{
    (void)state;
    float times[] = {0.0f, 1.0f / 3.0f, 1.0f};
    float values[] = {1, 1, 1, 2, 2, 2, 3, 3, 3};
    cb_channel ch = make_channel(CB_PATH_SCALE, CB_INTERP_STEP, times, values, 3);
    double v[4];
    cb_channel_eval(&ch, 0.3, v);
    assert_float_equal(v[0], 1.0, 0);
    /* 1/3 in double is just below... or above the float32 key; within 1e-6 s it counts. */
    cb_channel_eval(&ch, 1.0 / 3.0 - 5e-7, v);
    assert_float_equal(v[0], 2.0, 0);
    cb_channel_eval(&ch, 1.0 / 3.0 - 5e-6, v);
    assert_float_equal(v[0], 1.0, 0);
    cb_channel_eval(&ch, 5.0, v);
    assert_float_equal(v[0], 3.0, 0);
}

static void test_cubicspline_scales_tangents_by_the_key_interval(void **state)
{
    (void)state;
    /* One component (x of a translation): p0 = 0, p1 = 1, out-tangent of key 0 = 2, in-tangent
     * of key 1 = 0; keys 2 s apart. At s = 0.5: h00 = .5, h10 = .125, h01 = .5, h11 = -.125:
     * p = .5*0 + .125*2*2 + .5*1 + (-.125)*2*0 = 1.0 (without scaling by 2 s: 0.75). */
    float times[] = {1.0f, 3.0f};
    float values[] = {/* key 0: in, value, out */ 0, 0, 0, 0, 0, 0, 2, 0, 0,
                      /* key 1 */ 0, 0, 0, 1, 0, 0, 5, 0, 0};
    cb_channel ch = make_channel(CB_PATH_TRANSLATION, CB_INTERP_CUBICSPLINE, times, values, 2);
    double v[4];
    cb_channel_eval(&ch, 2.0, v);
    assert_float_equal(v[0], 1.0, 1e-12);
    cb_channel_eval(&ch, 0.0, v); /* clamps to the value, not a tangent */
    assert_float_equal(v[0], 0.0, 0);
    cb_channel_eval(&ch, 3.5, v);
    assert_float_equal(v[0], 1.0, 0);
}

static void test_cubicspline_rotations_are_normalized(void **state)
{
    (void)state;
    float s = (float)sqrt(0.5);
    float times[] = {0, 1};
    float values[] = {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, /* key 0 */
                      0, 0, 0, 0, 0, 0, s, s, 0, 0, 0, 0 /* key 1 */};
    cb_channel ch = make_channel(CB_PATH_ROTATION, CB_INTERP_CUBICSPLINE, times, values, 2);
    double v[4];
    cb_channel_eval(&ch, 0.5, v);
    /* Hermite with zero tangents at s=.5 gives (p0+p1)/2 = (0,0,.354,.854), then normalized. */
    double n = sqrt(0.5 * s * 0.5 * s + (0.5 + 0.5 * s) * (0.5 + 0.5 * s));
    assert_float_equal(v[2], 0.5 * s / n, 1e-7);
    assert_float_equal(v[3], (0.5 + 0.5 * s) / n, 1e-7);
    assert_float_equal(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3], 1.0, 1e-12);
}

/* The assimp test files: a plain node animated 0 -> 1 s with each interpolation mode; the
 * expected numbers come from the file's own keys, worked by hand. */
static void test_assimp_interpolation_files(void **state)
{
    (void)state;
    cb_model *lin = load_shared("assets/assimp-animation-interpolation/animation_interpolation_linear.gltf");
    cb_model *step = load_shared("assets/assimp-animation-interpolation/animation_interpolation_step.gltf");
    cb_model *cubic = load_shared("assets/assimp-animation-interpolation/animation_interpolation_cubic.gltf");
    const cb_channel *cl = &lin->animations[0].channels[0], *cs = &step->animations[0].channels[0],
                     *cc = &cubic->animations[0].channels[0];
    assert_int_equal(cl->interp, CB_INTERP_LINEAR);
    assert_int_equal(cs->interp, CB_INTERP_STEP);
    assert_int_equal(cc->interp, CB_INTERP_CUBICSPLINE);
    int comps = cl->path == CB_PATH_ROTATION ? 4 : 3;
    double v[4], a[4], b[4];
    for (int k = 0; k < comps; ++k) a[k] = cl->values[k], b[k] = cl->values[comps + k];
    cb_channel_eval(cl, 0.5, v);
    if (comps == 3)
        for (int k = 0; k < 3; ++k) assert_float_equal(v[k], 0.5 * (a[k] + b[k]), 1e-6);
    cb_channel_eval(cs, 0.999, v);
    for (int k = 0; k < comps; ++k) assert_float_equal(v[k], cs->values[k], 0);
    cb_channel_eval(cs, 1.0, v);
    for (int k = 0; k < comps; ++k) assert_float_equal(v[k], cs->values[comps + k], 0);
    /* Cubic at the midpoint: (p0 + p1)/2 + dt/8 * (b0 - a1). */
    cb_channel_eval(cc, 0.5, v);
    double dt = cc->times[1] - cc->times[0];
    if (comps == 3)
        for (int k = 0; k < 3; ++k) {
            double p0 = cc->values[3 + k], b0 = cc->values[6 + k], a1 = cc->values[9 + k], p1 = cc->values[12 + k];
            assert_float_equal(v[k], 0.5 * (p0 + p1) + dt / 8 * (b0 - a1), 1e-6);
        }
    cb_model_free(lin);
    cb_model_free(step);
    cb_model_free(cubic);
}

static void test_frame_count_rule(void **state)
{
    (void)state;
    assert_int_equal(cb_clip_step_count(0.7083, 30), 21); /* Fox Walk: round(21.25) */
    assert_int_equal(cb_clip_step_count(1.0, 30), 30);
    assert_int_equal(cb_clip_step_count(0.0, 30), 1);     /* a one-key clip still has a frame */
    assert_int_equal(cb_clip_step_count(0.01, 30), 1);
    assert_int_equal(cb_clip_step_count(1.0 / 60, 30), 1); /* round(0.5) = 1 */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_linear_translation_and_clamping),
        cmocka_unit_test(test_slerp_halfway_is_45_degrees),
        cmocka_unit_test(test_slerp_takes_the_short_way_across_the_hemisphere_flip),
        cmocka_unit_test(test_step_holds_and_reaches_keys_within_a_microsecond),
        cmocka_unit_test(test_cubicspline_scales_tangents_by_the_key_interval),
        cmocka_unit_test(test_cubicspline_rotations_are_normalized),
        cmocka_unit_test(test_assimp_interpolation_files),
        cmocka_unit_test(test_frame_count_rule),
    };
    return cmocka_run_group_tests_name("interpolation", tests, NULL, NULL);
}
