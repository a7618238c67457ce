/* test_babylon.c - `crowdbake bake --format babylon` (.bvat.json) in real Babylon.js
 * (tests/runtimes/babylon/check_babylon.mjs, headless Chromium): Babylon's own VertexAnimationBaker bakes
 * Cow.glb loaded by @babylonjs/loaders at the file's row times, and the two must agree value by
 * value; thin instances drawn by BakedVertexAnimationManager from each must cover the same
 * pixels. Three broken files (the joints reversed, the handedness mirrored into the matrices,
 * rows without Babylon's extra bones and matrix) must fail those checks. The quadruped sample
 * without its skin's skeleton node (Babylon finds the joints' common ancestor) and with a walk and
 * a run that travel (a loop's closing row is its end pose) agrees too. u16 is refused; the same
 * bake twice gives the same bytes. A catalog with format "pal,babylon" writes each animal its
 * .bvat.json: its states' rows (in the file and the manifest) are Babylon's own bake of each
 * state's clip, and a missing, stale or torn file is baked again. */
#define _DEFAULT_SOURCE /* realpath */
#include "testutil.h"

#include <limits.h>

#define TMP TEST_TMP "/babylon"

static void require_babylon(void)
{
    FILE *f = fopen("tests/runtimes/babylon/node_modules/.package-lock.json", "r");
    if (!f) fail_msg("tests/runtimes/babylon: npm packages not installed (make test installs them; or: cd tests/runtimes/babylon && npm ci)");
    fclose(f);
}

static int setup(void **state)
{
    (void)state;
    char cmd[4096], cow[1024];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    if (system("rm -rf " TMP " && mkdir -p " TMP)) return -1;
    /* Root motion kept: Babylon's bake plays the clips as the file has them. */
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 --root-motion keep -o " TMP "/cow.bvat.json -q", crowdbake_exe(), cow);
    return system(cmd);
}

static void test_babylon_bakes_the_same_matrices_and_draws_the_same_herd(void **state)
{
    (void)state;
    require_babylon();
    char cmd[4096], cow[1024], out[16384];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "node tests/runtimes/babylon/check_babylon.mjs %s " TMP "/cow.bvat.json --controls 2>&1", cow);
    int rc = run_command(cmd, out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    /* Babylon's skeleton of Cow: 42 joints and 2 non-joint ancestors (RootNode, AnimalArmature). 751 rows: 753
     * while Attack_Headbutt and Idle_HitReact_Left were taken for loops (issue 45: they play once), 752 while
     * Gallop_Jump got one more key interval. Its 44 rows and closing row are left out of the comparison: its
     * closing key's mismatch is spread over the cycle, which Babylon plays as it is (test_loop_close checks
     * those rows against the reference matrices). */
    assert_non_null(strstr(out, "ok   cow.bvat.json: 180x751 texels, as Babylon's bake of 44 bones (+1) and 751 rows"));
    assert_non_null(strstr(out, "ok   cow.bvat.json: worst difference from Babylon's VertexAnimationBaker"));
    assert_non_null(strstr(out, "and 45 rows of loops closed over their key span"));
    assert_non_null(strstr(out, "ok   cow.bvat.json: thin instances through BakedVertexAnimationManager: 0 of"));
    assert_non_null(strstr(out, "ok   control reversed-bones fails"));
    assert_non_null(strstr(out, "ok   control mirrored-handedness fails"));
    assert_non_null(strstr(out, "ok   control joints-only fails"));
}

