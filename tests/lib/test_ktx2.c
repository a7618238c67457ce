/* test_ktx2.c - `crowdbake bake --format ktx2` read back by readers crowdbake did not write:
 * ktx-parse in Node and three.js's KTX2Loader in headless Chromium (tests/tools/ktx2/check_ktx2.mjs)
 * must find the .pal's texels bit for bit and its clip table. A KTX2 with one texel byte
 * changed must fail the same checks; u16 is refused with the reason. crowdbake's own `inspect`
 * and `verify` read the .ktx2 as they read the .pal and .exr of the same bake (same clip table,
 * same errors), and a truncated or corrupted .ktx2 is a one-line error. */
#include "testutil.h"

#define TMP TEST_TMP "/ktx2"

static void require_ktx2_readers(void)
{
    FILE *f = fopen("tests/tools/ktx2/node_modules/.package-lock.json", "r");
    if (!f) fail_msg("tests/tools/ktx2: npm packages not installed (make test installs them; or: cd tests/tools/ktx2 && npm ci)");
    fclose(f);
}

static int setup(void **state)
{
    (void)state;
    char cmd[4096], quadruped[1024], fox[1024];
    sample_path(quadruped, sizeof quadruped, "quadruped");
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    if (system("rm -rf " TMP " && mkdir -p " TMP)) return -1;
    /* The same bake as .pal and .ktx2: half on the sample (with relative positions), float on Fox. */
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/quadruped --format pal,ktx2 --precision half -q", crowdbake_exe(),
             quadruped);
    if (system(cmd)) return -1;
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/fox --format pal,ktx2 --precision float --layout mat4 -q",
             crowdbake_exe(), fox);
    if (system(cmd)) return -1;
    /* --zstd: the KTX2 level supercompressed (Zstandard, as toktx --zcmp), beside a plain .pal of the same bake. */
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/foxz.ktx2 --precision half --zstd -q && %s bake %s --fps 30 -o "
             TMP "/foxz.pal --precision half -q", crowdbake_exe(), fox, crowdbake_exe(), fox);
    if (system(cmd)) return -1;
    /* In place (a root velocity per clip), qpos/half: every clip field verify reads. */
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/fox_in_place --format pal,exr,ktx2 --precision half "
             "--root-motion in-place -q", crowdbake_exe(), fox);
    return system(cmd);
}

static void test_readers_find_the_pal_texels_bit_for_bit(void **state)
{
    (void)state;
    require_ktx2_readers();
    static char out[1 << 16];
    int rc = run_command("node tests/tools/ktx2/check_ktx2.mjs " TMP "/quadruped.ktx2 " TMP "/quadruped.pal " TMP "/fox.ktx2 " TMP
                         "/fox.pal " TMP "/foxz.ktx2 " TMP "/foxz.pal 2>&1", out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "quadruped.ktx2: ktx-parse level 0 is bit-identical to the .pal texels (173840 bytes)"));
    assert_non_null(strstr(out, "fox.ktx2: three.js KTX2Loader makes a 96x159 RGBA FloatType texture"));
    assert_non_null(strstr(out, "quadruped.ktx2: three.js KTX2Loader makes a 82x265 RGBA HalfFloatType texture"));
    /* zstd: ktx-parse and the zstd command, then three.js's KTX2Loader (its own zstd decoder), find the texels */
    assert_non_null(strstr(out, "ok   foxz.ktx2: zstd -d reads its level"));
    assert_non_null(strstr(out, "ok   foxz.ktx2: ktx-parse level 0 is bit-identical to the .pal texels"));
    assert_non_null(strstr(out, "ok   foxz.ktx2: the three.js texture's data is bit-identical to the .pal texels"));
}

