/* test_error_budget.c - the error budget is a promise (issue 33, items 3 and 4), through the
 * command as a user runs it: a bake without --fps meets 1 mm/m on Cow, measured independently
 * by `crowdbake verify` (exact float64 skinning from the glTF at every row, mid-row and 64
 * random times), at no more than 1.5x the bytes of a fixed 30 fps bake; an unmeetable
 * --max-error (a budget stated, not the default's goal: issue 43) fails with exit 6, writes nothing (no temporary left either) and names every
 * clip; --allow-over-budget writes it with a warning per clip, in text and --json; a fixed
 * --fps with --max-error is checked; a palette mixes fitted and sampled clips (inspect says
 * which); and the catalog forms of each. */
#define _DEFAULT_SOURCE /* realpath */
#include "testutil.h"

#include <dirent.h>
#include <limits.h>
#include <sys/stat.h>

#define OUT_DIR TEST_TMP "/budget"

static char cow[1024];

static int setup(void **state)
{
    (void)state;
    char rel[1024];
    shared_path(rel, sizeof rel, "assets/quaternius-cow/Cow.glb");
    if (!realpath(rel, cow)) return -1; /* catalogs resolve paths against their own directory */
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "rm -rf %s && mkdir -p %s", OUT_DIR, OUT_DIR);
    return system(cmd) == 0 ? 0 : -1;
}

static long file_bytes(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

/* Files in dir whose name contains `part` (a temporary is ".NAME.tmp.XXXXXX"). */
static int files_matching(const char *dir, const char *part)
{
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));) n += strstr(e->d_name, part) != NULL;
    if (d) closedir(d);
    return n;
}

static void test_default_bake_meets_1mm_within_the_bytes_of_30_fps(void **state)
{
    (void)state;
    static char out[1 << 16];
    int rc = run(out, sizeof out, "%s bake %s -o %s/cow.pal 2>&1", crowdbake_exe(), cow, OUT_DIR);
    if (rc != 0) fail_msg("%s", out);
    rc = run(out, sizeof out, "%s bake %s -o %s/cow30.pal --fps 30 -q 2>&1", crowdbake_exe(), cow, OUT_DIR);
    assert_int_equal(rc, 0);
    char pal[512], pal30[512], global[512];
    snprintf(pal, sizeof pal, "%s/cow.pal", OUT_DIR), snprintf(pal30, sizeof pal30, "%s/cow30.pal", OUT_DIR);
    snprintf(global, sizeof global, "%s/cow-global.pal", OUT_DIR);
    long bytes = file_bytes(pal), bytes30 = file_bytes(pal30);
    printf("  default %ld bytes, fixed 30 fps %ld (%.2fx)\n", bytes, bytes30, (double)bytes / bytes30);
    assert_true(bytes <= bytes30); /* issue 43 item 1: local rows, 0.80x the texels */
    /* Independently: verify skins every clip exactly and compares; exit 6 if any is over 1 mm/m. */
    rc = run(out, sizeof out, "%s verify %s %s --max-error 1 2>&1", crowdbake_exe(), cow, pal);
    if (rc != 0) fail_msg("default bake over 1 mm/m: %s", out);
    rc = run(out, sizeof out, "%s verify %s %s --max-error 1 2>&1", crowdbake_exe(), cow, pal30);
    assert_int_equal(rc, EXIT_VERIFY); /* off the keys' 24 fps grid, 30 fps rows miss it */
    /* Global rows: within 1 mm/m too, in more bytes (at most 1.5x), fitted and sampled clips mixed, said per clip. */
    rc = run(out, sizeof out, "%s bake %s -o %s --bone-space global -q 2>&1", crowdbake_exe(), cow, global);
    assert_int_equal(rc, 0);
    long bytes_global = file_bytes(global);
    printf("  global rows %ld bytes (%.2fx)\n", bytes_global, (double)bytes_global / bytes30);
    assert_true(bytes_global > bytes30 && bytes_global <= 1.5 * bytes30);
    rc = run(out, sizeof out, "%s verify %s %s --max-error 1 2>&1", crowdbake_exe(), cow, global);
    if (rc != 0) fail_msg("global bake over 1 mm/m: %s", out);
    rc = run(out, sizeof out, "%s inspect %s 2>&1", crowdbake_exe(), global);
    assert_int_equal(rc, 0);
    if (!strstr(out, " fitted ") || !strstr(out, " sampled ")) fail_msg("%s", out);
    rc = run(out, sizeof out, "%s inspect %s --json 2>&1", crowdbake_exe(), global);
    assert_non_null(strstr(out, "\"fitted_rows\": true"));
    assert_non_null(strstr(out, "\"fitted_rows\": false"));
}

