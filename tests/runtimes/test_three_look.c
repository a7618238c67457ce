/* test_three_look.c - the three.js herd looks like the model (tests/runtimes/browser/look_check.mjs): in
 * headless Chromium, a one-instance CrowdbakeHerd with its default materials (each primitive's own
 * glTF material, patched by the same skinning) against three.js's own SkinnedMesh + AnimationMixer
 * of the same glTF at the same clip time, under the same lights and camera, compared in colour:
 * Cow (7 materials) and Husky (5), multi-material models, and the Fox, whose one material is
 * textured (UVs). The old look, one beige MeshLambertMaterial for every primitive, is the negative
 * control; the herd draws once per material. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>

#define TMP TEST_TMP "/three_look"

static char out[1 << 14];

static void link_and_bake(const char *asset, const char *name)
{
    char path[PATH_MAX];
    shared_path(path, sizeof path, asset);
    link_model(path, TMP, name);
    /* Root motion kept and 30 fps: three.js plays the glTF's own keys. */
    assert_int_equal(run(NULL, 0, "%s bake " TMP "/%s.glb -o " TMP "/%s.pal -q --fps 30 --max-error 1000", crowdbake_exe(), name,
                         name), 0);
}

static int setup(void **state)
{
    (void)state;
    assert_int_equal(system("rm -rf " TMP " && mkdir -p " TMP), 0);
    link_and_bake("assets/quaternius-cow/Cow.glb", "cow");
    link_and_bake("assets/quaternius-husky/Husky.glb", "husky");
    link_and_bake("assets/fox-bevy/Fox.glb", "fox");
    int rc = run_command("node tests/runtimes/browser/look_check.mjs " TMP " 'cow:AnimalArmature|Walk:0.5' "
                         "'husky:AnimalArmature|Walk:0.4' 'fox:Walk:0.3' 2>&1", out, sizeof out);
    if (rc) fail_msg("look_check.mjs failed (%d): %s", rc, out);
    return 0;
}

static void check_model(const char *name, double materials, double textured)
{
    double share = json_number_in(out, name, "share"), covered = json_number_in(out, name, "covered");
    const char *beige_at = strstr(strstr(out, name), "\"beige\":");
    assert_non_null(beige_at);
    double beige = json_number_after(beige_at, "share");
    double calls = json_number_in(out, name, "draw_calls"), n = json_number_in(out, name, "materials"), tex = json_number_in(out, name, "textured");
    double ref_colours = json_number_in(out, name, "colours_reference"), herd_colours = json_number_in(out, name, "colours_herd");
    printf("  %s: %.0f covered pixels, %.2f%% differ in colour from three.js's SkinnedMesh (one beige material: %.1f%%); "
           "%.0f materials (%.0f textured), %.0f draw calls; %.0f colours drawn, three.js %.0f\n",
           name, covered, 100 * share, 100 * beige, n, tex, calls, herd_colours, ref_colours);
    assert_true(covered > 2000);
    assert_true(share < 0.01);
    assert_true(beige > 0.5);
    assert_true(n == materials && tex == textured && calls == materials);
}

static void test_multi_material_cow(void **state)
{
    (void)state;
    check_model("cow", 7, 0);
}

static void test_multi_material_husky(void **state)
{
    (void)state;
    check_model("husky", 5, 0);
}

static void test_textured_fox(void **state)
{
    (void)state;
    check_model("fox", 1, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_multi_material_cow),
        cmocka_unit_test(test_multi_material_husky),
        cmocka_unit_test(test_textured_fox),
    };
    return cmocka_run_group_tests_name("three_look", tests, setup, NULL);
}
