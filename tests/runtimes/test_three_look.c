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

/* The number after "key": inside the object that follows "section": in the check's JSON. */
static double number_in(const char *section, const char *key)
{
    char pattern[96];
    snprintf(pattern, sizeof pattern, "\"%s\":", section);
    const char *at = strstr(out, pattern);
    if (!at) fail_msg("no \"%s\" in the check's output: %s", section, out);
    snprintf(pattern, sizeof pattern, "\"%s\":", key);
    if (!(at = strstr(at, pattern))) fail_msg("no \"%s\" after \"%s\" in the check's output", key, section);
    return atof(at + strlen(pattern));
}

static void link_and_bake(const char *asset, const char *name)
{
    char path[PATH_MAX], cmd[3 * PATH_MAX];
    shared_path(path, sizeof path, asset);
    /* Root motion kept and 30 fps: three.js plays the glTF's own keys. */
    snprintf(cmd, sizeof cmd, "ln -s \"$(realpath %s)\" " TMP "/%s.glb && %s bake " TMP "/%s.glb -o " TMP "/%s.pal -q --fps 30 "
             "--max-error 1000", path, name, crowdbake_exe(), name, name);
    assert_int_equal(system(cmd), 0);
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
    double share = number_in(name, "share"), covered = number_in(name, "covered");
    const char *beige_at = strstr(strstr(out, name), "\"beige\":");
    assert_non_null(beige_at);
    double beige = atof(strstr(beige_at, "\"share\":") + 8);
    double calls = number_in(name, "draw_calls"), n = number_in(name, "materials"), tex = number_in(name, "textured");
    double ref_colours = number_in(name, "colours_reference"), herd_colours = number_in(name, "colours_herd");
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
