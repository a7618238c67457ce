/* test_loop_decision.c - loop or one-shot, weighed from the clip's name, its poses (root travel
 * taken off) and its feet, with the reason said (issue 45): every clip of Cow, Husky, Fox and the
 * robot (../shared/assets) against what each clip is by its maker's name and what it does (a
 * hit reaction or an attack plays once though it returns to its first pose; a gallop loops);
 * no decision within a hair of its threshold; `--loop`/`--one-shot` and a catalog's loop still
 * win. And the speed reference that a program linking the library records. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <math.h>

#include "crowdbake_pal.h"
#include "crowdbake/bake.h"
#include "crowdbake/stride.h"
#include "internal/plumbing.h"

#define TMP TEST_TMP "/loop_decision"

static int setup(void **state)
{
    (void)state;
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

/* What each clip is, by its name and what it does on screen. */
typedef struct expected {
    const char *clip;
    bool loops;
} expected;

static const expected cow[] = {
    {"AnimalArmature|Attack_Headbutt", false}, {"AnimalArmature|Attack_Kick", false}, {"AnimalArmature|Death", false},
    {"AnimalArmature|Eating", true},           {"AnimalArmature|Gallop", true},      {"AnimalArmature|Gallop_Jump", true},
    {"AnimalArmature|Idle", true},             {"AnimalArmature|Idle_2", true},      {"AnimalArmature|Idle_Headlow", true},
    {"AnimalArmature|Idle_HitReact_Left", false}, {"AnimalArmature|Jump_toIdle", false}, {"AnimalArmature|Walk", true}};
static const expected husky[] = {
    {"AnimalArmature|Attack", false},  {"AnimalArmature|Death", false},       {"AnimalArmature|Eating", true},
    {"AnimalArmature|Gallop", true},   {"AnimalArmature|Gallop_Jump", true},  {"AnimalArmature|Idle", true},
    {"AnimalArmature|Idle_2", true},   {"AnimalArmature|Idle_2_HeadLow", true}, {"AnimalArmature|Idle_HitReact_Left", false},
    {"AnimalArmature|Idle_HitReact_Right", false}, {"AnimalArmature|Jump_ToIdle", false}, {"AnimalArmature|Walk", true}};
static const expected fox[] = {{"Survey", true}, {"Walk", true}, {"Run", true}};
/* The robot's gestures (No, Yes, Wave, ThumbsUp) end where they start: a crowd may repeat them.
 * Sitting and Standing go from one posture to another: played once. */
static const expected robot[] = {
    {"Robot_Dance", true},     {"Robot_Death", false},   {"Robot_Idle", true},     {"Robot_Jump", false},
    {"Robot_No", true},        {"Robot_Punch", false},   {"Robot_Running", true},  {"Robot_Sitting", false},
    {"Robot_Standing", false}, {"Robot_ThumbsUp", true}, {"Robot_Walking", true},  {"Robot_WalkJump", true},
    {"Robot_Wave", true},      {"Robot_Yes", true}};

static void check_model(const char *asset, const expected *want, size_t count)
{
    cb_model *m = load_shared(asset);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    assert_int_equal(m->animation_count, count + (m->animation_count > count ? m->animation_count - count : 0));
    for (size_t i = 0; i < count; ++i) {
        int32_t a = cb_model_find_animation(m, want[i].clip);
        if (a < 0) fail_msg("%s has no clip '%s'", asset, want[i].clip);
        cb_clip_info info;
        assert_int_equal(cb_clip_analyze(s, a, 30, -1, NULL, &info, &err), CB_OK);
        char why[512];
        cb_loop_reason_text(&info, why, sizeof why);
        printf("  %-36s %s\n", want[i].clip, why);
        if (info.loops != want[i].loops) fail_msg("%s '%s': %s", asset, want[i].clip, why);
        /* The reason names all three pieces of evidence and what overrides it. */
        assert_non_null(strstr(why, want[i].loops ? "loops (+" : "plays once (-"));
        assert_true(strstr(why, "the name says") || strstr(why, "no word of the name decides"));
        assert_true(strstr(why, "feet"));
        assert_non_null(strstr(why, "--loop/--one-shot or a catalog's loop overrides"));
        /* Never a knife edge: the evidence clears the threshold by a margin. */
        double total = info.loop_name + info.loop_pose + info.loop_feet;
        if (fabs(total) < 0.5) fail_msg("%s '%s' decided by a hair: %s", asset, want[i].clip, why);
    }
    cb_sampler_free(s);
    cb_model_free(m);
}

