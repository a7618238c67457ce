/* test_asset_ci.c - crowdbake as a build step, driven by the real Make and Ninja: a failed bake
 * never leaves a green build behind (with and without .DELETE_ON_ERROR), a touched input
 * converges, the manifest names what failed, the default output folder is created, and
 * command-line bake flags apply to a catalog (or are refused), never ignored. */
#define _DEFAULT_SOURCE
#include "testutil.h"

#include <limits.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "crowdbake_pal.h"
#include "crowdbake/exr.h"

#define TMP TEST_TMP "/asset_ci"

static char exe[PATH_MAX], fish[PATH_MAX];

static int setup(void **state)
{
    (void)state;
    char sample[PATH_MAX];
    snprintf(sample, sizeof sample, "%s/fish.glb", samples_dir());
    if (!realpath(crowdbake_exe(), exe) || !realpath(sample, fish)) return -1;
    return system("rm -rf " TMP " && mkdir -p " TMP);
}

/* Runs `cmd` in `dir` with stderr folded into out; returns the exit status. The make run by
 * `make test` must not hand its jobserver or flags to the make under test. */
static int run_in(const char *dir, const char *cmd, char *out, size_t size)
{
    char line[2 * PATH_MAX];
    snprintf(line, sizeof line, "cd %s && env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL %s 2>&1", dir, cmd);
    return run_command(line, out, size);
}

static void copy_file(const char *from, const char *to)
{
    char cmd[3 * PATH_MAX];
    snprintf(cmd, sizeof cmd, "cp %s %s", from, to);
    assert_int_equal(system(cmd), 0);
}

/* A project with two types on their own model copies (fish.glb, eel.glb). */
static void make_project(const char *dir)
{
    char cmd[PATH_MAX + 64], path[PATH_MAX];
    snprintf(cmd, sizeof cmd, "rm -rf %s && mkdir -p %s/build/roster", dir, dir);
    assert_int_equal(system(cmd), 0);
    snprintf(path, sizeof path, "%s/fish.glb", dir);
    copy_file(fish, path);
    snprintf(path, sizeof path, "%s/eel.glb", dir);
    copy_file(fish, path);
    snprintf(path, sizeof path, "%s/catalog.toml", dir);
    write_text(path, "[bake]\nfps = 30\n[animal.fish]\nmodel = \"fish.glb\"\n\n[animal.eel]\nmodel = \"eel.glb\"\nfps = 24\n");
}

/* Every file of the project 100 s older, as if the last build ran a while ago: the edit that
 * follows is then newer than the outputs whatever the file system's clock granularity. */
static void age_files(const char *dir)
{
    char cmd[PATH_MAX + 128];
    snprintf(cmd, sizeof cmd, "find %s -type f -exec touch -d @%lld {} +", dir, (long long)time(NULL) - 100);
    assert_int_equal(system(cmd), 0);
}

/* Runs the build tool; checks its exit status and that it did (or did not) run crowdbake. */
static void build_expect(const char *dir, const char *tool, bool succeeds, bool runs_bake)
{
    static char out[16384];
    int rc = run_in(dir, tool, out, sizeof out);
    if (succeeds != (rc == 0) || runs_bake != (strstr(out, "crowdbake") != NULL && strstr(out, " bake ") != NULL))
        fail_msg("%s in %s: exit %d, expected %s%s; output:\n%s", tool, dir, rc, succeeds ? "success" : "failure",
                 runs_bake ? " running the bake" : " without running the bake", out);
}

static void break_model(const char *dir)
{
    char path[PATH_MAX];
    age_files(dir);
    snprintf(path, sizeof path, "%s/eel.glb", dir);
    write_text(path, "not a model\n");
}

static void fix_model(const char *dir)
{
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/eel.glb", dir);
    copy_file(fish, path);
}

