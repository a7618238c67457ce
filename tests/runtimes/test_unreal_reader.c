/* test_unreal_reader.c - the Unreal plugin's engine-free part, proven outside Unreal: its .pal
 * reading (runtimes/unreal/.../CrowdbakePalReader.cpp, the factory's and the palette asset's, through
 * the C reader crowdbake_pal.h) and its herd logic (CrowdbakeHerdLogic.cpp, the herd component's)
 * compile with g++ -Wall -Wextra -Werror, and tests/runtimes/unreal/reader_check.cpp holds them to
 * the C reader on Fox and Cow in every layout x precision: texels byte for byte, bind positions,
 * clip table, a herd's bone matrices mid-fade and after, SetSpeed without a pop. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include "runtimes/bone_order.h"
#include "runtimes/conformance.h"
#include "runtimes/timed_roster.h"
#include "crowdbake/pal_view.h"
#include "timed_subset.h"

#define TMP TEST_TMP "/unreal_reader"
#define SRC "runtimes/unreal/Crowdbake/Source/Crowdbake"

static void run_or_fail(const char *cmd, char *log, size_t size)
{
    if (run_command(cmd, log, size) != 0) fail_msg("%s:\n%s", cmd, log);
}

/* g++, warnings as errors, outside Unreal: the reading part and the herd logic with the check program. */
static void build_reader_check(void)
{
    static char log[8192];
    char cmd[4096];
    snprintf(cmd, sizeof cmd,
             "mkdir -p %s && g++ -std=c++17 -O1 -Wall -Wextra -Werror -I%s/Public -Iinclude -o %s/reader_check "
             "tests/runtimes/unreal/reader_check.cpp %s/Private/CrowdbakePalReader.cpp %s/Private/CrowdbakeHerdLogic.cpp 2>&1",
             TMP, SRC, TMP, SRC, SRC);
    run_or_fail(cmd, log, sizeof log);
}

static void test_reader_and_herd_equal_the_c_reader(void **state)
{
    (void)state;
    static char log[8192];
    char cmd[4096], model[1024];
    build_reader_check();
    const char *models[] = {"assets/fox-bevy/Fox.glb", "assets/quaternius-cow/Cow.glb"};
    const char *layouts[] = {"mat4", "affine", "qpos"}, *precisions[] = {"float", "half", "u16"};
    for (int m = 0; m < 2; ++m) {
        shared_path(model, sizeof model, models[m]);
        for (int l = 0; l < 3; ++l)
            for (int p = 0; p < 3; ++p) {
                snprintf(cmd, sizeof cmd, "%s bake %s -o %s/x.pal --layout %s --precision %s -q 2>&1 && %s/reader_check %s/x.pal 2>&1",
                         crowdbake_exe(), model, TMP, layouts[l], precisions[p], TMP, TMP);
                run_or_fail(cmd, log, sizeof log);
                printf("  %s %s/%s: %s", models[m] + 7, layouts[l], precisions[p], strstr(log, ": ") ? strstr(log, ": ") + 2 : log);
            }
        for (int p = 0; p < 3; p += 2) { /* local rows (.pal version 6): qpos, u16 or float */
            snprintf(cmd, sizeof cmd,
                     "%s bake %s -o %s/x.pal --bone-space local --layout qpos --precision %s -q 2>&1 && %s/reader_check %s/x.pal 2>&1",
                     crowdbake_exe(), model, TMP, precisions[p], TMP, TMP);
            run_or_fail(cmd, log, sizeof log);
            printf("  %s local qpos/%s: %s", models[m] + 7, precisions[p], strstr(log, ": ") ? strstr(log, ": ") + 2 : log);
            if (!strstr(log, "CB_LOCAL_ROWS=1")) fail_msg("local rows: no CB_LOCAL_ROWS=1 define: %s", log);
        }
    }
}

/* Timed rows (.pal version 7): Fox baked uniform, Walk and Run made timed (timed_subset.h: rows kept at intervals
 * of 1, 2 and 3 cells, their maps before them), Survey left uniform. The plugin's clip table carries cells and
 * cell_rate, its herd's states of the timed clips carry -cell_rate, and its bone matrices (mid-fade and after,
 * through its instance numbers) equal the C reader's, which follows the map; SetSpeed keeps the sign and the cell. */
