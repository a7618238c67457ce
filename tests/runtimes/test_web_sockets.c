/* test_web_sockets.c - sockets in headless Chromium (tests/runtimes/browser/socket_check.mjs): Cow eating
 * in a CrowdbakeHerd beside three.js's own SkinnedMesh + AnimationMixer of the glTF. Every socket
 * of `crowdbake info` placed by herd.socketMatrixAt sits where three.js's node hierarchy puts that
 * node; the head bone's rigid triangles placed by boneMatrixAt cover exactly the pixels the herd's
 * shader skins them to, at a row and half-way between rows (the GLSL's blend), and placed at a
 * wrong time they do not. The sockets' axes are unit long (a prop keeps its own scale) on Cow, whose
 * armature carries scale 100, and on the same Cow with every node at scale 1. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

#define TMP TEST_TMP "/web_sockets"

/* Bakes `model` (linked as model.glb in a fresh TMP) and runs the check: one line per time. */
static void check_model(const char *model, bool scaled)
{
    char cmd[4096], log[4096];
    /* Root motion kept and 30 fps: three.js plays the glTF's own keys. */
    snprintf(cmd, sizeof cmd,
             "rm -rf %s && mkdir -p %s && ln -s \"$(realpath %s)\" %s/model.glb && %s bake %s -o %s/model.pal -q --fps 30 "
             "--max-error 1000 && %s info %s --json > %s/info.json 2>&1",
             TMP, TMP, model, TMP, crowdbake_exe(), model, TMP, crowdbake_exe(), model, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    static char out[1 << 16];
    int rc = run_command("node tests/runtimes/browser/socket_check.mjs " TMP " 'AnimalArmature|Eating' 1.0,2.55,4.05 | python3 -c \""
                         "import json, sys\n"
                         "d = json.load(sys.stdin)\n"
                         "for r in d['results']: print(r['time'], r['covered'], r['differ'], r['differ_wrong_time'], "
                         "len(r['sockets']), max(s['position'] for s in r['sockets']) / d['height'], "
                         "max(s['axes'] for s in r['sockets']), max(s['scale'] for s in r['sockets']), "
                         "min(s['node_scale'] for s in r['sockets']))\" 2>&1",
                         out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    const char *p = out;
    for (int i = 0; i < 3; ++i) {
        double t, differ, wrong, position, axes, scale, node_scale;
        int covered, sockets, used;
        assert_int_equal(sscanf(p, "%lf %d %lf %lf %d %lf %lf %lf %lf%n", &t, &covered, &differ, &wrong, &sockets, &position,
                                &axes, &scale, &node_scale, &used),
                         9);
        p += used;
        printf("  %s, %.2f s: %d sockets within %.3g of the height (axes %.2g) of three.js's nodes; their axes' lengths "
               "within %.2g of 1 (three.js's nodes: %.4g); head triangles (%d px) differ on %.1f%% of the pixels, at a "
               "wrong time %.0f%%\n",
               scaled ? "Cow (armature at scale 100)" : "Cow at unit scale", t, sockets, position, axes, scale, node_scale,
               covered, 100 * differ, 100 * wrong);
        assert_int_equal(sockets, 10); /* not the 4 IK pole targets (rig helpers) */
        /* At a row (1.0 s) the u16 encoding's error alone; half-way between rows (2.55 s, 4.05 s: the shader's blend
         * of two, which the pixels compare) also the blend's, within the default budget of 1 mm/m. */
        bool at_row = fabs(t * 30 - round(t * 30)) < 1e-6;
        assert_true(position < (at_row ? 2e-4 : 1e-3));
        assert_true(axes < (at_row ? 1e-3 : 5e-3));
        /* A prop keeps its own size: unit axes, where three.js's node is 100 units long on the scaled model (what a
         * prop hung on the node's own frame would be scaled by). */
        assert_true(scale < (at_row ? 1e-3 : 5e-3));
        assert_true(scaled ? node_scale > 99 : fabs(node_scale - 1) < 1e-3);
        assert_true(covered > 100);
        assert_true(differ < 0.02);
        assert_true(wrong > 0.15);
    }
}

static void test_props_follow_their_bones_in_chromium(void **state)
{
    (void)state;
    char cow[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    check_model(cow, true);
}

/* The same Cow with every node at scale 1 (tests/tools/unscale_armature.py): sockets on a model whose nodes carry no
 * scale, where the scale correction must change nothing. */
static void test_props_on_an_unscaled_model(void **state)
{
    (void)state;
    char cow[1024], cmd[4096], log[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "mkdir -p %s_src && python3 tests/tools/unscale_armature.py %s %s_src/cow_unit.glb", TMP, cow, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    check_model(TMP "_src/cow_unit.glb", false);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_props_follow_their_bones_in_chromium),
        cmocka_unit_test(test_props_on_an_unscaled_model),
    };
    return cmocka_run_group_tests_name("web_sockets", tests, NULL, NULL);
}
