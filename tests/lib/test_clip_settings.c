/* test_clip_settings.c - each clip's settings resolved once (clip_settings.h): the precedence
 * of the layers a setting may come from (default < catalog [bake] < catalog animal < command
 * line < catalog clip), each value's origin, and the line that states them. The catalogs are
 * parsed by the real TOML reader and the command line's options laid over them as `bake
 * CATALOG` does; the expected values are those the catalog text and the options state. */
#include "testutil.h"

#include "crowdbake/bake.h"
#include "catalog/catalog_toml.h"

/* A catalog of one animal (the quadruped sample) with these [bake], [animal] and clip keys. */
static void parse_catalog(const char *bake_keys, const char *animal_keys, const char *clip_keys, cb_catalog *cat)
{
    char text[2048], model[512];
    sample_path(model, sizeof model, "quadruped");
    snprintf(text, sizeof text, "[bake]\n%s\n[animal.a]\nmodel = \"%s\"\n%s\nclips = [{ source = \"walk\" %s }]\n", bake_keys,
             model, animal_keys, clip_keys);
    cb_error err = {0};
    if (cb_catalog_parse(text, strlen(text), "catalog.toml", cat, &err)) fail_msg("%s\n%s", err.message, text);
}

/* The command line's options for one run (NULL: none), as `bake CATALOG` lays them over it. */
typedef struct run_options {
    const char *fps;       /* "auto" or a rate */
    double max_error, max_fps;
    bool fit_rows, in_place;
} run_options;

static void override(cb_catalog *cat, const run_options *o)
{
    cb_bake_settings v = cb_default_bake_settings();
    unsigned fields = 0;
    if (o->fps) {
        fields |= CB_BAKE_FPS;
        v.fps_auto = strcmp(o->fps, "auto") == 0;
        if (!v.fps_auto) v.fps = atof(o->fps);
    }
    if (o->max_error > 0) v.max_error_mm = o->max_error, fields |= CB_BAKE_MAX_ERROR;
    if (o->max_fps > 0) v.max_fps = o->max_fps, fields |= CB_BAKE_MAX_FPS;
    if (o->fit_rows) v.fit_rows = true, fields |= CB_BAKE_FIT_ROWS;
    if (o->in_place) v.root_motion = CB_ROOT_MOTION_IN_PLACE, fields |= CB_BAKE_ROOT_MOTION;
    cb_error err = {0};
    if (cb_catalog_override_bake(cat, &v, fields, &err)) fail_msg("%s", err.message);
}

/* The animal's one clip, resolved as the roster's bake job resolves it. */
static cb_clip_settings resolve(const char *bake_keys, const char *animal_keys, const char *clip_keys,
                                const run_options *o, bool measurable)
{
    cb_catalog cat;
    parse_catalog(bake_keys, animal_keys, clip_keys, &cat);
    if (o) override(&cat, o);
    const cb_catalog_animal *an = &cat.animals[0];
    const cb_catalog_clip *c = &an->clips[0];
    cb_clip_plan plan = {0, c->name, c->loop, c->fps, false, false, 0, NULL};
    cb_clip_request request = {c->fps_auto, c->max_error_mm};
    cb_clip_settings s;
    cb_resolve_clip_settings(&an->bake, &plan, &request, CB_FROM_CLIP, measurable, &s);
    cb_catalog_free(&cat);
    return s;
}

static void expect_rate(cb_clip_settings s, bool fps_auto, double fps, cb_setting_from from)
{
    assert_int_equal(s.fps_auto, fps_auto);
    if (!fps_auto) assert_true(s.fps == fps);
    assert_int_equal(s.from.fps, from);
}

static void expect_budget(cb_clip_settings s, double max_error_mm, cb_setting_from from)
{
    if (s.max_error_mm != max_error_mm) fail_msg("max_error %g, expected %g", s.max_error_mm, max_error_mm);
    assert_int_equal(s.from.max_error, from);
}

