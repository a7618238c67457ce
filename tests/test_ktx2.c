/* test_ktx2.c - `crowdbake bake --format ktx2` read back by readers crowdbake did not write:
 * ktx-parse in Node and three.js's KTX2Loader in headless Chromium (tests/ktx2/check_ktx2.mjs)
 * must find the .pal's texels bit for bit and its clip table. A KTX2 with one texel byte
 * changed must fail the same checks; u16 is refused with the reason. */
#include "testutil.h"

#define TMP TEST_TMP "/ktx2"

static void require_ktx2_readers(void)
{
    FILE *f = fopen("tests/ktx2/node_modules/.package-lock.json", "r");
    if (!f) fail_msg("tests/ktx2: npm packages not installed (make test installs them; or: cd tests/ktx2 && npm ci)");
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
    return system(cmd);
}

static void test_readers_find_the_pal_texels_bit_for_bit(void **state)
{
    (void)state;
    require_ktx2_readers();
    static char out[1 << 16];
    int rc = run_command("node tests/ktx2/check_ktx2.mjs " TMP "/quadruped.ktx2 " TMP "/quadruped.pal " TMP "/fox.ktx2 " TMP
                         "/fox.pal 2>&1", out, sizeof out);
    printf("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "quadruped.ktx2: ktx-parse level 0 is bit-identical to the .pal texels (173840 bytes)"));
    assert_non_null(strstr(out, "fox.ktx2: three.js KTX2Loader makes a 96x159 RGBA FloatType texture"));
    assert_non_null(strstr(out, "quadruped.ktx2: three.js KTX2Loader makes a 82x265 RGBA HalfFloatType texture"));
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
    int rc = run_command("node tests/ktx2/check_ktx2.mjs " TMP "/broken.ktx2 " TMP "/quadruped.pal 2>&1", out, sizeof out);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_readers_find_the_pal_texels_bit_for_bit),
        cmocka_unit_test(test_a_changed_texel_is_caught),
        cmocka_unit_test(test_u16_is_refused_and_output_repeats),
    };
    return cmocka_run_group_tests_name("ktx2", tests, setup, NULL);
}
