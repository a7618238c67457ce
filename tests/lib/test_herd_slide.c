/* test_herd_slide.c - the slide a herd shows (crowdbake/herd_slide.h), decided in one place:
 * the rule on made-up strides, then `info` agreeing with the roster's warning and the report
 * (test_row_travel) on Husky: its Gallop slides 32% without its per-row travel and under the
 * quarter with it, so no word of sliding at any rate; its Walk, which gets none, slides 134%.
 * And per-row travel refused to a loop whose name says an action: Husky's Gallop, the same
 * keys under the name "Attack_Gallop" and looped, would ship offsets (they cut its slide by more
 * than half) that no runtime draws, since an attack never follows the speed. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include "crowdbake/herd_slide.h"

#define TMP TEST_TMP "/herd_slide"

static cb_stride striding(double mean, double worst)
{
    cb_stride st;
    memset(&st, 0, sizeof st);
    st.stride = true, st.speed = 1, st.slide_mean = mean, st.slide_worst = worst;
    return st;
}

static void test_the_rule(void **state)
{
    (void)state;
    cb_stride st = striding(0.32, 1.1);
    cb_row_travel travel;
    memset(&travel, 0, sizeof travel);
    travel.slide_mean = 0.32, travel.slide_with = 0.12;
    cb_herd_slide h;
    /* Offsets measured but not shipped: the herd shows the stride's own slide. */
    cb_herd_slide_decide(&st, &travel, &h);
    assert_true(h.measured && !h.with_travel && h.mean == 0.32 && h.worst == 1.1 && h.warn && h.plant);
    /* Shipped: what they leave, under the warning, still worth planting. */
    travel.applied = true;
    cb_herd_slide_decide(&st, &travel, &h);
    assert_true(h.with_travel && h.mean == 0.12 && h.without == 0.32 && !h.warn && h.plant);
    /* Planting asks before any travel is decided; the thresholds are exclusive. */
    st.slide_mean = CB_PLANT_SLIDE_GOAL;
    cb_herd_slide_decide(&st, NULL, &h);
    assert_true(!h.with_travel && !h.plant && !h.warn);
    st.slide_mean = CB_SLIDE_WARN;
    cb_herd_slide_decide(&st, NULL, &h);
    assert_true(h.plant && !h.warn);
    /* No stride: nothing measured, nothing said. */
    st.stride = false;
    cb_herd_slide_decide(&st, &travel, &h);
    assert_true(!h.measured && h.mean == 0 && !h.warn && !h.plant);
}

/* `info`'s text on Husky: the line of a clip's slide says the asset slides at any rate only where
 * the herd shows it (the walk), not where the per-row travel takes it under (the gallop). */
static void test_info_agrees(void **state)
{
    (void)state;
    char model[1024], cmd[4096];
    static char log[65536];
    shared_path(model, sizeof model, "assets/quaternius-husky/Husky.glb");
    snprintf(cmd, sizeof cmd, "%s info %s 2>&1", crowdbake_exe(), model);
    if (run_command(cmd, log, sizeof log) != 0) fail_msg("%s: %s", cmd, log);
    bool walk = false, gallop = false;
    const char *clip = "";
    for (char *line = strtok(log, "\n"); line; line = strtok(NULL, "\n")) {
        if (strstr(line, "AnimalArmature|")) clip = strstr(line, "AnimalArmature|");
        if (!strstr(line, "the asset's feet slide at any rate")) continue;
        walk |= strncmp(clip, "AnimalArmature|Walk", 19) == 0;
        gallop |= strncmp(clip, "AnimalArmature|Gallop ", 22) == 0;
    }
    assert_true(walk);
    assert_false(gallop);
}

static int32_t animation_named(const cb_model *m, const char *name)
{
    for (uint32_t a = 0; a < m->animation_count; ++a)
        if (strcmp(m->animations[a].name, name) == 0) return (int32_t)a;
    fail_msg("no animation %s", name);
    return -1;
}

/* The decision on one animation of the model, looped and baked in place at 30 fps. */
static void travel_of(const cb_model *m, int32_t a, cb_row_travel *out)
{
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    cb_limits limits = cb_default_limits();
    cb_clip_info info;
    assert_non_null(s);
    assert_int_equal(cb_clip_analyze(s, a, 30, 1, &limits, &info, &err), CB_OK);
    float *offsets = calloc(info.frames, sizeof *offsets);
    assert_non_null(offsets);
    cb_row_travel_measure(s, &info, true, info.frames, offsets, out);
    free(offsets);
    cb_sampler_free(s);
}

static void test_no_travel_for_an_action(void **state)
{
    (void)state;
    cb_model *m = load_shared("assets/quaternius-husky/Husky.glb");
    int32_t a = animation_named(m, "AnimalArmature|Gallop");
    cb_row_travel gallop, attack;
    travel_of(m, a, &gallop);
    const char *name = m->animations[a].name;
    m->animations[a].name = "AnimalArmature|Attack_Gallop";
    travel_of(m, a, &attack);
    m->animations[a].name = name;
    print_message("Gallop: %s\nAttack_Gallop: %s\n", gallop.why, attack.why);
    assert_true(gallop.applied);
    assert_false(attack.applied);
    assert_non_null(strstr(attack.why, "the clip's name says 'attack'"));
    assert_true(attack.slide_mean == gallop.slide_mean && attack.slide_with == gallop.slide_with); /* measured all the same */
    cb_model_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_rule),
        cmocka_unit_test(test_info_agrees),
        cmocka_unit_test(test_no_travel_for_an_action),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
