/* test_web_sockets.c - sockets in headless Chromium (tests/runtimes/browser/socket_check.mjs): Cow eating
 * in a CrowdbakeHerd beside three.js's own SkinnedMesh + AnimationMixer of the glTF. Every socket
 * of `crowdbake info` placed by herd.socketMatrixAt sits where three.js's node hierarchy puts that
 * node; the head bone's rigid triangles placed by boneMatrixAt cover exactly the pixels the herd's
 * shader skins them to, at a row and half-way between rows (the GLSL's blend), and placed at a
 * wrong time they do not. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

#define TMP TEST_TMP "/web_sockets"

static void test_props_follow_their_bones_in_chromium(void **state)
{
    (void)state;
    char cow[1024], cmd[4096], log[4096];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    /* Root motion kept and 30 fps: three.js plays the glTF's own keys. */
    snprintf(cmd, sizeof cmd,
             "rm -rf %s && mkdir -p %s && ln -s \"$(realpath %s)\" %s/model.glb && %s bake %s -o %s/model.pal -q --fps 30 "
             "--max-error 1000 && %s info %s --json > %s/info.json 2>&1",
             TMP, TMP, cow, TMP, crowdbake_exe(), cow, TMP, crowdbake_exe(), cow, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    static char out[1 << 16];
    int rc = run_command("node tests/runtimes/browser/socket_check.mjs " TMP " 'AnimalArmature|Eating' 1.0,2.55,4.05 | python3 -c \""
                         "import json, sys\n"
                         "d = json.load(sys.stdin)\n"
                         "for r in d['results']: print(r['time'], r['covered'], r['differ'], r['differ_wrong_time'], "
                         "len(r['sockets']), max(s['position'] for s in r['sockets']) / d['height'], "
                         "max(s['axes'] for s in r['sockets']))\" 2>&1",
                         out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    const char *p = out;
    for (int i = 0; i < 3; ++i) {
        double t, differ, wrong, position, axes;
        int covered, sockets, used;
        assert_int_equal(sscanf(p, "%lf %d %lf %lf %d %lf %lf%n", &t, &covered, &differ, &wrong, &sockets, &position, &axes, &used),
                         7);
        p += used;
        printf("  %.2f s: %d sockets within %.3g of the height (axes %.2g) of three.js's nodes; head triangles (%d px) "
               "differ on %.1f%% of the pixels, at a wrong time %.0f%%\n",
               t, sockets, position, axes, covered, 100 * differ, 100 * wrong);
        assert_int_equal(sockets, 10); /* not the 4 IK pole targets (rig helpers) */
        /* At a row (1.0 s) the u16 encoding's error alone; half-way between rows (2.55 s, 4.05 s: the shader's blend
         * of two, which the pixels compare) also the blend's, within the default budget of 1 mm/m. */
        bool at_row = fabs(t * 30 - round(t * 30)) < 1e-6;
        assert_true(position < (at_row ? 2e-4 : 1e-3));
        assert_true(axes < (at_row ? 1e-3 : 5e-3));
        assert_true(covered > 100);
        assert_true(differ < 0.02);
        assert_true(wrong > 0.15);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_props_follow_their_bones_in_chromium),
    };
    return cmocka_run_group_tests_name("web_sockets", tests, NULL, NULL);
}
