/* test_web_local.c - local rows (.pal version 6, `--bone-space local`) in the web runtimes, in headless Chromium
 * (SwiftShader), driven by tests/runtimes/browser/local_check.mjs: Cow and Husky, each baked twice at the default
 * rates (qpos/u16, global and local), ten instances each (two cross-fading) at two times.
 * - The WebGL2 Crowd's skinned vertices of the local palette, per vertex and through the bone pass, against the CPU
 *   skinning with the reader's own composed bone matrices (crowdbake_pal.mjs): within the harness's own floor (the
 *   global palette against its CPU skinning, the same comparison), cross-fades included; against the global bake:
 *   within 1 mm/m of the model's height where no instance cross-fades (each bake is within its error budget).
 * - Two broken runtimes miss by far: the local rows drawn as global rows, and the shader's compose step skipped.
 * - Images: the Crowd (per vertex, bone pass, the LOD's tiers drawn apart) and CrowdbakeHerd (three.js: per vertex,
 *   bone pass, tiers drawn apart) drawing the local palette against the same drawing of the global one: the share of
 *   covered pixels that differ; the local rows drawn as global: most of them.
 * - Sockets: CrowdbakeHerd.boneMatrixAt places every joint of the local palette within 1 mm/m of the global one's.
 * - `crowdbake view` of a catalog of Cow and Husky with bone_space = "local" (browser/view_check.mjs, 1,000 animals):
 *   it serves version 6 palettes, and the palette half covers the VAT half's pixels (exact skinning of the same
 *   frames) as closely as the global catalog's does. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>

#define TMP TEST_TMP "/web_local"

static char out[1 << 16];

static void link_and_bake(const char *asset, const char *name)
{
    char path[PATH_MAX];
    shared_path(path, sizeof path, asset);
    link_model(path, TMP, name);
    assert_int_equal(run(NULL, 0, "%s bake " TMP "/%s.glb -o " TMP "/%s.pal -q --layout qpos --precision u16", crowdbake_exe(),
                         name, name), 0);
    assert_int_equal(run(NULL, 0, "%s bake " TMP "/%s.glb -o " TMP "/%s-local.pal -q --layout qpos --precision u16 "
                         "--bone-space local", crowdbake_exe(), name, name), 0);
}

static int setup(void **state)
{
    (void)state;
    assert_int_equal(system("rm -rf " TMP " && mkdir -p " TMP), 0);
    link_and_bake("assets/quaternius-cow/Cow.glb", "cow");
    link_and_bake("assets/quaternius-husky/Husky.glb", "husky");
    int rc = run_command("node tests/runtimes/browser/local_check.mjs " TMP " 'cow:AnimalArmature|Walk:AnimalArmature|Idle' "
                         "'husky:AnimalArmature|Gallop:AnimalArmature|Walk' 2>&1", out, sizeof out);
    if (rc) fail_msg("local_check.mjs failed (%d): %.4000s", rc, out);
    return 0;
}

/* The number after `key` inside the object named `section` after `at`. */
static double number_in(const char *at, const char *section, const char *key)
{
    char pattern[64];
    snprintf(pattern, sizeof pattern, "\"%s\":", section);
    const char *s = strstr(at, pattern);
    if (!s) fail_msg("no \"%s\" after %.200s", section, at);
    return json_number_after(s, key);
}

/* One time's result of one model: capture, image and herd. */
static void check_time(const char *name, const char *at)
{
    const char *capture = strstr(at, "\"capture\":"), *image = strstr(at, "\"image\":"), *herd = strstr(at, "\"herd\":");
    assert_true(capture && image && herd);
    double floor_steady = number_in(capture, "global_vs_its_cpu", "steady"), floor_fading = number_in(capture, "global_vs_its_cpu", "fading");
    static const char *const paths[] = {"direct", "bones"};
    for (int i = 0; i < 2; ++i) {
        const char *p = strstr(capture, paths[i]);
        double steady = number_in(p, "vs_cpu", "steady"), fading = number_in(p, "vs_cpu", "fading");
        double global = number_in(p, "vs_global", "steady");
        printf("  %s t=%.1f %-6s: vs the reader's CPU composition %.2g (steady) %.2g (cross-fading) model heights "
               "(the global palette vs its CPU skinning: %.2g, %.2g); vs the global bake %.2g\n", name, json_number_after(at, "time"),
               paths[i], steady, fading, floor_steady, floor_fading, global);
        assert_true(steady <= 1.5 * floor_steady + 1e-6 && fading <= 1.5 * floor_fading + 1e-6);
        assert_true(global <= 1e-3);
    }
    double no_local = number_in(capture, "no_local", "steady"), no_compose = number_in(capture, "no_compose", "steady");
    printf("  %s broken: local rows drawn as global %.2f, compose skipped %.2f model heights off\n", name, no_local, no_compose);
    assert_true(no_local > 0.05 && no_compose > 0.05);
    static const char *const drawn[] = {"direct", "bones", "tiers"};
    for (int i = 0; i < 3; ++i) {
        double share = number_in(image, drawn[i], "share");
        printf("  %s Crowd %-6s: %.3f%% of %.0f covered pixels differ from the global bake's image\n", name, drawn[i], 100 * share,
               number_in(image, drawn[i], "covered"));
        assert_true(share <= 0.005 && number_in(image, drawn[i], "covered") > 2000);
    }
    double wrong = number_in(image, "no_local", "share");
    double herd_direct = number_in(herd, "direct", "share"), herd_bones = number_in(herd, "bones", "share");
    double herd_tiers = number_in(herd, "tiers", "share");
    double joints = json_number_after(herd, "joints_vs_global");
    printf("  %s local rows drawn as global: %.0f%%; CrowdbakeHerd %.3f%% (per vertex) %.3f%% (bone pass) %.3f%% (tiers); "
           "joints (boneMatrixAt) %.2g model heights from the global bake's\n", name, 100 * wrong, 100 * herd_direct,
           100 * herd_bones, 100 * herd_tiers, joints);
    assert_true(wrong > 0.3 && herd_direct <= 0.005 && herd_bones <= 0.005 && herd_tiers <= 0.005 && joints <= 1e-3);
}

