/* test_babylon.c - `crowdbake bake --format babylon` (.bvat.json) in real Babylon.js
 * (tests/babylon/check_babylon.mjs, headless Chromium): Babylon's own VertexAnimationBaker bakes
 * Cow.glb loaded by @babylonjs/loaders at the file's row times, and the two must agree value by
 * value; thin instances drawn by BakedVertexAnimationManager from each must cover the same
 * pixels. Three broken files (the joints reversed, the handedness mirrored into the matrices,
 * rows without Babylon's extra bones and matrix) must fail those checks. The quadruped sample
 * without its skin's skeleton node (Babylon finds the joints' common ancestor) and with a walk and
 * a run that travel (a loop's closing row is its end pose) agrees too. u16 is refused; the same
 * bake twice gives the same bytes. */
#include "testutil.h"

#define TMP TEST_TMP "/babylon"

static void require_babylon(void)
{
    FILE *f = fopen("tests/babylon/node_modules/.package-lock.json", "r");
    if (!f) fail_msg("tests/babylon: npm packages not installed (make test installs them; or: cd tests/babylon && npm ci)");
    fclose(f);
}

static int setup(void **state)
{
    (void)state;
    char cmd[4096], cow[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    if (system("rm -rf " TMP " && mkdir -p " TMP)) return -1;
    /* Root motion kept: Babylon's bake plays the clips as the file has them. */
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 --root-motion keep -o " TMP "/cow.bvat.json -q", crowdbake_exe(), cow);
    return system(cmd);
}

static void test_babylon_bakes_the_same_matrices_and_draws_the_same_herd(void **state)
{
    (void)state;
    require_babylon();
    char cmd[4096], cow[1024], out[16384];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "node tests/babylon/check_babylon.mjs %s " TMP "/cow.bvat.json --controls 2>&1", cow);
    int rc = run_command(cmd, out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    /* Babylon's skeleton of Cow: 42 joints and 2 non-joint ancestors (RootNode, AnimalArmature). */
    assert_non_null(strstr(out, "ok   cow.bvat.json: 180x753 texels, as Babylon's bake of 44 bones (+1) and 753 rows"));
    assert_non_null(strstr(out, "ok   cow.bvat.json: worst difference from Babylon's VertexAnimationBaker"));
    assert_non_null(strstr(out, "ok   cow.bvat.json: thin instances through BakedVertexAnimationManager: 0 of"));
    assert_non_null(strstr(out, "ok   control reversed-bones fails"));
    assert_non_null(strstr(out, "ok   control mirrored-handedness fails"));
    assert_non_null(strstr(out, "ok   control joints-only fails"));
}

static void test_a_skin_without_skeleton_node_and_travelling_loops_agree(void **state)
{
    (void)state;
    require_babylon();
    char cmd[4096], quadruped[1024], out[16384];
    sample_path(quadruped, sizeof quadruped, "quadruped");
    snprintf(cmd, sizeof cmd, "node tests/babylon/strip_skeleton.mjs %s " TMP "/quadruped.glb", quadruped);
    assert_int_equal(system(cmd), 0);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/quadruped.glb --fps 30 --root-motion keep -o " TMP "/quadruped.bvat.json -q",
             crowdbake_exe());
    assert_int_equal(system(cmd), 0);
    int rc = run_command("node tests/babylon/check_babylon.mjs " TMP "/quadruped.glb " TMP "/quadruped.bvat.json --values-only 2>&1",
                         out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "ok   quadruped.bvat.json: 168x269 texels, as Babylon's bake of 41 bones (+1) and 269 rows"));
    assert_non_null(strstr(out, "ok   quadruped.bvat.json: worst difference from Babylon's VertexAnimationBaker"));
}

static void test_u16_is_refused_and_output_repeats(void **state)
{
    (void)state;
    char cmd[4096], cow[1024], out[4096];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/u16.bvat.json --precision u16 2>&1", crowdbake_exe(), cow);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_USAGE);
    assert_non_null(strstr(out, "Babylon.js's baked vertex animation data is Float32 matrices"));
    assert_null(fopen(TMP "/u16.bvat.json", "rb"));
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 --root-motion keep -o " TMP "/again --format babylon -q",
             crowdbake_exe(), cow);
    assert_int_equal(system(cmd), 0);
    size_t a, b;
    char *x = read_whole_file(TMP "/again.bvat.json", &a), *y = read_whole_file(TMP "/cow.bvat.json", &b);
    assert_true(a == b && memcmp(x, y, a) == 0);
    free(x), free(y);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_babylon_bakes_the_same_matrices_and_draws_the_same_herd),
        cmocka_unit_test(test_a_skin_without_skeleton_node_and_travelling_loops_agree),
        cmocka_unit_test(test_u16_is_refused_and_output_repeats),
    };
    return cmocka_run_group_tests_name("babylon", tests, setup, NULL);
}