static void test_timed_rows(void **state)
{
    (void)state;
    static char log[8192];
    static const char *const variants[] = {"--precision half", "--precision u16 --layout qpos", "--precision float --layout mat4",
                                           "--precision u16 --layout affine --max-texture-size 200"};
    char fox[1024], cmd[4096], err[256];
    build_reader_check();
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    cb_model *m = load_or_fail(fox);
    for (size_t v = 0; v < COUNT_OF(variants); ++v) {
        snprintf(cmd, sizeof cmd, "%s bake %s -o %s/uniform.pal --fps 30 -q %s 2>&1", crowdbake_exe(), fox, TMP, variants[v]);
        run_or_fail(cmd, log, sizeof log);
        cbpal_file uniform;
        cb_palette view, timed;
        cb_error e = {0};
        if (cbpal_open(TMP "/uniform.pal", CBPAL_VERIFY_CHECKSUM, &uniform, err, sizeof err)) fail_msg("%s", err);
        assert_int_equal(cb_palette_view(&uniform, &view, &e), CB_OK);
        assert_true(timed_subset_make(&uniform, &view, 0, v == 3 ? 200 : 0, &timed));
        if (timed_subset_write(TMP "/timed.pal", &timed, &uniform, m, &e)) fail_msg("%s", e.message);
        timed_subset_free(&timed);
        cb_palette_view_free(&view);
        cbpal_close(&uniform);
        snprintf(cmd, sizeof cmd, "%s/reader_check %s/timed.pal 2>&1", TMP, TMP);
        run_or_fail(cmd, log, sizeof log);
        printf("  Fox timed %s: %s", variants[v], strstr(log, ": ") ? strstr(log, ": ") + 2 : log);
        if (!strstr(log, "(2 timed)")) fail_msg("expected 2 timed clips: %s", log);
    }
    cb_model_free(m);
}

/* The runtime conformance cases of timed rows (.pal version 7: conformance.h's timed_* but the local one, whose
 * composing the plugin leaves to the shader, and broken-timed-map-ignored) through the plugin's InstanceBoneMatrix
 * (reader_check conformance): every instance's skinned positions, cross-fades mixed as the herd mixes them, within the
 * cases' tolerance of the C runtime's; the map ignored misses by far. The plugin's instance numbers must name a whole
 * clip (InstanceClip), so the cases' "first row, still" (first, 1, 0, 0) is given as its clip on its first row. */
static void test_timed_conformance_cases(void **state)
{
    (void)state;
    static char log[8192];
    build_reader_check();
    conformance conf;
    conformance_make(&conf, TMP "/conformance");
    int ran = 0, caught = 0;
    for (int i = 0; i < conf.case_count; ++i) {
        const conf_case *k = &conf.cases[i];
        if (!k->timed || k->local) continue;
        const conf_palette *p = &conf.palettes[k->palette];
        FILE *f = fopen(TMP "/conformance/instances.txt", "w");
        assert_non_null(f);
        for (int t = 0; t < CONF_TIMES; ++t)
            for (uint32_t cl = 0; cl < p->view.clip_count; ++cl)
                for (int n = 0; n < CONF_PER_CLIP; ++n) {
                    float v[16];
                    conf_instance(&p->view.clips[cl], conf_times[t], n, k->row_offset, v);
                    if (v[9] == 1 && v[10] == 0) { /* "the first row, still" names no clip, which the plugin's numbers must: */
                        v[9] = v[5], v[10] = v[6];  /* the clip itself, on its first row at this time */
                        v[11] = (float)((1e-5 - conf_times[t] * fabs(v[6])) / fabs(v[5])); /* 1e-5 in: never wrapped */
                    }
                    double fade = v[13] > 0 ? fmin(fmax((conf_times[t] - v[12]) / v[13], 0), 1) : 1;
                    fprintf(f, "%.9g", conf_times[t]);
                    for (int j = 4; j < 12; ++j) fprintf(f, " %.9g", v[j]);
                    fprintf(f, " %.9g\n", (float)fade);
                }
        fclose(f);
        char cmd[4096];
        snprintf(cmd, sizeof cmd, "%s/reader_check conformance %s/conformance/%s %s/conformance/%s %s/conformance/instances.txt "
                 "%s/conformance/%s.cpp.out 2>&1", TMP, TMP, p->file, TMP, p->mesh, TMP, TMP, k->name);
        if (k->broken && run_command(cmd, log, sizeof log) != 0) { /* the map ignored: numbers that name no clip of the file */
            if (!strstr(log, "refused")) fail_msg("%s", log);
            printf("  %-24s refused: its instances (+-frames, a positive rate) name no clip of the timed file\n", k->name);
            ++caught, ++ran;
            continue;
        }
        run_or_fail(cmd, log, sizeof log);
        snprintf(cmd, sizeof cmd, "%s/conformance/%s.cpp.out", TMP, k->name);
        double units, ratio = conformance_compare_file(&conf, k, cmd, &units);
        printf("  %-24s %7zu positions, cross-fades included: C++ vs C runtime %.2g (%.3f of the tolerance)\n", k->name,
               conf_positions(&conf, k), units, ratio);
        if (k->broken) assert_true(ratio > 10), ++caught;
        else assert_true(ratio <= 1);
        ++ran;
    }
    conformance_free(&conf);
    assert_true(ran >= 7 && caught == 1);
}

