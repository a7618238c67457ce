/* test_web.c - the WebGL2 runtime (runtimes/web/crowdbake_crowd.mjs, whose vertex shader is the shipped
 * runtimes/glsl/crowdbake_palette.glsl) in a real browser: headless Chromium, WebGL2 on
 * SwiftShader, driven by tests/runtimes/browser/skin_check.mjs. For every layout x precision, palettes
 * baked by the command are read by runtimes/web/crowdbake_pal.mjs, uploaded by the runtime and drawn as one
 * instanced draw per time; transform feedback reads every instance's skinned vertices back and
 * they must match the C runtime's positions of the conformance cases (conformance.h, the one set
 * every runtime's test reads) within 1e-5 x model height. The broken variants test_gl catches
 * (transposed matrices, rows off by one, no loop wrap, no hemisphere flip) must fail the same
 * comparison here. Timed rows (.pal version 7): every timed case per vertex and through the bone pass within the
 * tolerance, the map ignored (broken-timed-map-ignored) or its read skipped in the shader far off. The fuzzers'
 * hostile palettes are read in the same page (fzstd as
 * the decoder) and every one is refused with a one-line message. CrowdbakeHerd (three.js) is
 * compared with three.js's own skinning of the glTF. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include "runtimes/conformance.h"

#include <dirent.h>

#define TMP TEST_TMP "/web"

/* Largest |browser - C runtime| over a conformance case, in tolerances (conformance.h). */
static double compare(const conformance *c, const char *name, double *units)
{
    const conf_case *k = conformance_case(c, name);
    char path[PATH_MAX];
    snprintf(path, sizeof path, TMP "/%s.out", name);
    return conformance_compare_file(c, k, path, units);
}

/* A local or timed case's run by the browser (`variant`: "" as given, "bones" through the bone pass, "nocompose" or
 * "nomap" broken) against the C runtime's positions, cross-fades included (conf_expected fades local rows before
 * composing), in tolerances. */
static double compare_variant(const conformance *c, const char *name, const char *variant)
{
    const conf_case *k = conformance_case(c, name);
    char path[PATH_MAX];
    double units;
    snprintf(path, sizeof path, TMP "/%s.out%s%s", name, *variant ? "." : "", variant);
    return conformance_compare_file(c, k, path, &units);
}

/* Local rows (.pal version 6): each bone blended in its parent's frame and composed down the skeleton, per vertex
 * and in the bone pass, as the C runtime composes (steady and cross-fading instances alike); with the shader's
 * compose step skipped, far off. */
static void check_local_cases(const conformance *conf, const char *out)
{
    static const char *const names[] = {"local_qpos_u16", "local_qpos_float", "local_blocks"};
    for (int i = 0; i < 3; ++i) {
        double direct = compare_variant(conf, names[i], ""), bones = compare_variant(conf, names[i], "bones");
        double skipped = compare_variant(conf, names[i], "nocompose");
        printf("  %-16s local rows, cross-fades included: browser vs C runtime %.2f (per vertex), %.2f (bone pass) of the "
               "tolerance; compose skipped: %.0f\n", names[i], direct, bones, skipped);
        assert_true(direct <= 1 && bones <= 1 && skipped > 10);
    }
    assert_non_null(strstr(out, "ran  local_qpos_u16 (bone pass): "));
    assert_non_null(strstr(strstr(out, "ran  local_qpos_u16 (bone pass): "), "with the bone pass"));
}

/* Timed rows (.pal version 7): each timed case per vertex and through the bone pass (cross-fades included) within the
 * tolerance of the C runtime's cb_runtime_frame_in; with the shader's map read skipped (the cell taken as a row), and
 * the map ignored in the instance numbers (broken-timed-map-ignored), far off. */
static void check_timed_cases(const conformance *conf, const char *out)
{
    int ran = 0;
    for (int i = 0; i < conf->case_count; ++i) {
        const conf_case *k = &conf->cases[i];
        if (!k->timed || k->broken) continue;
        double direct = compare_variant(conf, k->name, ""), bones = compare_variant(conf, k->name, "bones");
        double skipped = compare_variant(conf, k->name, "nomap");
        printf("  %-17s timed rows, cross-fades included: browser vs C runtime %.2f (per vertex), %.2f (bone pass) of the "
               "tolerance; map read skipped: %.0f\n", k->name, direct, bones, skipped);
        assert_true(direct <= 1 && bones <= 1 && skipped > 10);
        ++ran;
    }
    assert_true(ran >= 7);
    double units, ignored = compare(conf, "broken-timed-map-ignored", &units);
    printf("  broken-timed-map-ignored: %.0f tolerances off\n", ignored);
    assert_true(ignored > 10);
    assert_non_null(strstr(out, "ran  timed_qpos_u16 (bone pass): "));
    assert_non_null(strstr(strstr(out, "ran  timed_qpos_u16 (bone pass): "), "with the bone pass"));
}

