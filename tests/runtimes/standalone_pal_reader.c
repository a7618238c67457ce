/* standalone_pal_reader.c - the .pal reader header on its own, as an engine would use it:
 * compiled as C99 without the rest of crowdbake. The palette it maps is baked by the
 * crowdbake command first. */
#define _DEFAULT_SOURCE
#include <math.h>
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

/* ---- timed rows (version 7), a palette written by hand from docs/pal-format.md ---- */

static void put32(unsigned char *d, uint32_t v) { memcpy(d, &v, 4); }
static void putf(unsigned char *d, float f) { memcpy(d, &f, 4); }

/* One bone, qpos float, identity rotations, row k of each clip at x = 10 k: the bone's matrix's x
 * translation is the blend of the rows the reader picks. Clip 0 "loop": 6 cells at 2 cells/s, rows
 * at cells 0, 1, 3 (its last interval, 3 to 6, wraps to row 0). Clip 1 "once": 4 cells at 4
 * cells/s, rows at cells 0, 3, 4 (the last at its end). Their maps (row_texels 2: 3 and 2 rows)
 * lie just before their first rows 3 and 8. */
enum { T_ROWS = 11, T_PAYLOAD = 4096, T_SIZE = 4096 + T_ROWS * 2 * 16 };
static const uint32_t t_cells[2] = {6, 4}, t_first[2] = {3, 8}, t_at[2][3] = {{0, 1, 3}, {0, 3, 4}};
static const float t_rate[2] = {2, 4};

static void timed_texel(unsigned char *d, uint32_t row, uint32_t k, const float v[4])
{
    memcpy(d + T_PAYLOAD + (row * 2 + k) * 16, v, 16);
}

static void timed_palette(unsigned char *d)
{
    static const unsigned char magic[8] = {'C', 'B', 'P', 'A', 'L', '\r', '\n', 0x1a};
    uint32_t u[14] = {7, CBPAL_FLAG_TIMED_ROWS, 256, CBPAL_LAYOUT_QPOS, CBPAL_PRECISION_FLOAT, 2, 1, 2, T_ROWS, 2, T_ROWS, 1, 16, 2};
    uint64_t w[9] = {0, 256, 416, 480, 15, T_PAYLOAD, T_ROWS * 32, T_ROWS * 32, 0};
    memset(d, 0, T_SIZE);
    memcpy(d, magic, 8);
    for (int i = 0; i < 14; ++i) put32(d + 8 + 4 * i, u[i]);
    putf(d + 64, 2), putf(d + 104, 1);
    memcpy(d + 112, w, sizeof w);
    uint64_t timed = 448;
    memcpy(d + 208, &timed, 8);
    for (uint32_t c = 0; c < 2; ++c) {
        unsigned char *e = d + 256 + 80 * c, *t = d + timed + 16 * c;
        float duration = (float)t_cells[c] / t_rate[c];
        put32(e, 5 * c), put32(e + 4, 4), put32(e + 8, t_first[c]), put32(e + 12, 3);
        putf(e + 16, 3 / duration), putf(e + 20, duration), put32(e + 28, (c ? 0 : CBPAL_CLIP_LOOPS) | CBPAL_CLIP_TIMED);
        put32(t, t_cells[c]), putf(t + 4, t_rate[c]), put32(t + 8, (t_cells[c] + 1) / 2);
        for (uint32_t k = 0; k < 3; ++k) { /* the rows */
            float q[4] = {0, 0, 0, 1}, p[4] = {10.0f * k, 0, 0, 1};
            timed_texel(d, t_first[c] + k, 0, q), timed_texel(d, t_first[c] + k, 1, p);
        }
        for (uint32_t cell = 0, k = 0; cell < t_cells[c]; ++cell) { /* the map, as the spec says */
            while (k + 1 < 3 && t_at[c][k + 1] <= cell) ++k;
            float end = k + 1 < 3 ? (float)t_at[c][k + 1] : (float)t_cells[c], len = end - (float)t_at[c][k];
            float v[4] = {(float)k, k + 1 < 3 ? (float)k + 1 : 0, (cell - t_at[c][k]) / len, (cell + 1 - t_at[c][k]) / len};
            timed_texel(d, t_first[c] - (t_cells[c] + 1) / 2 + cell / 2, cell % 2, v);
        }
    }
    put32(d + 416, 10), put32(d + 420, 4), put32(d + 424, 0xffffffffu); /* the bone, at the origin */
    memcpy(d + 480, "loop\0once\0root", 15);
    uint64_t sum = cbpal_xxh64(d, T_SIZE);
    memcpy(d + CBPAL_CHECKSUM_OFFSET, &sum, 8);
}