/* The Cow's 12 clips, each named in a message. */
static void expect_every_clip_named(const char *out)
{
    static const char *const clips[] = {"Attack_Headbutt", "Attack_Kick", "Death", "Eating", "'AnimalArmature|Gallop'",
                                        "Gallop_Jump", "'AnimalArmature|Idle'", "Idle_2", "Idle_Headlow",
                                        "Idle_HitReact_Left", "Jump_toIdle", "'AnimalArmature|Walk'"};
    for (size_t i = 0; i < COUNT_OF(clips); ++i)
        if (!strstr(out, clips[i])) fail_msg("clip %s not named in:\n%s", clips[i], out);
}

static void test_unmeetable_budget_fails_and_writes_nothing(void **state)
{
    (void)state;
    static char out[1 << 16];
    int rc = run(out, sizeof out, "%s bake %s -o %s/tight.pal --max-error 0.01 --bone-space global 2>&1", crowdbake_exe(), cow, OUT_DIR);
    assert_int_equal(rc, EXIT_VERIFY);
    char path[512];
    snprintf(path, sizeof path, "%s/tight.pal", OUT_DIR);
    assert_int_equal(file_bytes(path), -1);
    assert_int_equal(files_matching(OUT_DIR, "tight"), 0); /* no temporary left */
    expect_every_clip_named(out);
    /* Each line: the error reached, the rate it stopped at, and what would meet it. */
    if (!strstr(out, "reaches ") || !strstr(out, "at 120 fps") || !strstr(out, "over max_error 0.01") ||
        !strstr(out, "--max-error 0.") || !strstr(out, "nothing was written"))
        fail_msg("%s", out);
    /* Reachable by raising the cap: the line says which rate meets it. The default budget is a
     * goal (written, a warning per clip: issue 43); stated, a promise. */
    rc = run(out, sizeof out, "%s bake %s -o %s/capped.pal --max-fps 24 --bone-space global 2>&1", crowdbake_exe(), cow, OUT_DIR);
    if (rc != 0 || !strstr(out, "warning: clip") || !strstr(out, "the default max_error is a goal")) fail_msg("%s", out);
    snprintf(path, sizeof path, "%s/capped.pal", OUT_DIR);
    assert_true(file_bytes(path) > 0);
    rc = run(out, sizeof out, "%s bake %s -o %s/capped1.pal --max-fps 24 --max-error 1 --bone-space global 2>&1", crowdbake_exe(), cow, OUT_DIR);
    assert_int_equal(rc, EXIT_VERIFY);
    if (!strstr(out, "it meets it at ") || !strstr(out, "(--max-fps ")) fail_msg("%s", out);
    snprintf(path, sizeof path, "%s/capped1.pal", OUT_DIR);
    assert_int_equal(file_bytes(path), -1);
    /* A fixed rate with a budget is checked, not raised. */
    rc = run(out, sizeof out, "%s bake %s -o %s/fixed.pal --fps 30 --max-error 1 2>&1", crowdbake_exe(), cow, OUT_DIR);
    assert_int_equal(rc, EXIT_VERIFY);
    if (!strstr(out, "at 30 fps") || !strstr(out, "its rate is fixed")) fail_msg("%s", out);
    /* A loop that travels with its root motion kept (by hand: the default bakes travelling loops in
     * place): no rate helps, and the line says what does.
     * The sample quadruped's walk is generated travelling 1.2 units a 1 s loop. */
    char quadruped[1024];
    sample_path(quadruped, sizeof quadruped, "quadruped");
    rc = run(out, sizeof out, "%s bake %s -o %s/travel.pal --max-error 1 --root-motion keep 2>&1", crowdbake_exe(),
             quadruped, OUT_DIR);
    assert_int_equal(rc, EXIT_VERIFY);
    if (!strstr(out, "clip 'walk' reaches ") || !strstr(out, "its root travels 1.2 units a loop") ||
        !strstr(out, "(--root-motion in-place)"))
        fail_msg("%s", out);
    rc = run(out, sizeof out, "%s bake %s -o %s/travel.pal --root-motion in-place 2>&1", crowdbake_exe(), quadruped, OUT_DIR);
    assert_int_equal(rc, 0);
}