/* Local rows whose every parent comes after its children (runtimes/bone_order.h): the reader's bind
 * texture rows and the herd's composed matrices still equal the C reader's. */
static void test_parents_after_children(void **state)
{
    (void)state;
    static char log[8192];
    build_reader_check();
    run_or_fail("mkdir -p " TMP, log, sizeof log);
    write_local_quadruped(TMP "/reversed.pal", true);
    run_or_fail(TMP "/reader_check " TMP "/reversed.pal 2>&1", log, sizeof log);
    printf("  quadruped local u16, bones reversed: %s", strstr(log, ": ") ? strstr(log, ": ") + 2 : log);
}

/* The herd component's footsteps and travel, outside Unreal: a Cow catalog with a walk, a gallop
 * (per-row travel) and a one-shot, baked with the [bake] keys KEYS into TMP/DIR; the roster as Python's json reads it;
 * the herd logic at several speeds and across cross-fades. Each footstep falls on a contact of its state's clip, in
 * order, and each travel offset is the C reader's (tests/runtimes/unreal/reader_check.cpp `herd`). */
static void check_cow_herd(const char *dir, const char *keys)
{
    static char log[8192];
    char cmd[4096], bake_keys[512];
    build_reader_check();
    run_or_fail("mkdir -p " TMP, log, sizeof log);
    snprintf(cmd, sizeof cmd, TMP "/%s.toml", dir);
    snprintf(bake_keys, sizeof bake_keys, "out_dir = \"%s\"\n%s", dir, keys);
    if (bake_cow_catalog(cmd, bake_keys,
                         "states = { idle = [\"idle\"], wander = [\"walk\"], flee = [\"gallop\"], kick = [\"Attack_Kick\"] }"))
        fail_msg("%s did not bake", cmd);
    snprintf(cmd, sizeof cmd,
             "python3 tests/runtimes/unity/roster_lines.py %s/%s/roster.json > %s/%s.txt && "
             "%s/reader_check herd %s/%s/cow.pal %s/%s.txt cow 2>&1",
             TMP, dir, TMP, dir, TMP, TMP, dir, TMP, dir);
    run_or_fail(cmd, log, sizeof log);
    printf("  %s: %s", dir, strstr(log, "herd of") ? strstr(log, "herd of") : log);
}

static void test_herd_footsteps_and_travel(void **state)
{
    (void)state;
    check_cow_herd("roster", "");
}

/* The same from local, timed rows: every clip timed, its states counting cells at z < 0, its contacts on cells. */
static void test_timed_herd_footsteps_and_travel(void **state)
{
    (void)state;
    check_cow_herd("timed-cow", "bone_space = \"local\"\ntimed_rows = \"on\"");
}

/* The herd component's roster states with timed rows, outside Unreal: the timed catalog's roster (tests/runtimes/
 * timed_roster.h) as Python's json reads it, each state through CheckRosterState (the component's check) and the herd
 * logic's four numbers standing still and moving (reader_check.cpp `states`); a damaged timed state refused, one line. */
static void test_roster_timed_states(void **state)
{
    (void)state;
    static char log[8192];
    char cmd[2048];
    build_reader_check();
    bake_timed_roster(TMP);
    snprintf(cmd, sizeof cmd,
             "python3 tests/runtimes/unity/roster_lines.py %s/timed/roster.json > %s/timed.txt && %s/reader_check states %s/timed.txt > "
             "%s/instances.txt 2>&1",
             TMP, TMP, TMP, TMP, TMP);
    run_or_fail(cmd, log, sizeof log);
    check_timed_instance_lines(TMP "/instances.txt", "Unreal");
    for (size_t d = 0; d < COUNT_OF(timed_roster_damages); ++d) {
        damage_timed_roster(TMP, timed_roster_damages[d].edit, TMP "/broken.json");
        snprintf(cmd, sizeof cmd, "python3 tests/runtimes/unity/roster_lines.py %s/broken.json > %s/broken.txt && %s/reader_check states %s/broken.txt 2>&1",
                 TMP, TMP, TMP, TMP);
        if (run_command(cmd, log, sizeof log) == 0) fail_msg("a damaged timed state (%s) was read", timed_roster_damages[d].edit);
        check_timed_refusal(log, d);
    }
}