static void test_a_changed_texel_is_caught(void **state)
{
    (void)state;
    require_ktx2_readers();
    size_t size;
    unsigned char *d = (unsigned char *)read_whole_file(TMP "/quadruped.ktx2", &size);
    uint64_t level = 0; /* the level index: byteOffset at byte 80 */
    for (int i = 7; i >= 0; --i) level = level << 8 | d[80 + i];
    assert_true(level > 0 && level + 1000 < size);
    d[level + 1000] ^= 0x01; /* one bit of one texel */
    FILE *f = fopen(TMP "/broken.ktx2", "wb");
    fwrite(d, 1, size, f);
    fclose(f);
    free(d);
    static char out[1 << 16];
    int rc = run_command("node tests/tools/ktx2/check_ktx2.mjs " TMP "/broken.ktx2 " TMP "/quadruped.pal 2>&1", out, sizeof out);
    printf("%s", out);
    assert_int_not_equal(rc, 0);
    assert_non_null(strstr(out, "FAIL broken.ktx2: ktx-parse level 0 is bit-identical to the .pal texels (173840 bytes; "
                                "first difference at byte 1000"));
    assert_non_null(strstr(out, "FAIL broken.ktx2: the three.js texture's data is bit-identical to the .pal texels (first "
                                "difference at byte 1000)"));
}

static void test_u16_is_refused_and_output_repeats(void **state)
{
    (void)state;
    char cmd[4096], quadruped[1024], out[4096];
    sample_path(quadruped, sizeof quadruped, "quadruped");
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/u16.ktx2 --precision u16 2>&1", crowdbake_exe(), quadruped);
    assert_int_equal(run_command(cmd, out, sizeof out), EXIT_USAGE);
    assert_non_null(strstr(out, "KTX2 palettes hold half or float texels"));
    assert_non_null(strstr(out, "RGBA16UI"));
    assert_null(fopen(TMP "/u16.ktx2", "rb"));
    /* The same bake twice gives the same bytes. */
    snprintf(cmd, sizeof cmd, "%s bake %s --fps 30 -o " TMP "/again.ktx2 --precision half -q", crowdbake_exe(), quadruped);
    assert_int_equal(system(cmd), 0);
    size_t a, b;
    char *x = read_whole_file(TMP "/again.ktx2", &a), *y = read_whole_file(TMP "/quadruped.ktx2", &b);
    assert_true(a == b && memcmp(x, y, a) == 0);
    free(x), free(y);
}

/* With no --precision, KTX2 takes the .pal's: half for the .pal's default u16 (RGBA16UI would be
 * refused by the loaders), said in a note; --precision float overrides it. */
static void test_ktx2_defaults_to_half_beside_a_u16_pal(void **state)
{
    (void)state;
    require_ktx2_readers();
    char quadruped[1024];
    static char out[1 << 16];
    sample_path(quadruped, sizeof quadruped, "quadruped");
    assert_int_equal(run(out, sizeof out, "%s bake %s --fps 30 -o " TMP "/dflt --format pal,ktx2 --bone-space global 2>&1", crowdbake_exe(), quadruped), 0);
    printf("%s", out);
    assert_non_null(strstr(out, "note: " TMP "/dflt.ktx2 is half (RGBA16F), the float format as wide as the .pal's default u16"));
    assert_non_null(strstr(out, "RGBA16UI, an integer format three.js's KTX2Loader and most engines refuse; --precision float"));
    assert_int_equal(run(out, sizeof out, "%s inspect " TMP "/dflt.pal", crowdbake_exe()), 0);
    assert_non_null(strstr(out, "u16"));
    /* the same texels as the explicit half bake, read back by ktx-parse and three.js */
    assert_int_equal(run(out, sizeof out, "node tests/tools/ktx2/check_ktx2.mjs " TMP "/dflt.ktx2 " TMP "/quadruped.pal 2>&1"), 0);
    printf("%s", out);
    assert_non_null(strstr(out, "ok   dflt.ktx2: vkFormat 97 for half texels"));
    assert_non_null(strstr(out, "ok   dflt.ktx2: ktx-parse level 0 is bit-identical to the .pal texels (173840 bytes)"));
    assert_non_null(strstr(out, "dflt.ktx2: three.js KTX2Loader makes a 82x265 RGBA HalfFloatType texture"));
    /* overridden: float texels, no note */
    assert_int_equal(run(out, sizeof out, "%s bake %s --fps 30 -o " TMP "/fl --format pal,ktx2 --precision float --bone-space global 2>&1",
                         crowdbake_exe(), quadruped), 0);
    assert_null(strstr(out, "RGBA16F"));
    assert_int_equal(run(out, sizeof out, "node tests/tools/ktx2/check_ktx2.mjs " TMP "/fl.ktx2 " TMP "/fl.pal 2>&1"), 0);
    printf("%s", out);
    assert_non_null(strstr(out, "ok   fl.ktx2: vkFormat 109 for float texels"));
    assert_non_null(strstr(out, "RGBA FloatType texture"));
}