/* fps: each layer over the one before; a clip's own fps or "auto" over the command line. */
static void test_rate_precedence(void **state)
{
    (void)state;
    expect_rate(resolve("", "", "", NULL, true), true, 0, CB_FROM_DEFAULT);
    expect_rate(resolve("fps = 24", "", "", NULL, true), false, 24, CB_FROM_CATALOG);
    expect_rate(resolve("fps = 24", "fps = \"auto\"", "", NULL, true), true, 0, CB_FROM_ANIMAL);
    expect_rate(resolve("fps = 24", "fps = \"auto\"", "", &(run_options){.fps = "30"}, true), false, 30,
                CB_FROM_COMMAND_LINE);
    expect_rate(resolve("", "fps = 24", "", &(run_options){.fps = "auto"}, true), true, 0, CB_FROM_COMMAND_LINE);
    expect_rate(resolve("", "", ", fps = \"auto\"", &(run_options){.fps = "30"}, true), true, 0, CB_FROM_CLIP);
    expect_rate(resolve("", "", ", fps = 12", &(run_options){.fps = "auto"}, true), false, 12, CB_FROM_CLIP);
    /* A skin with nothing to measure: the fixed fps, unless the clip itself asks for auto. */
    expect_rate(resolve("", "", "", NULL, false), false, 30, CB_FROM_RIG);
    expect_rate(resolve("fps = 20", "", "", NULL, false), false, 20, CB_FROM_CATALOG);
    expect_rate(resolve("", "", ", fps = \"auto\"", NULL, false), true, 0, CB_FROM_CLIP);
}

/* max_error: the budget of an error-bounded clip from the nearest layer; a fixed fps checked
 * only against a max_error given beside it, never the job's for a clip with an fps of its own. */
static void test_budget_precedence(void **state)
{
    (void)state;
    expect_budget(resolve("", "", "", NULL, true), 1, CB_FROM_DEFAULT);
    expect_budget(resolve("max_error = 2", "", "", NULL, true), 2, CB_FROM_CATALOG);
    expect_budget(resolve("max_error = 2", "max_error = 3", "", NULL, true), 3, CB_FROM_ANIMAL);
    expect_budget(resolve("max_error = 2", "max_error = 3", "", &(run_options){.max_error = 0.5}, true), 0.5,
                  CB_FROM_COMMAND_LINE);
    expect_budget(resolve("", "max_error = 3", ", max_error = 4", &(run_options){.max_error = 0.5}, true), 4,
                  CB_FROM_CLIP);
    /* A fixed fps: no budget unless one is given beside it. */
    expect_budget(resolve("fps = 30", "", "", NULL, true), 0, CB_FROM_CATALOG);
    expect_budget(resolve("fps = 30\nmax_error = 2", "", "", NULL, true), 2, CB_FROM_CATALOG);
    expect_budget(resolve("max_error = 2", "fps = 24", "", NULL, true), 0, CB_FROM_ANIMAL);
    expect_budget(resolve("", "fps = 24", "", &(run_options){.max_error = 0.5}, true), 0.5, CB_FROM_COMMAND_LINE);
    expect_budget(resolve("", "", ", fps = 12", &(run_options){.max_error = 0.5}, true), 0, CB_FROM_CLIP);
    expect_budget(resolve("", "", ", fps = 12, max_error = 4", NULL, true), 4, CB_FROM_CLIP);
}

/* max_fps, fit_rows and root_motion are the job's: [bake] < animal < command line. loop is the
 * clip's, else decided from the poses. */
static void test_job_wide_settings(void **state)
{
    (void)state;
    cb_clip_settings s = resolve("", "", "", NULL, true);
    assert_true(s.max_fps == CB_AUTO_MAX_FPS && !s.fit_rows && s.root_motion == CB_ROOT_MOTION_KEEP && s.loop == -1);
    assert_int_equal(s.from.max_fps, CB_FROM_DEFAULT);
    assert_int_equal(s.from.loop, CB_FROM_DEFAULT);
    s = resolve("max_fps = 60\nfit_rows = true", "max_fps = 90\nroot_motion = \"in-place\"", ", loop = false", NULL, true);
    assert_true(s.max_fps == 90 && s.fit_rows && s.root_motion == CB_ROOT_MOTION_IN_PLACE && s.loop == 0);
    assert_int_equal(s.from.max_fps, CB_FROM_ANIMAL);
    assert_int_equal(s.from.fit_rows, CB_FROM_CATALOG);
    assert_int_equal(s.from.root_motion, CB_FROM_ANIMAL);
    assert_int_equal(s.from.loop, CB_FROM_CLIP);
    s = resolve("max_fps = 60", "max_fps = 90", "", &(run_options){.max_fps = 180, .fit_rows = true, .in_place = true}, true);
    assert_true(s.max_fps == 180 && s.fit_rows && s.root_motion == CB_ROOT_MOTION_IN_PLACE);
    assert_int_equal(s.from.max_fps, CB_FROM_COMMAND_LINE);
    assert_int_equal(s.from.fit_rows, CB_FROM_COMMAND_LINE);
    assert_int_equal(s.from.root_motion, CB_FROM_COMMAND_LINE);
}

