/* standalone_pal_reader.c - the .pal reader header on its own, as an engine would use it:
 * compiled as C99 without the rest of crowdbake. The palette it maps is baked by the
 * crowdbake command first. */
#define _DEFAULT_SOURCE
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef BUILD_DIR
#define BUILD_DIR "build"
#endif
#define TMP BUILD_DIR "/tmp-tests/standalone"

#define CBPAL_WITH_ZSTD
#define CROWDBAKE_PAL_IMPLEMENTATION
#include "crowdbake_pal.h"

static void bake(const char *extra, const char *out)
{
    const char *exe = getenv("CROWDBAKE") ? getenv("CROWDBAKE") : BUILD_DIR "/crowdbake";
    const char *shared = getenv("CROWDBAKE_SHARED") ? getenv("CROWDBAKE_SHARED") : "../shared";
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "mkdir -p " TMP " && %s bake %s/assets/fox-bevy/Fox.glb -o %s -q --fps 30 %s", exe, shared, out,
             extra);
    assert_int_equal(system(cmd), 0);
}

static void test_texels_point_into_the_mapping(void **state)
{
    (void)state;
    bake("", TMP "/standalone.pal");
    cbpal_file f;
    char err[256];
    assert_int_equal(cbpal_open(TMP "/standalone.pal", 0, &f, err, sizeof err), 0);
    const unsigned char *t = (const unsigned char *)f.texels;
    assert_true(t >= f.data && t + f.texels_size <= f.data + f.size); /* inside the file: no copy */
    assert_ptr_equal(t, f.data + f.header.payload_offset);
    assert_int_equal((uintptr_t)t % 4096, 0); /* page-aligned: a GPU upload can take it as it is */
    assert_null(f.owned_);
    assert_int_equal(f.texels_size, (size_t)f.header.width * f.header.height * f.header.texel_bytes);
    cbpal_clip c;
    assert_int_equal(cbpal_get_clip(&f, 1, &c), 0);
    assert_string_equal(c.name, "Walk");
    assert_int_equal(c.first_row, 103); /* Survey: round(3.4167 * 30) = 103 looping rows */
    cbpal_close(&f);
    /* Verifying the checksum reads the whole file and agrees. */
    assert_int_equal(cbpal_open(TMP "/standalone.pal", CBPAL_VERIFY_CHECKSUM, &f, err, sizeof err), 0);
    cbpal_close(&f);
}

static void test_compressed_palette_is_decompressed_once(void **state)
{
    (void)state;
    bake("--zstd", TMP "/standalone-zstd.pal");
    cbpal_file f;
    char err[256];
    assert_int_equal(cbpal_open(TMP "/standalone-zstd.pal", CBPAL_VERIFY_CHECKSUM, &f, err, sizeof err), 0);
    assert_non_null(f.owned_);
    assert_ptr_equal(f.texels, f.owned_);
    cbpal_close(&f);
}

/* Vectors computed with python3-xxhash (the reference xxHash library). */
static void test_xxh64_matches_the_reference_library(void **state)
{
    (void)state;
    assert_true(cbpal_xxh64("", 0) == 0xef46db3751d8e999ull);
    assert_true(cbpal_xxh64("abc", 3) == 0x44bc2cf5ad770999ull);
    unsigned char b[1000];
    for (int i = 0; i < 1000; ++i) b[i] = (unsigned char)(i * 7 + 3);
    assert_true(cbpal_xxh64(b, 1000) == 0x5f235fa033f1a3fbull);
    cbpal_xxh64_state s;
    cbpal_xxh64_init(&s);
    for (int i = 0; i < 1000; i += 13) cbpal_xxh64_update(&s, b + i, i + 13 > 1000 ? (size_t)(1000 - i) : 13);
    assert_true(cbpal_xxh64_digest(&s) == 0x5f235fa033f1a3fbull);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_texels_point_into_the_mapping),
        cmocka_unit_test(test_compressed_palette_is_decompressed_once),
        cmocka_unit_test(test_xxh64_matches_the_reference_library),
    };
    return cmocka_run_group_tests_name("standalone-reader", tests, NULL, NULL);
}