/* A damaged file: the factory's message is the C reader's, with the file's name. */
static void test_bad_file_message(void **state)
{
    (void)state;
    static char log[8192];
    build_reader_check();
    run_or_fail("mkdir -p " TMP " && printf 'CBPAL\\r\\n\\032\\377\\377\\377\\377' > " TMP "/bad.pal", log, sizeof log);
    char cmd[1024];
    snprintf(cmd, sizeof cmd, "%s/reader_check %s/bad.pal 2>&1", TMP, TMP);
    assert_int_equal(run_command(cmd, log, sizeof log), 1);
    if (!strstr(log, "bad.pal: palette format version 4294967295 is newer than this reader")) fail_msg("%s", log);
}

/* `crowdbake mesh --vertex-id-uv N --skin-texture F`: the Khronos validator passes the .glb; Python
 * reads the ids (0, 1, ... over the primitives) and each vertex's joints and weights from the .glb,
 * equal to the skin texture as the plugin's ReadSkin reads it; a channel the model's own UVs hold,
 * or a skin texture without ids, is refused with the fix. */
static void test_vertex_ids_and_skin_texture(void **state)
{
    (void)state;
    static char log[16384];
    require_node_validators();
    build_reader_check();
    struct { const char *model, *args; unsigned set; } cases[] = {
        {"assets/fox-bevy/Fox.glb", "", 1}, {"assets/quaternius-cow/Cow.glb", "--quantize --max-influences 2", 2}};
    char cmd[8192], model[1024];
    for (int i = 0; i < 2; ++i) {
        shared_path(model, sizeof model, cases[i].model);
        snprintf(cmd, sizeof cmd,
                 "%s mesh %s -o %s/ids.glb --vertex-id-uv %u --skin-texture %s/ids.cbskin %s -q 2>&1 && "
                 "node tests/tools/validator/validate.mjs %s/ids.glb 2>&1 && %s/reader_check skin %s/ids.cbskin > %s/skin.txt && "
                 "python3 tests/runtimes/unreal/check_vertex_ids.py %s/ids.glb %u %s/skin.txt 2>&1",
                 crowdbake_exe(), model, TMP, cases[i].set, TMP, cases[i].args, TMP, TMP, TMP, TMP, TMP, cases[i].set, TMP);
        run_or_fail(cmd, log, sizeof log);
        printf("  %s", strstr(log, "vertex ids") ? strstr(log, "vertex ids") - 0 : log);
    }
    shared_path(model, sizeof model, "assets/fox-bevy/Fox.glb");
    snprintf(cmd, sizeof cmd, "%s mesh %s -o %s/no.glb --vertex-id-uv 0 2>&1", crowdbake_exe(), model, TMP);
    assert_int_equal(run_command(cmd, log, sizeof log), EXIT_INPUT);
    if (!strstr(log, "TEXCOORD_0 holds the model's texture coordinates") || !strstr(log, "--vertex-id-uv 1")) fail_msg("%s", log);
    snprintf(cmd, sizeof cmd, "%s mesh %s -o %s/no.glb --skin-texture %s/no.cbskin 2>&1", crowdbake_exe(), model, TMP, TMP);
    assert_int_equal(run_command(cmd, log, sizeof log), EXIT_USAGE);
    if (!strstr(log, "give --vertex-id-uv N too")) fail_msg("%s", log);
    FILE *f = fopen(TMP "/no.glb", "r");
    assert_null(f); /* nothing half-written */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reader_and_herd_equal_the_c_reader),
        cmocka_unit_test(test_parents_after_children),
        cmocka_unit_test(test_timed_rows),
        cmocka_unit_test(test_timed_conformance_cases),
        cmocka_unit_test(test_herd_footsteps_and_travel),
        cmocka_unit_test(test_timed_herd_footsteps_and_travel),
        cmocka_unit_test(test_roster_timed_states),
        cmocka_unit_test(test_bad_file_message),
        cmocka_unit_test(test_vertex_ids_and_skin_texture),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
