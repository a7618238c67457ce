/* test_root_motion.c - root motion decided like the rest (issue 45): a bare bake of a loop that
 * travels (the fish sample swims 0.6 units a loop) succeeds, the loop baked in place with its
 * velocity recorded and a note saying why; --root-motion keep still keeps the travel (and then
 * the wrap's pull-back is over the budget, as before); one-shots keep their travel where a loop
 * goes in place (Cow's Death beside its Jump_toIdle made a loop); info says the same per clip. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>

#include "crowdbake_pal.h"

#define TMP TEST_TMP "/root_motion"

static void open_pal(const char *path, cbpal_file *pal)
{
    char err[256];
    if (cbpal_open(path, 0, pal, err, sizeof err)) fail_msg("%s", err);
}

static void test_travelling_loop_bakes_in_place(void **state)
{
    (void)state;
    char fish[1024], cmd[4096], log[8192];
    sample_path(fish, sizeof fish, "fish");
    snprintf(cmd, sizeof cmd, "mkdir -p %s && %s bake %s -o %s/fish.pal 2>&1", TMP, crowdbake_exe(), fish, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    assert_non_null(strstr(log, "loops and travels 0.6 units/s"));
    assert_non_null(strstr(log, "--root-motion keep"));
    cbpal_file pal;
    open_pal(TMP "/fish.pal", &pal);
    assert_true(pal.header.flags & CBPAL_FLAG_IN_PLACE);
    cbpal_clip clip;
    cbpal_get_clip(&pal, 0, &clip);
    double v = hypot(clip.root_velocity[0], clip.root_velocity[2]);
    printf("  fish swim: baked in place, velocity %.4g units/s recorded\n", v);
    assert_true(fabs(v - 0.6) < 1e-3);
    cbpal_close(&pal);
    /* Overridden: the travel kept, its wrap over a budget the user states, nothing written (exit 6;
     * over the default budget, a goal, it would be written with a warning). */
    snprintf(cmd, sizeof cmd, "%s bake %s -o %s/kept.pal --root-motion keep --max-error 1 2>&1", crowdbake_exe(), fish, TMP);
    assert_int_equal(run_command(cmd, log, sizeof log), 6);
    snprintf(cmd, sizeof cmd, "%s info %s", crowdbake_exe(), fish);
    assert_int_equal(run_command(cmd, log, sizeof log), 0);
    assert_non_null(strstr(log, "root motion in place: it loops and travels 0.6 units a loop"));
}

static void test_one_shots_keep_their_travel(void **state)
{
    (void)state;
    char cow[1024], cmd[4096], log[8192];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && %s bake %s -o %s/cow.pal --fps 30 --clip 'AnimalArmature|Death,AnimalArmature|Jump_toIdle' "
             "--loop 'AnimalArmature|Jump_toIdle' 2>&1",
             TMP, crowdbake_exe(), cow, TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    assert_non_null(strstr(log, "clip 'AnimalArmature|Jump_toIdle' loops and travels"));
    cbpal_file pal;
    open_pal(TMP "/cow.pal", &pal);
    cbpal_clip death, jump;
    cbpal_get_clip(&pal, 0, &death);
    cbpal_get_clip(&pal, 1, &jump);
    assert_string_equal(death.name, "AnimalArmature|Death");
    printf("  Cow Death (one-shot) velocity %.4g, Jump_toIdle (made a loop) %.4g units/s\n",
           hypot(death.root_velocity[0], death.root_velocity[2]), hypot(jump.root_velocity[0], jump.root_velocity[2]));
    assert_true(death.root_velocity[0] == 0 && death.root_velocity[2] == 0); /* its travel stays in its rows */
    assert_true(hypot(jump.root_velocity[0], jump.root_velocity[2]) > 0.1);
    cbpal_close(&pal);
    snprintf(cmd, sizeof cmd, "%s info %s", crowdbake_exe(), cow);
    assert_int_equal(run_command(cmd, log, sizeof log), 0);
    assert_non_null(strstr(log, "root motion kept: a one-shot keeps its travel"));
}