/* The whole cycle a CI sees: green, a model broken (red, and red again on the next run, not
 * "up to date"), the model fixed (green, then up to date); and a model touched without a
 * change (one run of the bake, then up to date rather than a bake on every build). */
static void build_cycle(const char *dir, const char *tool)
{
    build_expect(dir, tool, true, true);
    build_expect(dir, tool, true, false);
    break_model(dir);
    build_expect(dir, tool, false, true);
    build_expect(dir, tool, false, true);
    /* The manifest names the failure instead of silently leaving the type out. */
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/build/roster/roster.json", dir);
    struct stat st;
    if (stat(path, &st) == 0) { /* with .DELETE_ON_ERROR Make removed it */
        char *json = read_whole_file(path, NULL);
        if (!strstr(json, "\"failed\": {\n    \"eel\": {") || !strstr(json, "not a GLB file") || !strstr(json, "\"fish\": {"))
            fail_msg("manifest after a failed type:\n%s", json);
        free(json);
        static char out[4096];
        char cmd[PATH_MAX + 128];
        require_node_validators();
        snprintf(cmd, sizeof cmd, "node tests/tools/validator/validate_schema.mjs docs/roster.schema.json %s 2>&1", path);
        if (run_command(cmd, out, sizeof out) != 0) fail_msg("%s", out);
    }
    /* The depfile keeps the failed type's output and model, which did not even load. */
    snprintf(path, sizeof path, "%s/build/roster.d", dir);
    if (strcmp(tool, "make") == 0) {
        char *deps = read_whole_file(path, NULL);
        char want[PATH_MAX + 64];
        snprintf(want, sizeof want, "build/roster/eel.pal: catalog.toml \\\n  %s \\\n  eel.glb\n", exe);
        if (!strstr(deps, want) || !strstr(deps, "\neel.glb:\n"))
            fail_msg("depfile after a failed type:\n%s", deps);
        free(deps);
    }
    fix_model(dir);
    build_expect(dir, tool, true, true);
    build_expect(dir, tool, true, false);
    age_files(dir);
    snprintf(path, sizeof path, "touch %s/fish.glb", dir);
    assert_int_equal(system(path), 0);
    build_expect(dir, tool, true, true);
    build_expect(dir, tool, true, false);
}

static void make_cycle(const char *name, bool delete_on_error)
{
    char dir[PATH_MAX], path[PATH_MAX + 16], text[PATH_MAX + 512];
    snprintf(dir, sizeof dir, TMP "/%s", name);
    make_project(dir);
    /* The rule the README shows. */
    snprintf(text, sizeof text,
             "%sCROWDBAKE = %s\n\nbuild/roster/roster.json: catalog.toml\n"
             "\t$(CROWDBAKE) bake catalog.toml --depfile build/roster.d -q\n\n-include build/roster.d\n",
             delete_on_error ? ".DELETE_ON_ERROR:\n" : "", exe);
    snprintf(path, sizeof path, "%s/Makefile", dir);
    write_text(path, text);
    build_cycle(dir, "make");
}

static void test_make_stays_red_until_the_model_is_fixed(void **state)
{
    (void)state;
    make_cycle("make", false);
}

static void test_make_with_delete_on_error(void **state)
{
    (void)state;
    make_cycle("make-delete-on-error", true);
}

/* The depfile names the crowdbake executable: a new build of the tool runs the bake again (which
 * decides per type what the new version changes), and the build after that is up to date, not a
 * bake on every build. The project runs its own copy of the tool, so that it can be touched. */