/* The output of `crowdbake ARGS` (stdout and stderr) from `from` on, into out; its exit code. */
static int crowdbake_from(const char *args, const char *from, char *out, size_t size)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "%s %s 2>&1", crowdbake_exe(), args);
    int rc = run_command(cmd, out, size);
    const char *at = strstr(out, from);
    if (!at) fail_msg("'%s' printed no '%s':\n%s", args, from, out);
    memmove(out, at, strlen(at) + 1);
    return rc;
}

static void same_from(const char *args_a, const char *args_b, const char *from)
{
    static char a[1 << 17], b[1 << 17];
    assert_int_equal(crowdbake_from(args_a, from, a, sizeof a), 0);
    assert_int_equal(crowdbake_from(args_b, from, b, sizeof b), 0);
    assert_string_equal(a, b);
}

static void test_inspect_reads_the_ktx2_as_the_pal(void **state)
{
    (void)state;
    static char out[1 << 16];
    /* Fox's skin has 24 joints and the clips Survey, Walk and Run (the glTF's); the .pal is read
     * by crowdbake_pal.h, the .ktx2 by cb_ktx2_read_palette: their tables must agree. */
    assert_int_equal(crowdbake_from("inspect " TMP "/fox.ktx2", TMP, out, sizeof out), 0);
    assert_non_null(strstr(out, "fox.ktx2: KTX2 palette, mat4/float, 24 bones x 4 texels"));
    assert_non_null(strstr(out, "  Survey ") && strstr(out, "  Walk ") && strstr(out, "  Run "));
    for (int i = 0; i < 2; ++i) {
        const char *name = i ? "fox_in_place" : "fox";
        char a[512], b[512];
        snprintf(a, sizeof a, "inspect " TMP "/%s.pal", name), snprintf(b, sizeof b, "inspect " TMP "/%s.ktx2", name);
        same_from(a, b, "  clip ");
        snprintf(a, sizeof a, "inspect " TMP "/%s.pal --json", name), snprintf(b, sizeof b, "inspect " TMP "/%s.ktx2 --json", name);
        same_from(a, b, "\"clips\"");
        snprintf(a, sizeof a, "inspect " TMP "/%s.pal --clip walk --frame 7", name);
        snprintf(b, sizeof b, "inspect " TMP "/%s.ktx2 --clip walk --frame 7", name);
        same_from(a, b, "\"clips\"");
    }
    assert_int_equal(crowdbake_from("inspect " TMP "/fox_in_place.ktx2", "root velocity removed", out, sizeof out), 0);
}

static void test_verify_reads_the_ktx2_as_the_exr(void **state)
{
    (void)state;
    char fox[1024], a[2048], b[2048];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    snprintf(a, sizeof a, "verify %s " TMP "/fox_in_place.exr --random 8 --json", fox);
    snprintf(b, sizeof b, "verify %s " TMP "/fox_in_place.ktx2 --random 8 --json", fox);
    same_from(a, b, "\"model_height\"");
    snprintf(a, sizeof a, "verify %s " TMP "/fox.pal --random 8", fox);
    snprintf(b, sizeof b, "verify %s " TMP "/fox.ktx2 --random 8", fox);
    same_from(a, b, "  clip ");
    /* The same verdict: over a goal no half palette meets, exit 6 with the same reason. */
    static char x[1 << 16], y[1 << 16];
    snprintf(a, sizeof a, "verify %s " TMP "/fox_in_place.exr --random 8 --max-error 0.001 -q", fox);
    snprintf(b, sizeof b, "verify %s " TMP "/fox_in_place.ktx2 --random 8 --max-error 0.001 -q", fox);
    assert_int_equal(crowdbake_from(a, "worst error", x, sizeof x), EXIT_VERIFY);
    assert_int_equal(crowdbake_from(b, "worst error", y, sizeof y), EXIT_VERIFY);
    assert_string_equal(x, y);
}