static void check_model(const char *name)
{
    char pattern[32];
    snprintf(pattern, sizeof pattern, "\"%s\":{", name);
    const char *at = strstr(out, pattern);
    assert_non_null(at);
    assert_non_null(strstr(at, "\"local_rows\":[true,true]"));
    for (int t = 0; t < 2; ++t) {
        assert_non_null(at = strstr(at + 1, "{\"time\":"));
        check_time(name, at);
    }
}

/* Header bytes 8 (version) and 12 (flags) of a .pal. */
static void pal_version_flags(const char *path, uint32_t *version, uint32_t *flags)
{
    unsigned char h[16] = {0};
    FILE *f = fopen(path, "rb");
    if (!f) fail_msg("%s: not written", path);
    assert_int_equal(fread(h, 1, sizeof h, f), sizeof h);
    fclose(f);
    *version = h[8] | h[9] << 8 | (uint32_t)h[10] << 16 | (uint32_t)h[11] << 24;
    *flags = h[12] | h[13] << 8 | (uint32_t)h[14] << 16 | (uint32_t)h[15] << 24;
}

/* `crowdbake view` of Cow and Husky with bone_space `space`: the palette half's pixels against the VAT half's. */
static double view_mismatch(const char *space)
{
    char cow[PATH_MAX], husky[PATH_MAX], dir[PATH_MAX];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    shared_path(husky, sizeof husky, "assets/quaternius-husky/Husky.glb");
    snprintf(dir, sizeof dir, TMP "/view-%s", space);
    assert_int_equal(run(NULL, 0, "mkdir -p %s && cat > %s/herd.toml <<EOF\n[bake]\nbone_space = \"%s\"\nroot_motion = \"in-place\"\n"
                         "[animal.cow]\nmodel = \"$(realpath %s)\"\nstates = { idle = [\"AnimalArmature|Idle\"], walk = "
                         "[\"AnimalArmature|Walk\"], gallop = [\"AnimalArmature|Gallop\"] }\n[animal.husky]\nmodel = \"$(realpath %s)\"\n"
                         "states = { idle = [\"AnimalArmature|Idle\"], walk = [\"AnimalArmature|Walk\"] }\nEOF", dir, dir, space, cow, husky), 0);
    static char view[1 << 17];
    int rc = run(view, sizeof view, "node tests/runtimes/browser/view_check.mjs %s %s/herd.toml %s/cache %s/view.png 1000 "
                 "2>&1", crowdbake_exe(), dir, dir, dir);
    if (rc) fail_msg("view_check.mjs failed (%d): %.2000s", rc, view);
    assert_non_null(strstr(view, "\"console_errors\":[]"));
    assert_non_null(strstr(view, "\"exit\":{\"code\":0"));
    char pal[PATH_MAX + 64];
    uint32_t version, flags;
    snprintf(pal, sizeof pal, "%s/cache/site/data/cow.pal", dir);
    pal_version_flags(pal, &version, &flags);
    assert_true(strcmp(space, "local") ? !(flags & 32) : version == 6 && (flags & 32));
    return json_number_after(view, "palette_vs_vat_mismatch");
}

static void test_view_draws_a_local_catalog(void **state)
{
    (void)state;
    double local = view_mismatch("local"), global = view_mismatch("global");
    printf("  crowdbake view, 1,000 Cows: the palette half and the VAT half differ on %.3f%% of the covered pixels "
           "(bone_space local), %.3f%% (global)\n", 100 * local, 100 * global);
    assert_true(local <= 0.01 && local <= global + 0.001);
}

static void test_cow(void **state)
{
    (void)state;
    check_model("cow");
}

static void test_husky(void **state)
{
    (void)state;
    check_model("husky");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cow),
        cmocka_unit_test(test_husky),
        cmocka_unit_test(test_view_draws_a_local_catalog),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