static void test_make_reruns_when_the_tool_changes(void **state)
{
    (void)state;
    char dir[] = TMP "/upgrade", tool[PATH_MAX], path[PATH_MAX + 16], text[PATH_MAX + 512];
    make_project(dir);
    snprintf(path, sizeof path, "%s/bin-crowdbake", dir);
    copy_file(exe, path);
    assert_non_null(realpath(path, tool)); /* as the depfile names it */
    write_text(TMP "/upgrade/Makefile", "CROWDBAKE = ./bin-crowdbake\n\nbuild/roster/roster.json: catalog.toml\n"
               "\t$(CROWDBAKE) bake catalog.toml --depfile build/roster.d -q\n\n-include build/roster.d\n");
    build_expect(dir, "make", true, true);
    build_expect(dir, "make", true, false);
    age_files(dir);
    snprintf(path, sizeof path, "touch %s", tool); /* as an upgrade leaves it: newer than the outputs */
    assert_int_equal(system(path), 0);
    build_expect(dir, "make", true, true);
    build_expect(dir, "make", true, false);
    char *deps = read_whole_file(TMP "/upgrade/build/roster.d", NULL);
    snprintf(text, sizeof text, "\n%s:\n", tool);
    if (!strstr(deps, text)) fail_msg("depfile without the tool's empty rule:\n%s", deps);
    free(deps);
}

static void test_ninja_stays_red_until_the_model_is_fixed(void **state)
{
    (void)state;
    char dir[PATH_MAX], path[PATH_MAX + 16], text[PATH_MAX + 512];
    snprintf(dir, sizeof dir, TMP "/ninja");
    make_project(dir);
    snprintf(text, sizeof text,
             "rule crowdbake\n  command = %s bake $in --depfile $out.d -q\n  depfile = $out.d\n  deps = gcc\n"
             "  description = crowdbake bake $in\n\nbuild build/roster/roster.json: crowdbake catalog.toml\n", exe);
    snprintf(path, sizeof path, "%s/build.ninja", dir);
    write_text(path, text);
    build_cycle(dir, "ninja");
}

/* A catalog without out_dir writes to build/roster beside it, creating both folders. */
static void test_default_output_folder_is_created(void **state)
{
    (void)state;
    char dir[] = TMP "/fresh", text[PATH_MAX + 64], out[8192];
    assert_int_equal(system("rm -rf " TMP "/fresh && mkdir -p " TMP "/fresh"), 0);
    snprintf(text, sizeof text, "[bake]\nfps = 30\n[animal.fish]\nmodel = \"%s\"\n", fish);
    write_text(TMP "/fresh/catalog.toml", text);
    char cmd[PATH_MAX + 128];
    snprintf(cmd, sizeof cmd, "%s bake catalog.toml -q", exe);
    int rc = run_in(dir, cmd, out, sizeof out);
    if (rc != 0) fail_msg("exit %d: %s", rc, out);
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/fresh/build/roster/fish.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    cbpal_close(&f);
    struct stat st;
    assert_int_equal(stat(TMP "/fresh/build/roster/roster.json", &st), 0);
    /* --manifest and --depfile in folders that do not exist yet. */
    snprintf(cmd, sizeof cmd, "%s bake catalog.toml -q --manifest out/m/roster.json --depfile deps/d/roster.d", exe);
    rc = run_in(dir, cmd, out, sizeof out);
    if (rc != 0) fail_msg("exit %d: %s", rc, out);
    assert_int_equal(stat(TMP "/fresh/out/m/roster.json", &st), 0);
    assert_int_equal(stat(TMP "/fresh/deps/d/roster.d", &st), 0);
}