static void test_allow_over_budget_writes_with_warnings(void **state)
{
    (void)state;
    static char out[1 << 16];
    int rc = run(out, sizeof out, "%s bake %s -o %s/over.pal --max-error 0.01 --allow-over-budget 2>&1", crowdbake_exe(),
                 cow, OUT_DIR);
    if (rc != 0) fail_msg("%s", out);
    char path[512];
    snprintf(path, sizeof path, "%s/over.pal", OUT_DIR);
    assert_true(file_bytes(path) > 0);
    expect_every_clip_named(out);
    assert_non_null(strstr(out, "warning: clip"));
    assert_non_null(strstr(out, "written anyway"));
    rc = run(out, sizeof out, "%s bake %s -o %s/over.pal --max-error 0.01 --allow-over-budget --json 2>/dev/null",
             crowdbake_exe(), cow, OUT_DIR);
    assert_int_equal(rc, 0);
    const char *over = strstr(out, "\"over_budget\": [");
    assert_non_null(over);
    assert_non_null(strstr(over, "\"max_error_mm_per_m\": 0.01"));
    assert_non_null(strstr(out, "\"why\": "));
}

static void write_catalog(const char *name, const char *bake_keys)
{
    char path[512], text[2048];
    snprintf(path, sizeof path, "%s/%s.toml", OUT_DIR, name);
    snprintf(text, sizeof text, "[bake]\nout_dir = \"%s-out\"\n%s\n[animal.cow]\nmodel = \"%s\"\n", name, bake_keys, cow);
    write_text(path, text);
}

static void test_catalog_forms(void **state)
{
    (void)state;
    static char out[1 << 16];
    char path[512];
    /* Unmeetable: the type fails, exit 6, no palette, every clip named in the log. */
    write_catalog("tight", "max_error = 0.01");
    int rc = run(out, sizeof out, "%s bake %s/tight.toml -j 1 2>&1", crowdbake_exe(), OUT_DIR);
    assert_int_equal(rc, EXIT_VERIFY);
    snprintf(path, sizeof path, "%s/tight-out/cow.pal", OUT_DIR);
    assert_int_equal(file_bytes(path), -1);
    expect_every_clip_named(out);
    if (!strstr(out, "FAILED") || !strstr(out, "max_error = 0.")) fail_msg("%s", out);
    /* The opt-out: written, with a warning per clip. */
    write_catalog("over", "max_error = 0.01\nallow_over_budget = true");
    rc = run(out, sizeof out, "%s bake %s/over.toml -j 1 2>&1", crowdbake_exe(), OUT_DIR);
    if (rc != 0) fail_msg("%s", out);
    snprintf(path, sizeof path, "%s/over-out/cow.pal", OUT_DIR);
    assert_true(file_bytes(path) > 0);
    expect_every_clip_named(out);
    assert_non_null(strstr(out, "warning: clip"));
    /* The default (no fps): error-bounded, verified within 1 mm/m. */
    write_catalog("plain", "");
    rc = run(out, sizeof out, "%s bake %s/plain.toml -j 1 2>&1", crowdbake_exe(), OUT_DIR);
    if (rc != 0) fail_msg("%s", out);
    assert_non_null(strstr(out, "error-bounded (max_error 1 mm/m)"));
    snprintf(path, sizeof path, "%s/plain-out/cow.pal", OUT_DIR);
    rc = run(out, sizeof out, "%s verify %s %s --max-error 1 2>&1", crowdbake_exe(), cow, path);
    if (rc != 0) fail_msg("%s", out);
    /* A fixed fps with max_error: checked. */
    write_catalog("fixed", "fps = 30\nmax_error = 1");
    rc = run(out, sizeof out, "%s bake %s/fixed.toml -j 1 2>&1", crowdbake_exe(), OUT_DIR);
    assert_int_equal(rc, EXIT_VERIFY);
    if (!strstr(out, "its rate is fixed (fps = 30)")) fail_msg("%s", out);
    /* The command line's --max-error over every animal (no clip says otherwise): the catalog's
     * fixed fps, unchecked alone, is then checked against it. */
    write_catalog("cli", "fps = 30");
    rc = run(out, sizeof out, "%s bake %s/cli.toml -j 1 --max-error 1 2>&1", crowdbake_exe(), OUT_DIR);
    assert_int_equal(rc, EXIT_VERIFY);
    if (!strstr(out, "over max_error 1;")) fail_msg("%s", out);
    rc = run(out, sizeof out, "%s bake %s/cli.toml -j 1 2>&1", crowdbake_exe(), OUT_DIR);
    if (rc != 0) fail_msg("%s", out);
    /* Baked unchecked, then asked for the check (the default's value, 1): not up to date. */
    rc = run(out, sizeof out, "%s bake %s/cli.toml -j 1 --max-error 1 2>&1", crowdbake_exe(), OUT_DIR);
    assert_int_equal(rc, EXIT_VERIFY);
}