static void test_cow_clips(void **state)
{
    (void)state;
    check_model("assets/quaternius-cow/Cow.glb", cow, sizeof cow / sizeof *cow);
}

static void test_husky_clips(void **state)
{
    (void)state;
    check_model("assets/quaternius-husky/Husky.glb", husky, sizeof husky / sizeof *husky);
}

static void test_fox_and_robot_clips(void **state)
{
    (void)state;
    check_model("assets/fox-bevy/Fox.glb", fox, sizeof fox / sizeof *fox);
    check_model("assets/robot-quaternius-raylib/robot.glb", robot, sizeof robot / sizeof *robot);
}

/* One clip's decision with its name replaced, the poses and feet its own. */
static cb_clip_info renamed(cb_model *m, cb_sampler *s, const char *clip, const char *name)
{
    int32_t a = cb_model_find_animation(m, clip);
    assert_true(a >= 0);
    const char *own = m->animations[a].name;
    m->animations[a].name = name;
    cb_clip_info info;
    cb_error err = {0};
    assert_int_equal(cb_clip_analyze(s, a, 30, -1, NULL, &info, &err), CB_OK);
    m->animations[a].name = own;
    char why[512];
    cb_loop_reason_text(&info, why, sizeof why);
    printf("  %s as '%s': %s\n", clip, name, why);
    return info;
}

/* The three weighed, not one number on a knife edge: Attack_Kick's poses lean a little to a
 * one-shot (its wrap a bit over its neighbour steps, as the pack's Gallop that was taken for a
 * one-shot by 73.4 against 66.3): named as a gallop it loops, over one more key interval. A
 * death named as a walk does not: its poses say one-shot as loud as the name says loop, and its
 * feet do not stride. A walk with a name that says nothing loops by its poses and its feet. */
static void test_evidence_weighed(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/quaternius-cow/Cow.glb");
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info kick = renamed(m, s, "AnimalArmature|Attack_Kick", "AnimalArmature|Gallop_B");
    assert_true(kick.loop_pose < 0 && kick.loop_pose > -1);
    assert_true(kick.loops);
    assert_float_equal(kick.duration, kick.t1 - kick.t0 + kick.key_interval, 1e-9);
    cb_clip_info death = renamed(m, s, "AnimalArmature|Death", "AnimalArmature|Walk_B");
    assert_false(death.loops);
    assert_true(death.loop_feet_weighed && death.loop_feet == 0);
    cb_clip_info walk = renamed(m, s, "AnimalArmature|Walk", "AnimalArmature|Clip_7");
    assert_true(walk.loops && walk.loop_name == 0);
    cb_sampler_free(s);
    cb_model_free(m);
}

/* The caller's word wins over every piece of evidence: a hit reaction forced to loop, a gallop
 * forced to play once; on the command line, --loop and --one-shot. */