/* A report over a roster whose type failed gives no budget verdict, whatever the budget. */
static void test_report_with_a_failed_type_passes_no_budget(void **state)
{
    (void)state;
    static char out[16384];
    assert_int_equal(system("rm -rf " TMP "/report && mkdir -p " TMP "/report"), 0);
    write_text(TMP "/report/broken.glb", "not a model\n");
    write_text(TMP "/report/catalog.toml", "[budget]\ntarget = \"Steam Deck\"\n\n[animal.eel]\nmodel = \"broken.glb\"\n");
    char cmd[PATH_MAX + 128];
    snprintf(cmd, sizeof cmd, "cd " TMP "/report && %s report catalog.toml --json --no-fail 2>/dev/null", exe);
    int rc = run_command(cmd, out, sizeof out);
    assert_int_equal(rc, 4); /* the model's error, --no-fail or not */
    if (!strstr(out, "\"over_budget\": null") || !strstr(out, "\"failed_types\": 1")) fail_msg("%s", out);
    write_text(TMP "/report/report.json", out);
    require_node_validators();
    if (run_command("node tests/tools/validator/validate_schema.mjs docs/report.schema.json " TMP "/report/report.json 2>&1", out,
                    sizeof out) != 0)
        fail_msg("%s", out);
    snprintf(cmd, sizeof cmd, "%s report catalog.toml 2>&1", exe);
    assert_int_equal(run_in(TMP "/report", cmd, out, sizeof out), 4);
    if (!strstr(out, "Roster: INCOMPLETE, 1 animal type failed to bake") || strstr(out, "% of the")) fail_msg("%s", out);
}

static void expect_refused(const char *args, const char *needle)
{
    char cmd[PATH_MAX + 256], out[4096];
    snprintf(cmd, sizeof cmd, "%s bake %s", exe, args);
    int rc = run_in(TMP "/flags", cmd, out, sizeof out);
    if (rc != 2 || !strstr(out, needle)) fail_msg("'%s': exit %d, expected 2 and '%s':\n%s", args, rc, needle, out);
}

/* The command line's bake options apply to every type of a catalog, count in what is up to
 * date, and those that mean nothing for a catalog are refused. */