static void test_a_skin_without_skeleton_node_and_travelling_loops_agree(void **state)
{
    (void)state;
    require_babylon();
    char cmd[4096], quadruped[1024], out[16384];
    sample_path(quadruped, sizeof quadruped, "quadruped");
    snprintf(cmd, sizeof cmd, "node tests/runtimes/babylon/strip_skeleton.mjs %s " TMP "/quadruped.glb", quadruped);
    assert_int_equal(system(cmd), 0);
    snprintf(cmd, sizeof cmd, "%s bake " TMP "/quadruped.glb --fps 30 --root-motion keep -o " TMP "/quadruped.bvat.json -q",
             crowdbake_exe());
    assert_int_equal(system(cmd), 0);
    int rc = run_command("node tests/runtimes/babylon/check_babylon.mjs " TMP "/quadruped.glb " TMP "/quadruped.bvat.json --values-only 2>&1",
                         out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "ok   quadruped.bvat.json: 168x269 texels, as Babylon's bake of 41 bones (+1) and 269 rows"));
    assert_non_null(strstr(out, "ok   quadruped.bvat.json: worst difference from Babylon's VertexAnimationBaker"));
}

static void test_u16_is_refused_and_output_repeats(void **state)
{
    (void)state;
    char cmd[4096], cow[1024], out[4096];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/u16.bvat.json --precision u16 2>&1", crowdbake_exe(), cow);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_USAGE);
    assert_non_null(strstr(out, "Babylon.js's baked vertex animation data is Float32 matrices"));
    assert_null(fopen(TMP "/u16.bvat.json", "rb"));
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 --root-motion keep -o " TMP "/again --format babylon -q",
             crowdbake_exe(), cow);
    assert_int_equal(system(cmd), 0);
    size_t a, b;
    char *x = read_whole_file(TMP "/again.bvat.json", &a), *y = read_whole_file(TMP "/cow.bvat.json", &b);
    assert_true(a == b && memcmp(x, y, a) == 0);
    free(x), free(y);
}

#define CATALOG TMP "/catalog"

/* Cow in a catalog, baked as setup bakes it alone (30 fps, root motion kept), with states. */
static void write_cow_catalog(const char *format)
{
    char cow[1024], abs[4096], text[8192];
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    assert_non_null(realpath(cow, abs));
    snprintf(text, sizeof text,
             "[bake]\nfps = 30\nroot_motion = \"keep\"\nformat = \"%s\"\nout_dir = \"out\"\n\n"
             "[animal.cow]\nmodel = \"%s\"\n"
             "states = { wander = [\"walk\"], flee = [\"gallop\"], graze = [\"eating\"], die = [\"death\"] }\n"
             /* every clip, as the single bake it is compared with: the states' four and the eight the
              * bake's note names to keep with extra_clips */
             "extra_clips = [\"Attack_Headbutt\", \"Attack_Kick\", \"Gallop_Jump\", \"Idle\", \"Idle_2\", \"Idle_Headlow\", "
             "\"Idle_HitReact_Left\", \"Jump_toIdle\"]\n",
             format, abs);
    write_text(CATALOG "/catalog.toml", text);
}

/* The catalog baked again; its summary line (baked, up to date). */
static void bake_cow_catalog(char *out, size_t size)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s bake " CATALOG "/catalog.toml --depfile " CATALOG "/cow.d 2>&1 | grep '^crowdbake: [0-9]'",
             crowdbake_exe());
    assert_int_equal(run_command(cmd, out, size), 0);
}

/* The rows of a .bvat.json: its vertexData, up to "width". */
static bool same_rows(const char *a_path, const char *b_path)
{
    size_t a, b;
    char *x = read_whole_file(a_path, &a), *y = read_whole_file(b_path, &b);
    const char *xe = x ? strstr(x, "\"width\"") : NULL, *ye = y ? strstr(y, "\"width\"") : NULL;
    bool same = xe && ye && xe - x == ye - y && memcmp(x, y, (size_t)(xe - x)) == 0;
    free(x), free(y);
    return same;
}