/* A fixed fps held to no budget still says when it misses the default max_error, and how to meet
 * it: leaving fps out, which baked with the budget enforced meets it as `verify` measures it
 * (float64 skinning from the glTF). The catalog's log says it too. */
static void test_a_fixed_fps_over_the_budget_warns_and_says_how_to_meet_it(void **state)
{
    (void)state;
    static char out[1 << 16];
    char pal[512], path[512];
    snprintf(pal, sizeof pal, "%s/fixed15.pal", OUT_DIR);
    int rc = run(out, sizeof out, "%s bake %s --clip idle --fps 15 -o %s 2>&1", crowdbake_exe(), cow, pal);
    if (rc != 0) fail_msg("%s", out);
    const char *w = strstr(out, "warning: clip 'AnimalArmature|Idle' reaches ");
    if (!w || !strstr(w, "at its fixed 15 fps (command line), over max_error 1 mm/m, which a fixed fps is not held to; "
                         "leave fps out to have the rate chosen within max_error"))
        fail_msg("%s", out);
    rc = run(out, sizeof out, "%s bake %s --clip idle --max-error 1 -o %s 2>&1", crowdbake_exe(), cow, pal);
    if (rc != 0 || strstr(out, "warning")) fail_msg("fps left out: %s", out);
    rc = run(out, sizeof out, "%s verify %s %s --max-error 1 2>&1", crowdbake_exe(), cow, pal);
    if (rc != 0) fail_msg("%s", out);
    write_catalog("fixed15", "fps = 15");
    rc = run(out, sizeof out, "%s bake %s/fixed15.toml -j 1 2>&1", crowdbake_exe(), OUT_DIR);
    if (rc != 0 || !strstr(out, "warning: clip 'AnimalArmature|Idle' reaches ") || !strstr(out, "(catalog [bake])"))
        fail_msg("%s", out);
    snprintf(path, sizeof path, "%s/fixed15-out/cow.pal", OUT_DIR);
    assert_true(file_bytes(path) > 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_bake_meets_1mm_within_the_bytes_of_30_fps),
        cmocka_unit_test(test_unmeetable_budget_fails_and_writes_nothing),
        cmocka_unit_test(test_allow_over_budget_writes_with_warnings),
        cmocka_unit_test(test_catalog_forms),
        cmocka_unit_test(test_a_fixed_fps_over_the_budget_warns_and_says_how_to_meet_it),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