/* The line `info`, a log or a manifest can give for a clip: each value with its origin. */
static void test_reason_text(void **state)
{
    (void)state;
    char text[512];
    cb_clip_settings s = resolve("", "", "", NULL, true);
    cb_clip_settings_text(&s, text, sizeof text);
    assert_string_equal(text, "fps auto (default), max_error 1 mm/m (default), max_fps 120 (default), rows fitted or "
                              "sampled (default), root_motion keep (default), loop from the poses (default)");
    s = resolve("max_error = 2", "fps = 24\nroot_motion = \"in-place\"", ", loop = true",
                &(run_options){.max_fps = 180, .fit_rows = true}, true);
    cb_clip_settings_text(&s, text, sizeof text);
    assert_string_equal(text, "fps 24 (catalog animal), max_error none (catalog animal), max_fps 180 (command line), rows "
                              "fitted (command line), root_motion in-place (catalog animal), loop true (catalog clip)");
    s = resolve("", "", "", NULL, false);
    cb_clip_settings_text(&s, text, sizeof text);
    assert_string_equal(text, "fps 30 (rig: no skinned mesh), max_error none (rig: no skinned mesh), max_fps 120 (default), "
                              "rows fitted or sampled (default), root_motion keep (default), loop from the poses (default)");
}

/* `bake MODEL --json` states each clip's settings and their origins: the command line's, the
 * defaults' and the poses'. */
static void test_bake_json_states_the_settings(void **state)
{
    (void)state;
    char model[512], cmd[2048];
    static char out[1 << 16];
    sample_path(model, sizeof model, "quadruped");
    snprintf(cmd, sizeof cmd, "mkdir -p %s && %s bake %s -o %s/settings.pal --fps 24 --clip idle,walk --one-shot walk "
             "--json 2>&1", TEST_TMP, crowdbake_exe(), model, TEST_TMP);
    if (run_command(cmd, out, sizeof out) != 0) fail_msg("%s", out);
    const char *idle = strstr(out, "\"name\": \"idle\""), *walk = strstr(out, "\"name\": \"walk\"");
    assert_non_null(idle);
    assert_non_null(walk);
    const char *first = strstr(idle, "\"settings\": \"fps 24 (command line), max_error none (command line), max_fps 120 "
                                     "(default), rows fitted or sampled (default), root_motion keep (default), loop from "
                                     "the poses (default)\"");
    const char *second = strstr(walk, "\"settings\": \"fps 24 (command line), max_error none (command line), max_fps 120 "
                                      "(default), rows fitted or sampled (default), root_motion keep (default), loop false "
                                      "(command line)\"");
    if (!first || first > walk || !second) fail_msg("%s", out);
}

/* The rate search takes a concrete ceiling: a goal's max_fps of 0 no longer means "the default"
 * (resolved once, above), it is an error naming the setting. */
static void test_rate_search_wants_a_concrete_max_fps(void **state)
{
    (void)state;
    char model[512];
    sample_path(model, sizeof model, "quadruped");
    cb_model *m = load_or_fail(model);
    cb_error err = {0};
    cb_sampler *s = cb_sampler_create(m, 0, &err);
    assert_non_null(s);
    cb_bake_options o = cb_default_bake_options();
    cb_clip_plan plan = {0, NULL, -1, 0, false, false, 0, NULL};
    cb_rate_goal goal = {1, 0, CB_ROWS_BEST};
    assert_int_equal(cb_choose_rates(s, &o, &plan, 1, &goal, NULL, &err), CB_ERR_SETTINGS);
    assert_int_equal(err.setting, CB_SETTING_MAX_FPS);
    cb_sampler_free(s);
    cb_model_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rate_precedence),
        cmocka_unit_test(test_budget_precedence),
        cmocka_unit_test(test_job_wide_settings),
        cmocka_unit_test(test_reason_text),
        cmocka_unit_test(test_bake_json_states_the_settings),
        cmocka_unit_test(test_rate_search_wants_a_concrete_max_fps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