static void test_a_catalog_writes_each_animal_its_bvat_json_with_its_states(void **state)
{
    (void)state;
    require_babylon();
    char cmd[4096], cow[1024], out[16384];
    assert_int_equal(system("rm -rf " CATALOG " && mkdir -p " CATALOG), 0);
    write_cow_catalog("pal,babylon");
    bake_cow_catalog(out, sizeof out);
    assert_non_null(strstr(out, "crowdbake: 1 baked, 0 up to date"));
    /* The rows are the single bake's (which Babylon's bake matches, above). */
    assert_true(same_rows(CATALOG "/out/cow.bvat.json", TMP "/cow.bvat.json"));
    shared_path(cow, sizeof cow, "assets/quaternius-cow/Cow.glb");
    snprintf(cmd, sizeof cmd, "node tests/runtimes/babylon/check_babylon.mjs %s " CATALOG "/out/cow.bvat.json --values-only "
             "--roster " CATALOG "/out/roster.json --type cow 2>&1", cow);
    int rc = run_command(cmd, out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "ok   cow.bvat.json: 180x751 texels, as Babylon's bake of 44 bones (+1) and 751 rows"));
    static const char *const states[] = {"wander", "flee", "graze", "die"};
    for (size_t i = 0; i < COUNT_OF(states); ++i) {
        char agree[128], baked[128];
        snprintf(agree, sizeof agree, "ok   state %s: the file's crowdbake.states and the manifest agree", states[i]);
        snprintf(baked, sizeof baked, "ok   state %s: rows ", states[i]);
        assert_non_null(strstr(out, agree));
        assert_non_null(strstr(out, baked));
    }
    size_t n;
    char *dep = read_whole_file(CATALOG "/cow.d", &n), *manifest = read_whole_file(CATALOG "/out/roster.json", &n);
    assert_non_null(strstr(dep, CATALOG "/out/cow.bvat.json:"));
    assert_non_null(strstr(manifest, "\"palette_babylon\": \"cow.bvat.json\""));
    free(dep), free(manifest);
    assert_int_equal(run_command("node tests/tools/validator/validate_schema.mjs docs/roster.schema.json " CATALOG
                                 "/out/roster.json 2>&1", out, sizeof out), 0);
}

static void test_a_catalogs_bvat_json_missing_stale_or_torn_is_baked_again(void **state)
{
    (void)state;
    char out[4096], cmd[4096];
    assert_int_equal(system("rm -rf " CATALOG " && mkdir -p " CATALOG), 0);
    write_cow_catalog("pal,babylon");
    bake_cow_catalog(out, sizeof out);
    bake_cow_catalog(out, sizeof out);
    assert_non_null(strstr(out, "crowdbake: 0 baked, 1 up to date"));
    static const char *const spoil[] = {
        "rm " CATALOG "/out/cow.bvat.json",                                   /* missing */
        "cp " TMP "/cow.bvat.json " CATALOG "/out/cow.bvat.json",             /* another bake's: same rows, other input */
        "head -c 100000 " TMP "/cow.bvat.json > " CATALOG "/out/cow.bvat.json", /* torn */
    };
    for (size_t i = 0; i < COUNT_OF(spoil); ++i) {
        assert_int_equal(system(spoil[i]), 0);
        bake_cow_catalog(out, sizeof out);
        assert_non_null(strstr(out, "crowdbake: 1 baked, 0 up to date"));
        size_t n;
        char *file = read_whole_file(CATALOG "/out/cow.bvat.json", &n);
        assert_non_null(strstr(file, "\"states\": {"));
        free(file);
    }
    /* Babylon alone is not a catalog's: the manifest's palette is a .pal's, an .exr's or a .ktx2's. */
    write_cow_catalog("babylon");
    snprintf(cmd, sizeof cmd, "%s bake " CATALOG "/catalog.toml -q 2>&1", crowdbake_exe());
    assert_int_not_equal(run_command(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "catalog.toml:4:"));
    assert_non_null(strstr(out, "with \"babylon\" beside any"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_babylon_bakes_the_same_matrices_and_draws_the_same_herd),
        cmocka_unit_test(test_a_skin_without_skeleton_node_and_travelling_loops_agree),
        cmocka_unit_test(test_u16_is_refused_and_output_repeats),
        cmocka_unit_test(test_a_catalog_writes_each_animal_its_bvat_json_with_its_states),
        cmocka_unit_test(test_a_catalogs_bvat_json_missing_stale_or_torn_is_baked_again),
    };
    return cmocka_run_group_tests_name("babylon", tests, setup, NULL);
}
