/* test_mesh_look.c - `crowdbake mesh` keeps what the model looks like (tests/runtimes/browser/
 * mesh_look_check.mjs): three.js's GLTFLoader in headless Chromium reads the source model and the
 * written mesh, and finds, primitive by primitive, the same material (type, colour, metalness,
 * roughness, alpha, sides), the same texture (sampler and decoded pixels) and the same UVs; drawn
 * in their bind pose under the same lights, no pixel differs in colour, where three's default
 * material on every primitive (the old output) differs almost everywhere. Cow (7 materials) and
 * Husky (5), multi-material, and the textured Fox, plain and --quantize'd (u16 UVs). The same mesh
 * written twice, from another folder, is the same bytes; a COLOR_0 added to the Fox
 * (tests/tools/add_vertex_colors.py) comes out as three's vertex colours; the Fox as .gltf with its
 * PNG in a file beside it gets the same texture embedded, and without that file `mesh` fails in
 * one line naming it, writing nothing. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <unistd.h>

#define TMP TEST_TMP "/mesh_look"

static char out[1 << 15];

static void link_and_mesh(const char *asset, const char *name, const char *options)
{
    char path[PATH_MAX];
    shared_path(path, sizeof path, asset);
    link_model(path, TMP, name);
    assert_int_equal(run(NULL, 0, "%s mesh " TMP "/%s.glb -o " TMP "/%s.mesh.glb -q %s", crowdbake_exe(), name, name, options), 0);
}

static int setup(void **state)
{
    (void)state;
    assert_int_equal(system("rm -rf " TMP " && mkdir -p " TMP), 0);
    link_and_mesh("assets/quaternius-cow/Cow.glb", "cow", "");
    link_and_mesh("assets/quaternius-husky/Husky.glb", "husky", "");
    link_and_mesh("assets/fox-bevy/Fox.glb", "fox", "");
    link_and_mesh("assets/fox-bevy/Fox.glb", "foxq", "--quantize --max-influences 2");
    char fox[PATH_MAX];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    assert_int_equal(run(NULL, 0, "python3 tests/tools/add_vertex_colors.py %s " TMP "/foxc.glb && %s mesh " TMP "/foxc.glb -o " TMP
                         "/foxc.mesh.glb -q", fox, crowdbake_exe()), 0);
    /* The Fox as .gltf + .bin + a PNG file beside it: the image is read when the mesh is written. */
    char separate[PATH_MAX];
    shared_path(separate, sizeof separate, "assets/derived-fox/separate");
    assert_int_equal(run(NULL, 0, "cp -r %s " TMP "/separate && %s mesh " TMP "/separate/Fox.gltf -o " TMP "/foxs.mesh.glb -q",
                         separate, crowdbake_exe()), 0);
    int rc = run(out, sizeof out, "node tests/runtimes/browser/mesh_look_check.mjs " TMP " cow husky fox foxq foxc "
                 "foxs=separate/Fox.gltf 2>&1");
    if (rc) fail_msg("mesh_look_check.mjs failed (%d): %s", rc, out);
    return 0;
}

static void check_model(const char *name, double primitives, double textured, double uvs)
{
    double n = json_number_in(out, name, "primitives"), same = json_number_in(out, name, "materials_same");
    double covered = json_number_in(out, name, "covered"), share = json_number_in(out, name, "share");
    const char *bare_at = strstr(strstr(out, name), "\"default_material\":");
    assert_non_null(bare_at);
    double bare = json_number_after(bare_at, "share");
    printf("  %s: %.0f of %.0f primitives' materials as three reads the source (%.0f textured, UVs the same in %.0f, %.0f "
           "colours); %.0f covered pixels, %.2f%% differ in colour (three's default material: %.1f%%)\n",
           name, same, n, json_number_in(out, name, "textured"), json_number_in(out, name, "uvs_same"), json_number_in(out, name, "distinct_colours"),
           covered, 100 * share, 100 * bare);
    assert_true(n == primitives && same == primitives);
    assert_true(json_number_in(out, name, "textured") == textured && json_number_in(out, name, "uvs_same") == uvs);
    assert_true(covered > 2000);
    assert_true(share == 0);
    assert_true(bare > 0.5);
}

static void test_multi_material_cow(void **state)
{
    (void)state;
    check_model("cow", 7, 0, 0);
    assert_true(json_number_in(out, "cow", "distinct_colours") == 7);
}

static void test_multi_material_husky(void **state)
{
    (void)state;
    check_model("husky", 5, 0, 0);
    assert_true(json_number_in(out, "husky", "distinct_colours") == 5);
}

static void test_textured_fox(void **state)
{
    (void)state;
    check_model("fox", 1, 1, 1);
    check_model("foxq", 1, 1, 1);
}

static void test_vertex_colours(void **state)
{
    (void)state;
    check_model("foxc", 1, 1, 1);
    assert_non_null(strstr(strstr(out, "\"foxc\":"), "\"vertex_colours\":1"));
}

static void test_an_image_file_beside_the_model(void **state)
{
    (void)state;
    check_model("foxs", 1, 1, 1);
    /* the same pixels as the GLB's embedded texture: the same PNG */
    const char *a = strstr(strstr(out, "\"fox\":"), "\"texture_pixels\":[\""), *b = strstr(strstr(out, "\"foxs\":"), "\"texture_pixels\":[\"");
    assert_true(a && b && strncmp(a, b, 50) == 0);
    printf("  foxs: %.47s, as the GLB's\n", b);
    /* without its image file: a one-line error naming it, and no output */
    static char err[4096];
    assert_int_equal(run(err, sizeof err, "rm " TMP "/separate/baseColor.png && %s mesh " TMP "/separate/Fox.gltf -o " TMP
                         "/missing.glb 2>&1", crowdbake_exe()), EXIT_IO);
    printf("  %s", err);
    assert_non_null(strstr(err, "separate/baseColor.png: cannot read the image a material uses (No such file or directory); "
                                "put it beside the model, where its uri says"));
    assert_false(exists(TMP "/missing.glb"));
}

static void test_the_same_bytes_from_another_folder(void **state)
{
    (void)state;
    char cwd[PATH_MAX];
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(run(NULL, 0, "cd " TMP " && %s/%s mesh fox.glb -o again.glb -q && cmp -s again.glb fox.mesh.glb",
                         crowdbake_exe()[0] == '/' ? "" : cwd, crowdbake_exe()), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_multi_material_cow),
        cmocka_unit_test(test_multi_material_husky),
        cmocka_unit_test(test_textured_fox),
        cmocka_unit_test(test_vertex_colours),
        cmocka_unit_test(test_an_image_file_beside_the_model),
        cmocka_unit_test(test_the_same_bytes_from_another_folder),
    };
    return cmocka_run_group_tests_name("mesh_look", tests, setup, NULL);
}
