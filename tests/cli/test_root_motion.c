/* test_root_motion.c - root motion decided like the rest (issue 45): a bare bake of a loop that
 * travels (the fish sample swims 0.6 units a loop) succeeds, the loop baked in place with its
 * velocity recorded and a note saying why; --root-motion keep still keeps the travel (and then
 * the wrap's pull-back is over the budget, as before); one-shots keep their travel where a loop
 * goes in place (Cow's Death beside its Jump_toIdle made a loop); info says the same per clip. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_travelling_loop_bakes_in_place),
        cmocka_unit_test(test_one_shots_keep_their_travel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
