/* test_web_sample.c - the copyable three.js page (samples/web/index.html and herd.mjs) loaded as it
 * is from the repository tree in headless Chromium (tests/runtimes/browser/sample_check.mjs), on a roster
 * of Cow baked here: it draws a herd of 500 (pixels that change when the herd is hidden), its
 * footstep callback fires, the prop on Cow's Head_end socket keeps its own size (Cow's armature is
 * at scale 100), and the page logs no console error. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <math.h>

#define TMP TEST_TMP "/web_sample"

static double number(const char *out, const char *key)
{
    char pattern[64];
    snprintf(pattern, sizeof pattern, "\"%s\":", key);
    const char *at = strstr(out, pattern);
    if (!at) fail_msg("no \"%s\" in the check's output: %s", key, out);
    return atof(at + strlen(pattern));
}

static void test_the_sample_page_draws_a_herd(void **state)
{
    (void)state;
    char cow[PATH_MAX], cmd[4 * PATH_MAX], log[4096];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    /* A copy, not a link: the roster names its model relative to itself, and the page fetches it from the
     * served folder. */
    snprintf(cmd, sizeof cmd,
             "rm -rf " TMP " && mkdir -p " TMP " && cp %s " TMP "/cow.glb && printf '%%s\\n' '[bake]' 'out_dir = \".\"' "
             "'root_motion = \"in-place\"' '[animal.cow]' 'model = \"cow.glb\"' "
             "'clips = [\"AnimalArmature|Walk\", \"AnimalArmature|Idle\"]' "
             "'states = { wander = [\"walk\"], idle = [\"idle\"] }' 'default_state = \"wander\"' > " TMP "/catalog.toml && "
             "%s bake " TMP "/catalog.toml -q 2>&1",
             cow, crowdbake_exe());
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    static char out[1 << 14];
    int rc = run_command("node tests/runtimes/browser/sample_check.mjs " TMP " cow 2>&1", out, sizeof out);
    if (rc) fail_msg("sample_check.mjs failed (%d): %s", rc, out);
    double herd = number(out, "herd_pixels"), pixels = number(out, "pixels"), steps = number(out, "footsteps");
    double frames = number(out, "frames"), instances = number(out, "instances"), prop = number(out, "prop_scale");
    printf("  %.0f cows: %.0f of %.0f pixels are the herd's (and its shadows); %.0f footsteps in %.0f frames; the prop on "
           "Head_end drawn at %.6f of its own size; no console errors\n", instances, herd, pixels, steps, frames, prop);
    assert_true(strstr(out, "\"errors\":[]") != NULL);
    assert_true(instances == 500);
    assert_true(herd > 0.02 * pixels);
    assert_true(steps > 0);
    assert_true(fabs(prop - 1) < 1e-3);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_sample_page_draws_a_herd),
    };
    return cmocka_run_group_tests_name("web_sample", tests, NULL, NULL);
}