static void test_overrides_win(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/quaternius-cow/Cow.glb");
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_clip_info info;
    char why[512];
    assert_int_equal(cb_clip_analyze(s, cb_model_find_animation(m, "AnimalArmature|Idle_HitReact_Left"), 30, 1, NULL, &info, &err), CB_OK);
    assert_true(info.loops && info.loop_set);
    cb_loop_reason_text(&info, why, sizeof why);
    assert_non_null(strstr(why, "set by the catalog or --loop/--one-shot"));
    assert_int_equal(cb_clip_analyze(s, cb_model_find_animation(m, "AnimalArmature|Gallop"), 30, 0, NULL, &info, &err), CB_OK);
    assert_false(info.loops);
    cb_sampler_free(s);
    cb_model_free(m);

    static char out[65536];
    char cow_path[1024], cmd[4096];
    shared_path(cow_path, sizeof cow_path, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "%s bake %s --clip Idle_HitReact_Left,Attack_Kick --loop Idle_HitReact_Left "
             "--fps 30 -o " TMP "/forced.pal -q && %s inspect " TMP "/forced.pal --json", crowdbake_exe(), cow_path,
             crowdbake_exe());
    if (run_command(cmd, out, sizeof out) != 0) fail_msg("%s", out);
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/forced.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    for (uint32_t c = 0; c < f.header.clip_count; ++c) {
        cbpal_clip clip;
        cbpal_get_clip(&f, c, &clip);
        bool hit = strstr(clip.name, "HitReact") != NULL;
        assert_int_equal((clip.flags & CBPAL_CLIP_LOOPS) != 0, hit); /* the hit reaction loops as told; the kick plays once as decided */
    }
    cbpal_close(&f);
}

/* A program linking the library, leaving the speed reference to the job, records the one the
 * command records: the slowest locomotion clip's ground speed (Cow's Walk, from its planted
 * feet; the independent reference's stance-weighted mean is 2.431 units/s). */
static void test_library_decides_the_speed_reference(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/quaternius-cow/Cow.glb");
    cb_bake_job job;
    cb_bake_job_init(&job);
    assert_true(job.speed_reference < 0); /* decided by the job unless given */
    job.model = m, job.skin = 0, job.threads = 2;
    cb_clip_plan clips[2] = {{cb_model_find_animation(m, "AnimalArmature|Walk"), NULL, -1, 30, false, false, 0, NULL},
                             {cb_model_find_animation(m, "AnimalArmature|Gallop"), NULL, -1, 30, false, false, 0, NULL}};
    job.clips = clips, job.clip_count = 2;
    job.settings.fps_auto = false, job.settings.fps = 30;
    cb_output_path out = {CB_FORMAT_PAL, TMP "/library.pal"};
    job.outputs = &out, job.output_count = 1;
    cb_bake_result result;
    cb_error err = {0};
    if (cb_bake_job_run(&job, &result, &err)) fail_msg("%s", err.message);
    printf("  speed reference %.4f: %s\n", job.speed_reference, job.speed_reference_from);
    assert_float_equal(job.speed_reference, 2.431, 0.05 * 2.431);
    assert_non_null(strstr(job.speed_reference_from, "'AnimalArmature|Walk'"));
    cb_bake_result_free(&result);
    cb_bake_job_free(&job);
    cb_model_free(m);
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/library.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    assert_float_equal(f.header.speed_reference, 2.431, 0.05 * 2.431);
    float library = f.header.speed_reference;
    cbpal_close(&f);
    /* The command's bake of the same clips records the same one. */
    static char log[8192];
    char cow[1024], cmd[4096];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "%s bake %s --clip Walk,Gallop --fps 30 -o " TMP "/command.pal -q", crowdbake_exe(), cow);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s", log);
    assert_int_equal(cbpal_open(TMP "/command.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    assert_true(f.header.speed_reference == library);
    cbpal_close(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cow_clips),
        cmocka_unit_test(test_husky_clips),
        cmocka_unit_test(test_fox_and_robot_clips),
        cmocka_unit_test(test_evidence_weighed),
        cmocka_unit_test(test_overrides_win),
        cmocka_unit_test(test_library_decides_the_speed_reference),
    };
    return cmocka_run_group_tests_name("loop decision", tests, setup, NULL);
}