static void test_runtime_in_chromium_matches_the_cpu(void **state)
{
    (void)state;
    FILE *installed = fopen("tests/runtimes/browser/node_modules/.package-lock.json", "r");
    if (!installed) fail_msg("tests/runtimes/browser: npm packages not installed (make test installs them; or: cd tests/runtimes/browser && npm ci)");
    fclose(installed);
    conformance conf;
    conformance_make(&conf, TMP);
    static char out[1 << 16];
    int rc = run_command("node tests/runtimes/browser/skin_check.mjs " TMP " 2>&1", out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    /* Every hostile palette of tests/fuzz/regressions/pal refused in the page with a message, as the C reader refuses it;
     * a valid one kept there as the fuzzer's seed (timed-held.pal) opened, as the C reader opens it. */
    int hostile = 0, refused = 0;
    DIR *dir = opendir("tests/fuzz/regressions/pal");
    assert_non_null(dir);
    for (struct dirent *e; (e = readdir(dir));) {
        if (e->d_name[0] == '.') continue;
        char path[PATH_MAX], err[256], line[PATH_MAX + 16];
        snprintf(path, sizeof path, "tests/fuzz/regressions/pal/%s", e->d_name);
        cbpal_file f;
        bool opens = cbpal_open(path, CBPAL_VERIFY_CHECKSUM, &f, err, sizeof err) == 0;
        if (opens) cbpal_close(&f);
        else ++hostile;
        snprintf(line, sizeof line, opens ? "\nACCEPTED %s\n" : "\nrefused %s: ", e->d_name);
        if (!strstr(out, line)) fail_msg("%s: the page did not judge it as the C reader does (%s)", e->d_name, opens ? "opens" : err);
    }
    closedir(dir);
    for (const char *p = out; (p = strstr(p, "\nrefused ")); ++p) ++refused;
    assert_true(hostile >= 8);
    assert_int_equal(refused, 2 * hostile); /* with and without the checksum check */
    assert_null(strstr(out, "BAD ERROR"));
    double units;
    for (int i = 0; i < 9; ++i) {
        const conf_case *k = &conf.cases[i];
        double ratio = compare(&conf, k->name, &units);
        printf("  %-12s %zu positions: browser vs C runtime %.2g (%.2f of the tolerance)\n", k->name,
               conf_positions(&conf, k), units, ratio);
        assert_true(ratio <= 1);
    }
    double spin_ok = compare(&conf, "spin", &units), wrapped_ok = compare(&conf, "wrapped", &units);
    printf("  qpos/half in 2 column blocks: browser vs C runtime %.2g (%.2f of the tolerance)\n", units, wrapped_ok);
    assert_true(wrapped_ok <= 1);
    double transposed = compare(&conf, "broken-transposed", &units);
    double off_by_one = compare(&conf, "broken-row-off-by-one", &units);
    double no_wrap = compare(&conf, "broken-no-wrap", &units);
    double no_flip = compare(&conf, "broken-no-hemisphere-flip", &units);
    printf("  error / tolerance: transposed %.0f, rows off by one %.0f, no wrap %.0f, no hemisphere flip %.0f "
           "(the same spin palette, shipped shader: %.2f)\n", transposed, off_by_one, no_wrap, no_flip, spin_ok);
    assert_true(spin_ok <= 1);
    assert_true(transposed > 10 && off_by_one > 10 && no_wrap > 10 && no_flip > 10);
    /* A STEP-keyed clip's held rows (.pal version 4): the row alone; blended across its steps, far off. */
    double held = compare(&conf, "held", &units), no_held = compare(&conf, "broken-no-held", &units);
    printf("  held rows (STEP SimpleSkin): browser vs C runtime %.2f of the tolerance; blended: %.0f\n", held, no_held);
    assert_true(held <= 1 && no_held > 10);
    double bones_qpos = compare(&conf, "bones-qpos-u16", &units), bones_mat4 = compare(&conf, "bones-mat4-half", &units);
    double bones_broken = compare(&conf, "broken-bones-transposed", &units);
    printf("  bone pass: browser vs C runtime %.2f (qpos/u16), %.2f (mat4/half, 16 instances a column block) of the "
           "tolerance; its columns read as rows: %.0f\n", bones_qpos, bones_mat4, bones_broken);
    assert_true(strstr(out, "ran  bones-qpos-u16: ") && strstr(out, "with the bone pass"));
    assert_true(bones_qpos <= 1 && bones_mat4 <= 1 && bones_broken > 10);
    check_local_cases(&conf, out);
    check_timed_cases(&conf, out);
    conformance_free(&conf);
}

/* The share of covered pixels where two silhouettes disagree, at the `index`th time of the
 * three.js check's output, for "herd" or "broken". */
static double disagreement(const char *out, int index, const char *which)
{
    const char *at = strstr(out, "\"results\":[");
    assert_non_null(at);
    for (int i = 0; i <= index; ++i) assert_non_null(at = strstr(at + 1, "{\"time\":"));
    char key[32];
    snprintf(key, sizeof key, "\"%s\":{", which);
    assert_non_null(at = strstr(at, key));
    assert_non_null(at = strstr(at, "\"share\":"));
    return atof(at + 8);
}

/* CrowdbakeHerd (three.js InstancedMesh, the shipped GLSL patched in) against three.js's own
 * SkinnedMesh + AnimationMixer playing the glTF: the Fox walking, silhouettes from one camera; and the
 * WebGL2 Crowd the same way: per vertex, bone pass, the herd-size choice and the animation LOD; and the
 * herd's own bone pass and herd-size choice. */
static void test_three_herd_matches_three_skinning(void **state)
{
    (void)state;
    char fox[PATH_MAX], cmd[2 * PATH_MAX + 64];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    assert_int_equal(system("rm -rf " TMP "/three && mkdir -p " TMP "/three"), 0);
    snprintf(cmd, sizeof cmd, "ln -s \"$(realpath %s)\" " TMP "/three/model.glb", fox);
    assert_int_equal(system(cmd), 0);
    /* Root motion kept: three plays the clip with its travel. */
    snprintf(cmd, sizeof cmd, "%s bake %s -o " TMP "/three/model.pal -q", crowdbake_exe(), fox);
    assert_int_equal(system(cmd), 0);
    static char out[1 << 16];
    int rc = run_command("node tests/runtimes/browser/three_check.mjs " TMP "/three Walk 0.1,0.37,0.6 2>&1", out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    for (int i = 0; i < 3; ++i) {
        double herd = disagreement(out, i, "herd"), broken = disagreement(out, i, "broken");
        printf("  time %d: herd vs three.js skinning %.2f%% of the covered pixels; unpatched herd %.0f%%\n", i, 100 * herd,
               100 * broken);
        assert_true(herd < 0.03);
        assert_true(broken > 0.2);
        /* The WebGL2 Crowd, each way it can skin, within the herd's tolerance of three.js. */
        static const char *crowds[] = {"crowd_palette", "crowd_bones", "crowd_auto_small", "crowd_auto_big",
                                       "crowd_lod_forced", "crowd_lod_one_forced", "crowd_lod_default", "herd_bones",
                                       "herd_auto_big", "herd_lod_one"};
        for (int k = 0; k < 10; ++k) {
            double share = disagreement(out, i, crowds[k]);
            printf("  time %d: %s vs three.js skinning %.2f%%\n", i, crowds[k], 100 * share);
            assert_true(share < 0.03);
        }
    }
    /* bonePass 'auto' picks by herd size: one Fox is under the threshold, over it with bonePassVertices 1. */
    assert_non_null(strstr(out, "\"auto_small\":{\"method\":\"palette\""));
    assert_non_null(strstr(out, "\"auto_big\":{\"method\":\"bones\""));
    assert_non_null(strstr(out, "\"herd\":{\"method\":\"palette\""));
    assert_non_null(strstr(out, "\"herd_auto_big\":{\"method\":\"bones\""));
    assert_non_null(strstr(out, "\"herd_bones\":{\"method\":\"bones\""));
    /* The LOD at its default leaves an instance this large on screen alone: the bone pass's pixels exactly. */
    const char *at = out;
    for (int i = 0; i < 3; ++i) {
        assert_non_null(at = strstr(at, "\"crowd_lod_default\":{"));
        assert_non_null(at = strstr(at, "\"vs_bones\":"));
        assert_int_equal(atoi(at + 11), 0);
    }
    /* The LOD's tiers drawn apart (the Crowd's lodTiers; the herd's update given the camera) draw the same image as one
     * draw finding each vertex's tier, and the check can fail: that image differs from every Fox on every influence and
     * from every Fox on the far tier. */
    static const char *const drawn_apart[] = {"\"tiers\":{\"counts\":[3,3,3],\"draws\":3,", "\"herd_tiers\":{\"counts\":[3,3,3],"};
    for (int k = 0; k < 2; ++k) {
        at = out;
        for (int i = 0; i < 3; ++i) {
            assert_non_null(at = strstr(at, drawn_apart[k]));
            const char *same = strstr(at, "\"bytes_differ\":"), *every = strstr(at, "\"vs_every_influence\":"),
                       *far = strstr(at, "\"vs_all_far\":");
            assert_non_null(same);
            assert_non_null(every);
            assert_non_null(far);
            int bytes = atoi(same + 15), off_every = atoi(every + 21), off_far = atoi(far + 13);
            printf("  time %d: %s the LOD's tiers drawn apart vs one draw: %d bytes differ (vs every influence %d, vs the "
                   "far tier %d)\n", i, k ? "herd" : "Crowd", bytes, off_every, off_far);
            assert_int_equal(bytes, 0);
            assert_true(off_every > 0 && off_far > 0);
            if (k == 1) /* the herd out of the render lists still answers a ray: the middle Fox, once, as in one draw */
                assert_non_null(strstr(at, "\"raycast\":[\"true:4\",\"true:4\"]"));
            ++at;
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_runtime_in_chromium_matches_the_cpu),
        cmocka_unit_test(test_three_herd_matches_three_skinning),
    };
    return cmocka_run_group_tests_name("web", tests, NULL, NULL);
}
