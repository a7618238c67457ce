/* test_three_herd.c - what a game needs from the three.js drop-in (runtimes/web/crowdbake_three.mjs,
 * CrowdbakeHerd), in headless Chromium (tests/runtimes/browser/herd_check.mjs): animated shadows under a
 * directional, a spot and a point light equal to those of three.js's own SkinnedMesh + AnimationMixer
 * (an unskinned depth material fails); frustum culling against the clip table's animated bounds
 * (no draw behind the camera, one in view, bounds that follow a moved instance) holding every
 * vertex of every baked row and mid-row of Cow and the fish; per-instance tints and scale, the
 * clip rate at a world speed divided by the scale; motion vectors equal to the finite difference
 * of three.js's CPU skinning at t - dt and t. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <math.h>

#define TMP TEST_TMP "/three_herd"

static void bake(const char *name, const char *more)
{
    char cmd[2 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/%s.glb -o " TMP "/%s.pal -q %s", crowdbake_exe(), name, name, more);
    assert_int_equal(system(cmd), 0);
}

static char out[1 << 16];

static int setup(void **state)
{
    (void)state;
    assert_int_equal(system("rm -rf " TMP " && mkdir -p " TMP), 0);
    char fox[PATH_MAX], cow[PATH_MAX], fish[PATH_MAX];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    sample_path(fish, sizeof fish, "fish");
    link_model(fox, TMP, "fox");
    link_model(cow, TMP, "cow");
    link_model(fish, TMP, "fish");
    bake("fox", "");                          /* root motion kept: three plays the clip with its travel */
    bake("cow", "--root-motion in-place");    /* as a herd the game moves */
    bake("fish", "--root-motion in-place");
    int rc = run_command("node tests/runtimes/browser/herd_check.mjs " TMP " 2>&1", out, sizeof out);
    if (rc) fail_msg("herd_check.mjs failed (%d): %s", rc, out);
    return 0;
}

/* Per light: the herd's shadow against three's skinned one at two clip times (share of the
 * shadowed pixels where they differ), and between the two times. */
static void test_shadows_move_with_the_animation(void **state)
{
    (void)state;
    const char *lights[] = {"directional", "spot", "point"};
    for (int l = 0; l < 3; ++l) {
        const char *light = lights[l], *at = out;
        char key[32];
        snprintf(key, sizeof key, "\"%s\":", light);
        assert_non_null(at = strstr(out, key));
        for (int i = 0; i < 2; ++i) {
            assert_non_null(at = strstr(at + 1, "\"shadow_pixels\":"));
            double pixels = json_number_after(at, "shadow_pixels"), herd = json_number_after(at, "herd");
            double unskinned = json_number_after(at, "unskinned");
            printf("  %s light, time %d: %.0f shadow pixels; herd vs three.js skinning %.2f%%, unskinned depth %.0f%%\n",
                   light, i, pixels, 100 * herd, 100 * unskinned);
            assert_true(pixels > 300);
            assert_true(herd < 0.02);
            assert_true(unskinned > 0.1);
        }
        double moved = json_number_after(at, "between_times");
        printf("  %s light: the herd's shadow differs on %.0f%% of its pixels between the two times\n", light, 100 * moved);
        assert_true(moved > 0.1);
    }
}

static void test_culling_uses_the_animated_bounds(void **state)
{
    (void)state;
    double in_view = json_number_in(out, "culling", "in_view"), behind = json_number_in(out, "culling", "behind"),
           moved = json_number_in(out, "culling", "moved_into_view");
    printf("  draw calls: in view %.0f, behind the camera %.0f, an instance moved back into view %.0f\n", in_view, behind,
           moved);
    assert_true(in_view == 1 && behind == 0 && moved == 1);
    assert_non_null(strstr(out, "\"frustum_culled\":true"));
    for (int m = 0; m < 2; ++m) {
        const char *name = m ? "fish" : "cow";
        double box = json_number_in(out, name, "worst_outside_box"), sphere = json_number_in(out, name, "worst_outside_sphere");
        double bind = json_number_in(out, name, "outside_bind_pose_box");
        printf("  %s: %.0f vertices x %.0f rows and mid-rows x 3 placements; the vertex nearest the bounds lies %.2f model "
               "heights inside the box, %.2f inside the sphere; the geometry's own box misses %.0f\n", name,
               json_number_in(out, name, "vertices"), json_number_in(out, name, "instances"), -box, -sphere, bind);
        assert_true(box <= 0 && sphere <= 0);
        assert_true(bind > 1000); /* what three would cull with, without the clip table */
    }
}

static void test_tints_and_scale_per_instance(void **state)
{
    (void)state;
    double red = json_number_in(out, "red", "pixels"), red_left = json_number_in(out, "red", "left");
    double blue = json_number_in(out, "blue", "pixels"), blue_left = json_number_in(out, "blue", "left");
    double red_h = json_number_in(out, "red", "height"), blue_h = json_number_in(out, "blue", "height");
    printf("  red instance %.0f pixels (%.0f on its side's left), blue %.0f (%.0f); heights %.0f and %.0f px (scale 2)\n",
           red, red_left, blue, blue_left, red_h, blue_h);
    assert_true(red > 20 && red_left == red && blue > 20 && blue_left == 0);
    assert_true(fabs(blue_h / red_h - 2) <= 2.0 / red_h); /* within a pixel of twice the height */
    const char *scales[] = {"1", "2", "4"};
    for (int i = 0; i < 3; ++i) {
        char got[32], want[32];
        snprintf(got, sizeof got, "rate_scale_%s", scales[i]);
        snprintf(want, sizeof want, "expected_rate_scale_%s", scales[i]);
        double g = json_number_in(out, "variety", got), w = json_number_in(out, "variety", want);
        printf("  scale %s at 80 units/s: %.4g rows/s (fps x speed / (scale x speed reference) = %.4g)\n", scales[i], g, w);
        assert_true(fabs(g - w) <= 1e-5 * w);
    }
    double before = json_number_in(out, "variety", "frame_before_rescale");
    double after = json_number_in(out, "variety", "frame_after_rescale");
    printf("  grown from scale 2 to 4 while walking: frame %.4f before, %.4f after\n", before, after);
    assert_true(fabs(before - after) < 1e-3);
}

static void test_motion_vectors_are_the_finite_difference(void **state)
{
    (void)state;
    double herd = json_number_in(out, "motion", "error"), px = json_number_in(out, "motion", "mean_velocity_px");
    double none = json_number_in(out, "no_previous_frame", "error"), wrong = json_number_in(out, "wrong_direction", "error");
    printf("  velocity (mean %.2f px a frame) vs three.js skinning's finite difference: error %.2f%% of it; previous time "
           "= now %.0f%%, t + dt %.0f%%\n", px, 100 * herd, 100 * none, 100 * wrong);
    assert_true(px > 0.5);
    assert_true(herd < 0.02);
    assert_true(none > 0.9 && wrong > 1.5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shadows_move_with_the_animation),
        cmocka_unit_test(test_culling_uses_the_animated_bounds),
        cmocka_unit_test(test_tints_and_scale_per_instance),
        cmocka_unit_test(test_motion_vectors_are_the_finite_difference),
    };
    return cmocka_run_group_tests_name("three_herd", tests, setup, NULL);
}