/* The x of row blend the spec gives: piecewise linear in the cell position between the rows' cells. */
static double timed_expected(uint32_t c, double time)
{
    double u = time * t_rate[c], n = t_cells[c];
    if (c == 0) u -= n * floor(u / n);
    else u = u < 0 ? 0 : u > n ? n : u;
    for (uint32_t k = 0; k < 3; ++k) {
        double start = t_at[c][k], end = k + 1 < 3 ? t_at[c][k + 1] : n, to = k + 1 < 3 ? 10.0 * (k + 1) : 0;
        if (u >= start && (u < end || k == 2)) /* a one-shot's last row at its end */
            return end > start ? 10.0 * k + (to - 10.0 * k) * (u - start) / (end - start) : 10.0 * k;
    }
    return NAN;
}

static void test_timed_rows_follow_their_map(void **state)
{
    (void)state;
    static unsigned char d[T_SIZE];
    timed_palette(d);
    cbpal_file f;
    char err[256];
    if (cbpal_open_memory(d, T_SIZE, CBPAL_VERIFY_CHECKSUM, &f, err, sizeof err)) fail_msg("%s", err);
    for (uint32_t c = 0; c < 2; ++c) {
        cbpal_clip clip;
        assert_int_equal(cbpal_get_clip(&f, c, &clip), 0);
        assert_true(clip.flags & CBPAL_CLIP_TIMED);
        assert_int_equal(clip.cells, t_cells[c]);
        assert_int_equal(clip.map_rows, (t_cells[c] + 1) / 2);
        assert_true(clip.cell_rate == t_rate[c]);
        for (double time = -1.3; time < 5; time += 0.0625) {
            float m[16];
            assert_int_equal(cbpal_bone_matrix(&f, c, time, 0, m), 0);
            double want = timed_expected(c, time);
            if (fabs(m[12] - want) > 1e-4) fail_msg("clip %u at %g s: x %g, the spec says %g", c, time, m[12], want);
        }
    }
    float v[4];
    assert_int_equal(cbpal_timed_map(&f, 0, 4, v), 0); /* cell 4 of the loop: rows 2 and 0, a third of 3..6 in */
    assert_true(v[0] == 2 && v[1] == 0 && fabsf(v[2] - 1.0f / 3) < 1e-6f && fabsf(v[3] - 2.0f / 3) < 1e-6f);
    assert_int_not_equal(cbpal_timed_map(&f, 0, 6, v), 0);
    cbpal_close(&f);
    /* A map row past the clip's rows, and a weight outside [0, 1]: refused, naming the clip. */
    float bad[2][4] = {{3, 0, 0, 1}, {0, 1, -0.5f, 1}};
    for (int i = 0; i < 2; ++i) {
        timed_palette(d);
        timed_texel(d, 1, 0, bad[i]); /* the loop's cell 2 */
        assert_int_not_equal(cbpal_open_memory(d, T_SIZE, 0, &f, err, sizeof err), 0);
        assert_non_null(strstr(err, "loop"));
        assert_non_null(strstr(err, "cell 2"));
    }
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
        cmocka_unit_test(test_timed_rows_follow_their_map),
    };
    return cmocka_run_group_tests_name("standalone-reader", tests, NULL, NULL);
}