static void test_catalog_applies_bake_flags(void **state)
{
    (void)state;
    static char out[16384];
    char cmd[PATH_MAX + 256], text[PATH_MAX + 64];
    assert_int_equal(system("rm -rf " TMP "/flags && mkdir -p " TMP "/flags/build/roster"), 0);
    snprintf(text, sizeof text, "[bake]\nfps = 30\n[animal.fish]\nmodel = \"%s\"\n", fish);
    write_text(TMP "/flags/catalog.toml", text);
    const char *flags = "--layout mat4 --precision float --zstd --format pal,exr --fps 24 --root-motion in-place "
                        "--exr-compression zip";
    snprintf(cmd, sizeof cmd, "%s bake catalog.toml %s --json", exe, flags);
    assert_int_equal(run_in(TMP "/flags", cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"baked\": 1"));
    cbpal_file f;
    char msg[256];
    assert_int_equal(cbpal_open(TMP "/flags/build/roster/fish.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    assert_int_equal(f.header.layout, CB_LAYOUT_MAT4);
    assert_int_equal(f.header.precision, CB_PRECISION_FLOAT);
    assert_int_equal(f.header.flags, CBPAL_FLAG_ZSTD | CBPAL_FLAG_IN_PLACE);
    assert_int_equal(f.header.rows, 24); /* the fish's 1 s swim loop at 24 fps */
    cbpal_close(&f);
    cb_exr_image img;
    cb_error err = {0};
    assert_int_equal(cb_exr_read(TMP "/flags/build/roster/fish.exr", &img, &err), CB_OK);
    assert_int_equal(img.precision, CB_PRECISION_FLOAT);
    assert_string_equal(img.layout, "mat4");
    assert_int_equal(img.rows, 24);
    cb_exr_image_free(&img);
    /* Same options: up to date. Without them: the catalog's own settings, baked again. */
    assert_int_equal(run_in(TMP "/flags", cmd, out, sizeof out), 0);
    if (!strstr(out, "\"up_to_date\": 1")) fail_msg("%s", out);
    snprintf(cmd, sizeof cmd, "%s bake catalog.toml --json", exe);
    assert_int_equal(run_in(TMP "/flags", cmd, out, sizeof out), 0);
    if (!strstr(out, "\"baked\": 1")) fail_msg("%s", out);
    assert_int_equal(cbpal_open(TMP "/flags/build/roster/fish.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    assert_int_equal(f.header.layout, CB_LAYOUT_QPOS);
    assert_int_equal(f.header.precision, CB_PRECISION_U16);
    assert_int_equal(f.header.rows, 30);
    assert_int_equal(f.header.blocks, 1);
    cbpal_close(&f);
    /* 60 rows of 26 texels under a 56-texel limit: two blocks of 30. */
    snprintf(cmd, sizeof cmd, "%s bake catalog.toml --fps 60 --max-texture-size 56 -q", exe);
    assert_int_equal(run_in(TMP "/flags", cmd, out, sizeof out), 0);
    assert_int_equal(cbpal_open(TMP "/flags/build/roster/fish.pal", CBPAL_VERIFY_CHECKSUM, &f, msg, sizeof msg), 0);
    assert_int_equal(f.header.rows, 60);
    assert_int_equal(f.header.blocks, 2);
    assert_int_equal(f.header.height, 30);
    cbpal_close(&f);
    expect_refused("catalog.toml --skin 0", "--skin is for single models");
    expect_refused("catalog.toml --speed-reference 2", "--speed-reference is for single models");
    /* --fps auto and its goal apply too (in place: the fish swims forward). */
    snprintf(cmd, sizeof cmd, "%s bake catalog.toml --fps auto --max-error 2 --max-fps 60 --root-motion in-place --json", exe);
    assert_int_equal(run_in(TMP "/flags", cmd, out, sizeof out), 0);
    if (!strstr(out, "\"baked\": 1") || !strstr(out, "error-bounded (max_error 2 mm/m)")) fail_msg("%s", out);
    expect_refused("catalog.toml --format exr --zstd", "--zstd compresses .pal payloads");
    expect_refused("catalog.toml --format exr --precision u16", "[animal.fish] would write u16 texels to EXR");
    expect_refused("catalog.toml --layout mat5", "--layout is mat4, affine or qpos");
    expect_refused("catalog.toml -o x.pal", "-o is for single models");
    /* And the catalog's options given to a single bake. */
    snprintf(cmd, sizeof cmd, "%s -o x.pal --depfile x.d", fish);
    expect_refused(cmd, "--depfile is for catalogs");
    snprintf(cmd, sizeof cmd, "%s -o x.exr --zstd", fish);
    expect_refused(cmd, "--zstd compresses .pal payloads");
}

/* Resource limits given with a catalog bound its bakes as they bound a single one. */
static void test_catalog_applies_limits(void **state)
{
    (void)state;
    char cmd[PATH_MAX + 256], text[PATH_MAX + 64], out[4096];
    assert_int_equal(system("rm -rf " TMP "/limits && mkdir -p " TMP "/limits/build/roster"), 0);
    snprintf(text, sizeof text, "[bake]\nfps = 30\n[animal.fish]\nmodel = \"%s\"\n", fish);
    write_text(TMP "/limits/catalog.toml", text);
    snprintf(cmd, sizeof cmd, "%s bake catalog.toml -q --max-joints 4", exe);
    int rc = run_in(TMP "/limits", cmd, out, sizeof out);
    if (rc != 4 || !strstr(out, "--max-joints")) fail_msg("exit %d: %s", rc, out); /* the fish has 13 joints */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_make_stays_red_until_the_model_is_fixed),
        cmocka_unit_test(test_make_with_delete_on_error),
        cmocka_unit_test(test_make_reruns_when_the_tool_changes),
        cmocka_unit_test(test_ninja_stays_red_until_the_model_is_fixed),
        cmocka_unit_test(test_default_output_folder_is_created),
        cmocka_unit_test(test_report_with_a_failed_type_passes_no_budget),
        cmocka_unit_test(test_catalog_applies_bake_flags),
        cmocka_unit_test(test_catalog_applies_limits),
    };
    return cmocka_run_group_tests_name("asset_ci", tests, setup, NULL);
}