static void write_bytes(const char *path, const unsigned char *d, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fwrite(d, 1, n, f);
    fclose(f);
}

/* One line on stderr naming the file, exit 4 (invalid input), from inspect and from verify. */
static void refused_in_one_line(const char *path)
{
    char fox[1024], cmd[4096];
    static char out[1 << 16];
    shared_path(fox, sizeof fox, "assets/fox-bevy/Fox.glb");
    for (int i = 0; i < 2; ++i) {
        if (i) snprintf(cmd, sizeof cmd, "%s verify %s %s 2>&1", crowdbake_exe(), fox, path);
        else snprintf(cmd, sizeof cmd, "%s inspect %s 2>&1", crowdbake_exe(), path);
        int rc = run_command(cmd, out, sizeof out);
        char *nl = strchr(out, '\n');
        if (rc != EXIT_INPUT || strncmp(out, "crowdbake: ", 11) || !strstr(out, path) || !nl || nl[1])
            fail_msg("%s: exit %d, not 4 with one line naming the file:\n%s", cmd, rc, out);
    }
}

static void test_a_broken_ktx2_is_one_line(void **state)
{
    (void)state;
    size_t size;
    unsigned char *d = (unsigned char *)read_whole_file(TMP "/fox_in_place.ktx2", &size);
    assert_non_null(d);
    /* Cut short: in the header, the level index, the key/value data, the texels. */
    const size_t cuts[] = {12, 40, 90, 200, 600, size / 2, size - 1};
    for (size_t i = 0; i < COUNT_OF(cuts); ++i) {
        write_bytes(TMP "/cut.ktx2", d, cuts[i]);
        refused_in_one_line(TMP "/cut.ktx2");
    }
    /* Offsets and lengths that point outside the file, and tables that disagree. */
    const size_t fields[] = {12 /* vkFormat */, 20 /* width */, 60 /* kvd length */, 84 /* level offset, high half */};
    for (size_t i = 0; i < COUNT_OF(fields); ++i) {
        unsigned char *e = malloc(size);
        memcpy(e, d, size);
        e[fields[i] + 3] ^= 0x40;
        write_bytes(TMP "/bad.ktx2", e, size);
        refused_in_one_line(TMP "/bad.ktx2");
        free(e);
    }
    char *rows = NULL; /* in the key/value data: before the texels, a C string search finds it */
    for (size_t i = 0; !rows && i + 8 < size; ++i)
        if (memcmp(d + i, "\"rows\": ", 8) == 0) rows = (char *)d + i;
    assert_non_null(rows);
    rows[8] = '9'; /* more rows than the texture holds */
    write_bytes(TMP "/bad.ktx2", d, size);
    refused_in_one_line(TMP "/bad.ktx2");
    free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_readers_find_the_pal_texels_bit_for_bit),
        cmocka_unit_test(test_a_changed_texel_is_caught),
        cmocka_unit_test(test_u16_is_refused_and_output_repeats),
        cmocka_unit_test(test_ktx2_defaults_to_half_beside_a_u16_pal),
        cmocka_unit_test(test_inspect_reads_the_ktx2_as_the_pal),
        cmocka_unit_test(test_verify_reads_the_ktx2_as_the_exr),
        cmocka_unit_test(test_a_broken_ktx2_is_one_line),
    };
    return cmocka_run_group_tests_name("ktx2", tests, setup, NULL);
}