/* The roster manifest says per clip what the bake did with its root travel and why, each clip's
 * visible error, and why its rate and rows (error-bounded, or the catalog's fixed fps); its rates print as the files record them (the shortest decimal that
 * reads back as the .pal's float32, not "24.0000006"). A second run, up to date, writes the
 * same manifest: what it says comes from the type's record, not from a bake. */
static void test_manifest_says_root_motion_per_clip(void **state)
{
    (void)state;
    char cow[1024], cow_abs[4096], text[8192], cmd[8192];
    static char log[16384];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    assert_non_null(realpath(cow, cow_abs));
    snprintf(text, sizeof text,
             "[bake]\nout_dir = \"out\"\n[animal.cow]\nmodel = \"%s\"\nclips = [\"AnimalArmature|Death\", "
             "{ source = \"AnimalArmature|Jump_toIdle\", loop = true, fps = 30 }, \"AnimalArmature|Walk\"]\n", cow_abs);
    assert_int_equal(system("rm -rf " TMP "/out && mkdir -p " TMP), 0);
    write_text(TMP "/cows.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/cows.toml 2>&1 && cp " TMP "/out/roster.json " TMP "/first.json && %s bake "
             TMP "/cows.toml 2>&1 && cmp " TMP "/first.json " TMP "/out/roster.json", crowdbake_exe(), crowdbake_exe());
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s", log);
    snprintf(cmd, sizeof cmd,
             "python3 -c \"import json; t = json.load(open('%s/out/roster.json'))['types']['cow']; "
             "[print(c['name'], c['root_motion'], c['visible_error_mm_per_m'] > 0, '|', c['root_motion_reason'], '|', "
             "c['loop_reason'][:10], '|', c['rate_reason']) for c in t['clips']]\"", TMP);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s", log);
    printf("%s", log);
    assert_non_null(strstr(log, "AnimalArmature|Death keep True | a one-shot keeps its travel"));
    assert_non_null(strstr(log, "AnimalArmature|Jump_toIdle in-place True | a loop travelling"));
    assert_non_null(strstr(log, "its velocity"));
    assert_non_null(strstr(log, "AnimalArmature|Walk in-place True | in place with the type's loops that travel"));
    assert_non_null(strstr(log, "| loops, set"));      /* Jump_toIdle: the catalog's loop */
    assert_non_null(strstr(log, "| plays once"));       /* Death: decided */
    /* Each clip's rate with its reason, as the bake says it; from the record the second time (the same file). */
    assert_non_null(strstr(log, "| 24 fps, local rows (its keys): the fewest within its budget (")); /* Death, Walk */
    assert_non_null(strstr(log, "| 30 fps, sampled rows: a fixed fps; baked as local rows, sampled")); /* Jump_toIdle */
    /* Each rate: the shortest decimal that reads back as the .pal's float32. */
    char *json = read_whole_file(TMP "/out/roster.json", NULL);
    cbpal_file pal;
    open_pal(TMP "/out/cow.pal", &pal);
    const char *p = json;
    for (uint32_t c = 0; c < pal.header.clip_count; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(&pal, c, &clip);
        p = strstr(p, "\"fps\": ");
        assert_non_null(p);
        p += 7;
        char number[32];
        size_t n = strcspn(p, ",\n}");
        assert_true(n < sizeof number);
        memcpy(number, p, n), number[n] = '\0';
        printf("  %s: fps %s (the file's %.9g)\n", clip.name, number, clip.fps);
        assert_true(strtof(number, NULL) == clip.fps);
        size_t digits = strspn(number, "0123456789") + (strchr(number, '.') ? strspn(strchr(number, '.') + 1, "0123456789") : 0);
        char shorter[320];
        snprintf(shorter, sizeof shorter, "%.*g", (int)digits - 1, clip.fps);
        assert_null(strchr(number, 'e'));
        assert_true(digits <= 1 || strchr(shorter, 'e') || strtof(shorter, NULL) != clip.fps); /* one digit fewer does not */
    }
    cbpal_close(&pal);
    free(json);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_travelling_loop_bakes_in_place),
        cmocka_unit_test(test_one_shots_keep_their_travel),
        cmocka_unit_test(test_manifest_says_root_motion_per_clip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
